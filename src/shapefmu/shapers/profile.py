"""Rest-to-rest motion profiles sampled on a uniform time grid, shared by the profile families.

A ``MotionProfile`` holds acceleration, velocity and position at ``t[k] = k * ts``: ``velocity[k]``
and ``position[k]`` are the exact values of the move at ``t[k]``, and ``acceleration[k]`` is the
mean acceleration over ``[t[k], t[k+1])``, so that ``v[k+1] = v[k] + a[k] ts`` holds for every
family and the acceleration sums to the final velocity, zero.

- Sampled families (window filters, paper 000; time-frequency, paper 004) hold the acceleration
  between grid points (zero-order hold, what a sampled controller commands), so the mean is the
  held value and ``p[k+1] = p[k] + v[k] ts + a[k] ts^2 / 2`` holds as well.
- Continuous-time constructions (twin-pulse family, paper 003) switch between grid points; their
  positions are exact, not the double integral of the held means.

The ``kernel`` is the sampled sequence whose spectrum explains the residual vibration: the shape
filter behind a velocity profile (paper 000, Fig. 4), the acceleration itself, or the twin-pulse
kernel averaged over each sample period.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from shapefmu.runtime.checks import check_positive
from shapefmu.shapers.sampled import SampledShaper


@dataclass(frozen=True, eq=False)
class MotionProfile:
    """Acceleration, velocity and position of a rest-to-rest move on the grid ``t = k * ts``.

    The last acceleration entry is 0 (the move is over). ``kernel`` is the sampled shaper the profile
    is built from (same ``ts``); see the module docstring for how the arrays relate.

    Examples
    --------
    >>> m = from_acceleration([1.0, -1.0], 0.5)  # bang-bang of 1 m/s2, 0.5 s each way
    >>> m.t.tolist(), m.velocity.tolist(), m.distance, m.duration
    ([0.0, 0.5, 1.0], [0.0, 0.5, 0.0], 0.25, 1.0)
    """

    t: np.ndarray
    acceleration: np.ndarray
    velocity: np.ndarray
    position: np.ndarray
    kernel: SampledShaper

    def __post_init__(self):
        arrays = [np.array(getattr(self, name), dtype=float) for name in ("t", "acceleration", "velocity", "position")]
        if len({a.shape for a in arrays}) != 1 or arrays[0].ndim != 1 or arrays[0].size < 2:
            raise ValueError("t, acceleration, velocity and position must be 1-D arrays of one length >= 2")
        for name, a in zip(("t", "acceleration", "velocity", "position"), arrays):
            a.setflags(write=False)
            object.__setattr__(self, name, a)

    @property
    def ts(self) -> float:
        return self.kernel.ts

    @property
    def duration(self) -> float:
        return float(self.t[-1])

    @property
    def distance(self) -> float:
        return float(self.position[-1])

    def to_json(self) -> str:
        return json.dumps(
            {
                "kind": "motion_profile",
                "ts": self.ts,
                "t": self.t.tolist(),
                "acceleration": self.acceleration.tolist(),
                "velocity": self.velocity.tolist(),
                "position": self.position.tolist(),
                "kernel": self.kernel.taps.tolist(),
            }
        )


def from_acceleration(acceleration, ts: float, kernel: SampledShaper | None = None) -> MotionProfile:
    """Integrate a zero-order-held acceleration ``a[k]`` (k = 0..N-1) exactly on the grid 0..N*ts.

    ``kernel`` defaults to the acceleration itself as a sampled sequence.

    Examples
    --------
    >>> m = from_acceleration([1.0, 1.0, -1.0, -1.0], 0.5)  # exact: p = a t^2 / 2 on each piece
    >>> m.position.tolist()
    [0.0, 0.125, 0.5, 0.875, 1.0]
    """
    ts = check_positive(ts, "ts")
    a = np.asarray(acceleration, dtype=float).ravel()
    if a.size == 0 or not np.all(np.isfinite(a)):
        raise ValueError("acceleration must be a non-empty sequence of finite numbers")
    v = np.concatenate([[0.0], np.cumsum(a) * ts])
    p = np.concatenate([[0.0], np.cumsum(v[:-1] * ts + a * ts * ts / 2.0)])
    t = np.arange(a.size + 1) * ts
    return MotionProfile(t, np.append(a, 0.0), v, p, kernel if kernel is not None else SampledShaper(a, ts))


def velocity_profile(shaper: SampledShaper, distance: float) -> MotionProfile:
    """Use a shape filter ``f[k]`` (taps summing to 1) as the velocity ``v[k] = distance f[k] / ts``.

    Paper 000 (section 3, Fig. 4; section 9): a filter whose first and last taps are zero is a
    velocity profile in its own right; the acceleration is the held difference
    ``(v[k+1] - v[k]) / ts`` and the position reaches ``distance * sum(f)``. Raises ValueError if
    the filter does not start and end at zero (the velocity would jump).

    Examples
    --------
    >>> import math
    >>> from shapefmu.shapers.window import hanning_filter
    >>> m = velocity_profile(hanning_filter(2 * math.pi, 0.0, 0.25), 2.0)  # a 1 Hz Hanning, 2 m
    >>> round(m.distance, 12), float(m.velocity[0]), float(m.velocity[-1])
    (2.0, 0.0, 0.0)
    """
    distance = check_positive(distance, "distance")
    f = shaper.taps
    scale = np.max(np.abs(f))
    if f.size < 3 or abs(f[0]) > 1e-12 * scale or abs(f[-1]) > 1e-12 * scale:
        raise ValueError(
            f"a shape filter is a velocity profile only if its first and last taps are 0, got "
            f"{f[0]:.3g} and {f[-1]:.3g} (the Hanning and Blackman filters qualify, the rectangle does not)"
        )
    v = distance * f / shaper.ts
    return from_acceleration(np.diff(v) / shaper.ts, shaper.ts, kernel=shaper)
