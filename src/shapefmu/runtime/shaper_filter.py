"""Streaming shaper filter for fixed-step use: one shaped sample out per command sample in.

Cost is O(number of non-zero taps) per step (of the taps' span where they fill it densely) and
memory is one buffer twice as long as the shaper, however long the filter runs.

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
from operator import mul

from .checks import check_finite, check_positive, check_size

# Impulse times within this fraction of a step from a grid point are taken to lie on it, so that a
# time computed as 2.9999999999 h is not split into a 1e-10 sliver.
_ON_GRID = 1e-9
# A dense span costs about half a non-zero tap per tap plus a set-up of about ten taps (the slice
# and the map; measured with benchmarks/shaper_filter.py): below that a sparse loop is faster.
_DENSE_SET_UP = 10


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
    """y[k] = sum_i w_i u[k - d_i], for integer delays d_i, over a buffer of past inputs.

    Before the first sample the input is taken to have rested at ``u0`` (default 0), so a shaper
    started on a command already held at some value does not produce a transient.

    The buffer holds the last ``length`` inputs twice over, newest first: u[k - d] is at
    ``buffer[pos + d]`` for every delay, so the taps read one contiguous slice without wrapping.
    Where the non-zero taps fill their span densely (window filters: hundreds of taps) the output is
    one C-level ``sum(map(mul, taps, slice))`` over the span, zeros included, about twice as fast
    as a Python loop; sparse impulse shapers (a few taps spread over many samples) keep the loop
    over their non-zero taps. The span is taken only for strictly increasing delays, so both add
    the same products in the same order from 0.0 and return the same floats for finite inputs (a
    zero tap adds 0 * u = 0).
    """

    def __init__(self, delays, weights, u0=0.0):
        if len(delays) != len(weights) or not delays:
            raise ValueError(
                f"delays and weights must be non-empty and of equal length, got {len(delays)} and {len(weights)}"
            )
        for d in delays:
            if isinstance(d, bool) or not isinstance(d, int) or d < 0:
                raise ValueError(f"delays must be integers >= 0, got {d!r}")
        check_size(max(delays) + 1, "MAX_SAMPLED_LENGTH", "a filter whose longest delay is", "samples",
                   "use a longer sampling period")
        self._pairs = tuple((d, check_finite(w, "weight")) for d, w in zip(delays, weights))
        self._length = max(delays) + 1
        self._first = min(delays)
        self._span_taps = self._taps_over_span()
        self.reset(u0)

    def _taps_over_span(self):
        """The taps over delays first..length-1, zeros included, if the span pays; else ()."""
        span = self._length - self._first
        increasing = all(a[0] < b[0] for a, b in zip(self._pairs, self._pairs[1:]))
        # Unsorted or repeated delays would change the order of the additions: those stay sparse.
        if not increasing or 2 * len(self._pairs) < span + _DENSE_SET_UP:
            return ()
        taps = [0.0] * span
        for d, w in self._pairs:
            taps[d - self._first] = w
        return tuple(taps)

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
        self._buffer = [check_finite(u0, "u0")] * (2 * self._length)
        self._pos = 0

    def step(self, u):
        """Push one input sample, return the shaped output for the same instant."""
        buffer, length = self._buffer, self._length
        pos = self._pos - 1 if self._pos else length - 1
        self._pos = pos
        buffer[pos] = buffer[pos + length] = u
        if self._span_taps:
            return sum(map(mul, self._span_taps, buffer[pos + self._first : pos + length]), 0.0)
        y = 0.0
        for d, w in self._pairs:
            y += w * buffer[pos + d]
        return y


class FeedthroughFIR:
    """y[k] = w_0 u[k] + r[k]: an FIR split into its feed-through and its history, for the FMUs.

    An FMU's output at a communication point must follow an input set at that point (ModelStructure
    declares the dependency) without committing the sample: setting u may happen any number of
    times before ``fmi2DoStep``. So r[k] = sum_{d >= 1} w_d u[k - d] is kept apart, computed by a
    StreamingShaper on the taps d >= 1 shifted by one sample: stepping it with u[k] when the step
    commits u[k] returns r[k + 1], so nothing is ever un-done. Used by the Shaper and ShapeFilter
    FMUs; ``delays`` are increasing, as ``grid_impulses`` returns them.
    """

    def __init__(self, delays, weights, u0):
        self.w0 = weights[0] if delays[0] == 0 else 0.0
        rest = [(d - 1, w) for d, w in zip(delays, weights) if d > 0]
        self.tail = StreamingShaper([d for d, _ in rest], [w for _, w in rest], u0) if rest else None
        self.r = u0 * math.fsum(w for _, w in rest)

    @classmethod
    def from_taps(cls, taps, u0):
        """The split of FIR taps taps[k] at delay k; zero taps after the first are left out."""
        delays = [k for k, w in enumerate(taps) if k == 0 or w != 0.0]
        return cls(delays, [taps[k] for k in delays], u0)

    def commit(self, u):
        """Commit one sample of u; r becomes the history part of the next sample."""
        if self.tail is not None:
            self.r = self.tail.step(u)

    def output(self, u):
        """y for the input u at the current sample, from the committed history."""
        return self.w0 * u + self.r
