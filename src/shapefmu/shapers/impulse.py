"""Impulse shapers: the ``ImpulseShaper`` design object and the closed-form single-mode designs.

``omega`` is the undamped natural frequency in rad/s and ``zeta`` the damping ratio throughout.
The formulas themselves live in ``shapefmu.runtime.impulse_formulas`` (standard library only) so
that an FMU re-evaluates exactly what is designed and analysed here.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np

from shapefmu.runtime import impulse_formulas
from shapefmu.runtime.checks import check_finite
from shapefmu.runtime.shaper_filter import grid_impulses
from shapefmu.runtime.units import RadPerSecond

# Impulses closer than this (relative to the shaper's duration) are one impulse: convolution
# produces coincident times, e.g. T1 + T2 == T2 + T1.
_MERGE = 1e-12


@dataclass(frozen=True)
class ImpulseShaper:
    """A sequence of impulses ``amplitudes[i]`` at ``times[i]`` (seconds, sorted, first at >= 0).

    Convolving a command with it gives the shaped command y(t) = sum_i A_i u(t - t_i).

    Examples
    --------
    >>> s = ImpulseShaper((0.0, 0.5), (0.5, 0.5))
    >>> s.duration, s.gain, len(s)
    (0.5, 1.0, 2)
    >>> s.convolve(s).amplitudes  # ZV * ZV = ZVD: binomial amplitudes
    (0.25, 0.5, 0.25)
    """

    times: tuple[float, ...]
    amplitudes: tuple[float, ...]

    def __post_init__(self):
        times = [check_finite(t, "times") for t in self.times]
        amplitudes = [check_finite(a, "amplitudes") for a in self.amplitudes]
        if not times or len(times) != len(amplitudes):
            raise ValueError(
                f"times and amplitudes must be non-empty and of equal length, got {len(times)} and {len(amplitudes)}"
            )
        if times[0] < 0.0 or any(b <= a for a, b in zip(times, times[1:])):
            raise ValueError(f"times must be >= 0 and strictly increasing, got {times}")
        object.__setattr__(self, "times", tuple(times))
        object.__setattr__(self, "amplitudes", tuple(amplitudes))

    @classmethod
    def from_impulses(cls, times, amplitudes) -> ImpulseShaper:
        """Build from unsorted impulses, summing those at (numerically) the same time."""
        order = np.argsort(np.asarray(times, dtype=float), kind="stable")
        t = np.asarray(times, dtype=float)[order]
        a = np.asarray(amplitudes, dtype=float)[order]
        tolerance = _MERGE * max(float(t[-1] - t[0]), 1.0) if t.size else 0.0
        merged_t, merged_a = [], []
        for ti, ai in zip(t, a):
            if merged_t and ti - merged_t[-1] <= tolerance:
                merged_a[-1] += ai
            else:
                merged_t.append(float(ti))
                merged_a.append(float(ai))
        return cls(tuple(merged_t), tuple(merged_a))

    @property
    def duration(self) -> float:
        """Time of the last impulse: the delay the shaper adds to a move."""
        return self.times[-1]

    @property
    def gain(self) -> float:
        """Sum of the amplitudes (1 for every design in this package: the set point is kept)."""
        return math.fsum(self.amplitudes)

    def __len__(self) -> int:
        return len(self.times)

    def convolve(self, other: ImpulseShaper) -> ImpulseShaper:
        """The shaper whose spectrum is the product of both (every pair of impulses, times added)."""
        times = [ti + tj for ti in self.times for tj in other.times]
        amplitudes = [ai * aj for ai in self.amplitudes for aj in other.amplitudes]
        return ImpulseShaper.from_impulses(times, amplitudes)

    def on_grid(self, h: float):
        """The sampled shaper a fixed-step filter with step ``h`` runs (centroid-preserving split)."""
        from shapefmu.shapers.sampled import SampledShaper

        delays, weights = grid_impulses(self.times, self.amplitudes, h)
        taps = np.zeros(delays[-1] + 1)
        taps[delays] = weights
        return SampledShaper(taps, h)

    def apply(self, t, u, hold: str = "linear") -> np.ndarray:
        """Shape a sampled command offline: y(t_k) = sum_i A_i u(t_k - t_i).

        ``u`` is read between samples by linear interpolation (``hold="linear"``, for position and
        velocity profiles) or held from the previous sample (``hold="zoh"``, for piecewise-constant
        commands such as a bang-bang). Before ``t[0]`` the command rests at ``u[0]`` and after
        ``t[-1]`` it stays at ``u[-1]``.
        """
        t = np.asarray(t, dtype=float)
        u = np.asarray(u, dtype=float)
        if t.ndim != 1 or t.shape != u.shape or t.size < 2:
            raise ValueError(f"t and u must be 1-D of equal length >= 2, got shapes {t.shape} and {u.shape}")
        if not np.all(np.diff(t) > 0):
            raise ValueError("t must be strictly increasing")
        if hold not in ("linear", "zoh"):
            raise ValueError(f"hold must be 'linear' or 'zoh', got {hold!r}")
        y = np.zeros_like(u)
        for ti, ai in zip(self.times, self.amplitudes):
            tau = t - ti
            if hold == "linear":
                y += ai * np.interp(tau, t, u)
            else:
                # Small tolerance so that a delay that lands on a sample picks that sample.
                index = np.searchsorted(t, tau + 1e-12 * (t[-1] - t[0]), side="right") - 1
                y += ai * u[np.clip(index, 0, None)]
        return y

    def to_json(self) -> str:
        return json.dumps({"kind": "impulse", "times": list(self.times), "amplitudes": list(self.amplitudes)})

    @classmethod
    def from_json(cls, text: str) -> ImpulseShaper:
        data = json.loads(text)
        if data.get("kind") != "impulse":
            raise ValueError(f"JSON kind must be 'impulse', got {data.get('kind')!r}")
        return cls(tuple(data["times"]), tuple(data["amplitudes"]))


def _shaper(pair) -> ImpulseShaper:
    times, amplitudes = pair
    return ImpulseShaper(tuple(times), tuple(amplitudes))


def zv(omega: RadPerSecond, zeta: float = 0.0) -> ImpulseShaper:
    """Zero-vibration shaper (paper 002, eq. 3): two impulses half a damped period apart.

    ``omega`` (rad/s) is the undamped natural frequency, ``zeta`` the damping ratio.

    Examples
    --------
    >>> import math
    >>> s = zv(2 * math.pi * 1.0)  # a 1 Hz mode: half a period is 0.5 s
    >>> s.times, s.amplitudes
    ((0.0, 0.5), (0.5, 0.5))
    >>> K = math.exp(-0.1 * math.pi / math.sqrt(1 - 0.1**2))  # damped: 1/(1+K), K/(1+K)
    >>> math.isclose(zv(2 * math.pi, 0.1).amplitudes[0], 1 / (1 + K))
    True
    """
    return _shaper(impulse_formulas.zv_dn(omega, zeta, 0))


def zvd(omega: RadPerSecond, zeta: float = 0.0) -> ImpulseShaper:
    """Zero-vibration-derivative shaper: ZV convolved with itself (one period long).

    Examples
    --------
    >>> import math
    >>> zvd(2 * math.pi).amplitudes  # 1 Hz: (1 + z)^2 / 4 at 0, 0.5, 1 s
    (0.25, 0.5, 0.25)
    """
    return _shaper(impulse_formulas.zv_dn(omega, zeta, 1))


def zvdd(omega: RadPerSecond, zeta: float = 0.0) -> ImpulseShaper:
    """ZVDD shaper: ZV convolved three times (1.5 periods long).

    Examples
    --------
    >>> import math
    >>> s = zvdd(2 * math.pi)
    >>> s.duration, s.amplitudes
    (1.5, (0.125, 0.375, 0.375, 0.125))
    """
    return _shaper(impulse_formulas.zv_dn(omega, zeta, 2))


def zv_dn(omega: RadPerSecond, zeta: float, n: int) -> ImpulseShaper:
    """ZV convolved n+1 times: residual and its first n frequency derivatives vanish at omega.

    Amplitudes C(n+1, i) K^i / (1+K)^(n+1) at i*pi/omega_d, K = exp(-zeta*pi/sqrt(1-zeta^2)).

    Examples
    --------
    >>> import math
    >>> zv_dn(2 * math.pi, 0.0, 3).amplitudes  # C(4, i) / 16
    (0.0625, 0.25, 0.375, 0.25, 0.0625)
    """
    return _shaper(impulse_formulas.zv_dn(omega, zeta, n))


def mzv(omega: RadPerSecond, zeta: float = 0.0) -> ImpulseShaper:
    """Three impulses over 0.75 of the damped period (spacing 3*pi/(4*omega_d)).

    Amplitudes (1, sqrt(2) K, K^2)/(1 + sqrt(2) K + K^2), K = exp(-zeta*omega*3*pi/(4*omega_d)),
    derived in ``runtime.impulse_formulas.mzv`` from the zero-vibration constraint.

    Examples
    --------
    >>> import math
    >>> s = mzv(2 * math.pi)  # undamped: K = 1, amplitudes 1/(2 + sqrt 2), sqrt 2/(2 + sqrt 2)
    >>> s.times, round(s.amplitudes[1], 12) == round(math.sqrt(2) / (2 + math.sqrt(2)), 12)
    ((0.0, 0.375, 0.75), True)
    """
    return _shaper(impulse_formulas.mzv(omega, zeta))


def um_zv(omega: RadPerSecond, zeta: float = 0.0) -> ImpulseShaper:
    """Unity-magnitude ZV: +1, -1, +1 at 0, ~T/6, ~T/3, times solved exactly for the damping.

    Examples
    --------
    >>> import math
    >>> s = um_zv(2 * math.pi)  # undamped: exactly T/6 and T/3
    >>> s.amplitudes, [round(t, 12) for t in s.times]
    ((1.0, -1.0, 1.0), [0.0, 0.166666666667, 0.333333333333])
    """
    return _shaper(impulse_formulas.um_zv(omega, zeta))

