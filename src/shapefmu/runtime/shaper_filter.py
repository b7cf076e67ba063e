"""Streaming shaper filter for fixed-step use: one shaped sample out per command sample in.

Cost is O(number of non-zero taps) per step and memory is one circular buffer as long as the
shaper, however long the filter runs.

Impulse times that are not multiples of the step h are mapped onto the grid by splitting: an
impulse of amplitude A at t = (k + alpha) h becomes (1 - alpha) A at k h and alpha A at (k + 1) h.
This keeps the amplitude sum (the steady-state gain) and the time centroid of every impulse
exactly. Its frequency response differs from the ideal delay by

    (1 - alpha) + alpha e^{-j w h} - e^{-j w alpha h} = -alpha (1 - alpha) (w h)^2 / 2 + O((w h)^3),

so an impulse shaper with exactly zero residual vibration keeps a residual of at most
max_alpha alpha(1-alpha) (w h)^2 / 2 <= (w h)^2 / 8 per unit of amplitude (second order in h);
``tests/test_shaper_filter.py`` measures that cost.
"""

import math

from .checks import check_finite, check_positive

# Impulse times within this fraction of a step from a grid point are taken to lie on it, so that a
# time computed as 2.9999999999 h is not split into a 1e-10 sliver.
_ON_GRID = 1e-9


def grid_impulses(times, amplitudes, h):
    """Map impulses onto the grid k*h by centroid-preserving splitting.

    Returns ``(delays, weights)``: sorted integer delays in steps and their summed weights.
    """
    h = check_positive(h, "h")
    if len(times) != len(amplitudes) or not times:
        raise ValueError(
            f"times and amplitudes must be non-empty and of equal length, got {len(times)} and {len(amplitudes)}"
        )
    taps = {}
    for t, a in zip(times, amplitudes):
        t = check_finite(t, "impulse time")
        a = check_finite(a, "impulse amplitude")
        if t < 0.0:
            raise ValueError(f"impulse times must be >= 0, got {t!r}")
        x = t / h
        k = math.floor(x)
        alpha = x - k
        if alpha > 1.0 - _ON_GRID:
            k, alpha = k + 1, 0.0
        elif alpha < _ON_GRID:
            alpha = 0.0
        taps[k] = taps.get(k, 0.0) + (1.0 - alpha) * a
        if alpha:
            taps[k + 1] = taps.get(k + 1, 0.0) + alpha * a
    delays = sorted(d for d, w in taps.items() if w != 0.0)
    return delays, [taps[d] for d in delays]


class StreamingShaper:
    """y[k] = sum_i w_i u[k - d_i], for integer delays d_i, over a circular buffer of past inputs.

    Before the first sample the input is taken to have rested at ``u0`` (default 0), so a shaper
    started on a command already held at some value does not produce a transient.
    """

    def __init__(self, delays, weights, u0=0.0):
        if len(delays) != len(weights) or not delays:
            raise ValueError(
                f"delays and weights must be non-empty and of equal length, got {len(delays)} and {len(weights)}"
            )
        for d in delays:
            if isinstance(d, bool) or not isinstance(d, int) or d < 0:
                raise ValueError(f"delays must be integers >= 0, got {d!r}")
        self._pairs = tuple((d, check_finite(w, "weight")) for d, w in zip(delays, weights))
        self._length = max(delays) + 1
        self.reset(u0)

    @classmethod
    def from_impulses(cls, times, amplitudes, h, u0=0.0):
        """A filter for impulses at arbitrary times, mapped onto the step ``h`` by splitting."""
        delays, weights = grid_impulses(times, amplitudes, h)
        return cls(delays, weights, u0)

    @classmethod
    def from_taps(cls, taps, u0=0.0):
        """A filter for FIR taps taps[k] at delay k (a sampled shaper at its own sampling period)."""
        delays = [k for k, w in enumerate(taps) if w != 0.0]
        if not delays:
            raise ValueError("taps must contain at least one non-zero value")
        return cls(delays, [taps[k] for k in delays], u0)

    @property
    def length(self):
        """Number of samples the filter remembers (largest delay + 1)."""
        return self._length

    def reset(self, u0=0.0):
        """Forget the past: the input is taken to have rested at ``u0``."""
        self._buffer = [check_finite(u0, "u0")] * self._length
        self._pos = 0

    def step(self, u):
        """Push one input sample, return the shaped output for the same instant."""
        buffer = self._buffer
        pos = self._pos
        buffer[pos] = u
        y = 0.0
        # pos - d lies in [-(length-1), length-1]; Python's negative indexing wraps it for us.
        for d, w in self._pairs:
            y += w * buffer[pos - d]
        pos += 1
        self._pos = 0 if pos == self._length else pos
        return y
