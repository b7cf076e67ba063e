"""Residual-vibration analysis of impulse shapers, sampled shapers and sampled commands.

Everything here accepts any *impulse sequence*: an ``ImpulseShaper``, a ``SampledShaper`` (taps at
``k*ts``), or a ``(times, amplitudes)`` pair. A sampled command u[k] at period ts is analysed as
``SampledShaper(u, ts)``.

Two definitions of residual vibration (Zhou & Misawa, paper 000) for a mode
omega^2 / (s^2 + 2 zeta omega s + omega^2) hit by impulses A_k at t_k, with t_N the last time:

- ``"percent"`` (eq. 5, Singer & Seering): the response amplitude after the last impulse relative
  to that of a unit impulse at t = 0,
  V = e^{-zeta omega t_N} sqrt(AC^2 + AS^2) / sum_k A_k;
- ``"absolute"`` (eq. 4): the amplitude itself, V = e^{-zeta omega t_N} omega/sqrt(1-zeta^2)
  sqrt(AC^2 + AS^2), which goes to 0 with omega (eq. 5 goes to 100 %),

where AC + j AS = sum_k A_k e^{zeta omega t_k} e^{j omega sqrt(1-zeta^2) t_k}.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from shapefmu.runtime.checks import check_finite, check_positive, check_vtol, check_zeta
from shapefmu.runtime.units import RadPerSecond

DEFINITIONS = ("percent", "absolute")


def impulses(shaper) -> tuple[np.ndarray, np.ndarray]:
    """``(times, amplitudes)`` of a shaper, sampled shaper or ``(times, amplitudes)`` pair.

    Examples
    --------
    >>> t, a = impulses(([0.0, 0.5], [0.5, 0.5]))
    >>> t.tolist(), a.tolist()
    ([0.0, 0.5], [0.5, 0.5])
    """
    if isinstance(shaper, tuple) and len(shaper) == 2:
        times, amplitudes = shaper
    else:
        times, amplitudes = shaper.times, shaper.amplitudes
    t = np.asarray(times, dtype=float).ravel()
    a = np.asarray(amplitudes, dtype=float).ravel()
    if t.size == 0 or t.shape != a.shape:
        raise ValueError(f"times and amplitudes must be non-empty and of equal length, got {t.size} and {a.size}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(a))):
        raise ValueError("times and amplitudes must be finite")
    return t, a


def _omega_array(omega, name="omega") -> np.ndarray:
    w = np.asarray(omega, dtype=float)
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        bad = float(w[~(np.isfinite(w) & (w >= 0))].ravel()[0])
        raise ValueError(f"{name} must be finite and >= 0 rad/s, got {bad!r}")
    return w


def residual_vibration(shaper, omega: RadPerSecond, zeta: float, definition: str = "percent") -> np.ndarray:
    """Residual vibration of a mode (omega, zeta) after the impulse sequence, vectorised over omega.

    Returns an array shaped like ``omega`` (a float for a scalar). See the module docstring for the
    two definitions; ``"percent"`` is a fraction (0.05 is 5 %). ``omega`` in rad/s.

    Examples
    --------
    >>> import math
    >>> from shapefmu.shapers import zv
    >>> shaper = zv(2 * math.pi)  # 1 Hz: at 1.1 Hz an undamped ZV leaves |cos(pi 1.1 / 2)|
    >>> residual_vibration(shaper, 2 * math.pi, 0.0) < 1e-15
    True
    >>> math.isclose(residual_vibration(shaper, 2 * math.pi * 1.1, 0.0), abs(math.cos(math.pi * 1.1 / 2)))
    True
    """
    if definition not in DEFINITIONS:
        raise ValueError(f"definition must be one of {DEFINITIONS}, got {definition!r}")
    zeta = check_zeta(zeta)
    t, a = impulses(shaper)
    w = _omega_array(omega)
    flat = w.reshape(-1, 1)
    damped = math.sqrt(1.0 - zeta * zeta)
    # exp(zeta w (t_k - t_N)) instead of exp(-zeta w t_N) exp(zeta w t_k): no overflow for long
    # commands at high frequency.
    terms = a * np.exp(zeta * flat * (t - t[-1]) + 1j * damped * flat * t)
    v = np.abs(terms.sum(axis=1))
    if definition == "percent":
        gain = a.sum()
        if abs(gain) <= 1e-12 * np.abs(a).sum():
            raise ValueError(
                "the 'percent' residual vibration divides by the sum of the amplitudes, which is 0 here; "
                "use definition='absolute'"
            )
        v = v / abs(gain)
    else:
        v = v * flat[:, 0] / damped
    v = v.reshape(w.shape)
    return float(v) if v.ndim == 0 else v


@dataclass(frozen=True)
class SensitivityCurve:
    """Residual vibration against the frequency ratio q = omega_actual / omega_model.

    Examples
    --------
    >>> import math
    >>> from shapefmu.shapers import zvd
    >>> curve = sensitivity(zvd(2 * math.pi), 2 * math.pi, 0.0, q=[0.9, 1.0, 1.1])
    >>> [round(float(v), 6) for v in curve.residual]  # ZVD: |cos(pi q / 2)|^2, 0 at q = 1
    [0.024472, 0.0, 0.024472]
    """

    q: np.ndarray
    residual: np.ndarray
    omega_model: float
    zeta: float
    definition: str


def sensitivity(shaper, omega_model: RadPerSecond, zeta: float, q=None, definition: str = "percent") -> SensitivityCurve:
    """Sensitivity curve (paper 000, eq. 4 / 5 with omega = q * omega_model); q defaults to 0..2.

    Examples
    --------
    >>> import math
    >>> from shapefmu.shapers import zv
    >>> curve = sensitivity(zv(2 * math.pi), 2 * math.pi, 0.0)  # 801 ratios on [0, 2]
    >>> curve.q.size, float(curve.residual[0]), float(curve.residual[400]) < 1e-15
    (801, 1.0, True)
    """
    omega_model = check_positive(omega_model, "omega_model")
    q = np.linspace(0.0, 2.0, 801) if q is None else _omega_array(q, "q")
    residual = residual_vibration(shaper, q * omega_model, zeta, definition)
    return SensitivityCurve(np.asarray(q), np.asarray(residual), omega_model, float(zeta), definition)


@dataclass(frozen=True)
class InsensitiveBand:
    """The contiguous band of frequency ratios around the design point where V <= vtol.

    Examples
    --------
    >>> InsensitiveBand(0.9, 1.1).width
    0.20000000000000007
    """

    q_low: float
    q_high: float

    @property
    def width(self) -> float:
        """The insensitivity I(vtol): band width over the design frequency."""
        return self.q_high - self.q_low


def insensitivity(shaper, omega: RadPerSecond, zeta: float, vtol: float = 0.05, q_max: float = 10.0) -> InsensitiveBand:
    """The band of q = omega_actual/omega around q = 1 where the percent residual stays <= vtol.

    A curve that touches vtol from below (the humps of EI shapers, exactly vtol by design) does not
    end the band: V is compared with vtol * (1 + 1e-7). The edges are then refined with Brent's
    method on V - vtol. The scan starts on (0, q_max] and doubles q_max (up to 1000) while the band
    is still open; ``q_high`` is ``inf`` when the band provably never ends (with damping, the
    residual of a shaper whose impulses after the first are small dies out at high frequency).
    Raises ValueError if V > vtol at the design point itself.

    Examples
    --------
    >>> import math
    >>> from shapefmu.shapers import ei, zvd
    >>> round(insensitivity(zvd(2 * math.pi), 2 * math.pi, 0.0).width, 3)  # I(5 %) of ZVD
    0.287
    >>> round(insensitivity(ei(2 * math.pi), 2 * math.pi, 0.0).width, 3)  # of EI, vtol = 5 %
    0.399
    """
    omega = check_positive(omega, "omega")
    vtol = check_vtol(vtol)
    q_max = check_positive(q_max, "q_max")

    def excess(q):
        return residual_vibration(shaper, q * omega, zeta) - vtol

    if excess(1.0) > vtol * 1e-7:
        raise ValueError(
            f"residual vibration at the design point is {excess(1.0) + vtol:.4g} > vtol = {vtol:g}: no band"
        )
    q_low = _band_edge(excess, 1.0, 1e-6, vtol)
    while True:
        q_high = _band_edge(excess, 1.0, q_max, vtol)
        if q_high is not None:
            break
        if _upper_bound(shaper, q_max * omega, zeta) <= vtol:
            q_high = math.inf  # heavily damped: V can never climb back above vtol (see _upper_bound)
            break
        if q_max >= 1000.0:
            raise ValueError(f"residual vibration stays below vtol up to q = {q_max:g} without a provable end")
        q_max *= 2.0
    return InsensitiveBand(0.0 if q_low is None else q_low, q_high)


def _band_edge(excess, start, stop, vtol):
    """Where V first exceeds vtol going from ``start`` to ``stop``, or None if it never does.

    Scans a grid fine enough to resolve the humps of multi-hump shapers (20000 points), treating
    V <= vtol (1 + 1e-7) as inside so that tangent humps do not end the band, then refines the
    crossing with Brent's method.
    """
    grid = np.linspace(start, stop, 20001)
    outside = np.flatnonzero(excess(grid) > vtol * 1e-7)
    if outside.size == 0:
        return None
    k = outside[0]
    return float(brentq(excess, grid[k - 1], grid[k], xtol=1e-12))


def _upper_bound(shaper, omega, zeta) -> float:
    """sum_k |A_k| e^{zeta omega (t_k - t_N)} / |sum A|: bounds the percent residual at omega and,
    being non-increasing in omega, at every higher frequency too."""
    t, a = impulses(shaper)
    return float(np.sum(np.abs(a) * np.exp(zeta * omega * (t - t[-1]))) / abs(a.sum()))


def spectrum(shaper, omega: RadPerSecond) -> np.ndarray:
    """Frequency response H(j omega) = sum_k A_k e^{-j omega t_k}, vectorised over omega (rad/s).

    Examples
    --------
    >>> import math
    >>> from shapefmu.shapers import zv
    >>> spectrum(zv(2 * math.pi), 0.0)  # the gain
    (1+0j)
    """
    t, a = impulses(shaper)
    w = np.asarray(omega, dtype=float)
    h = (a * np.exp(-1j * w.reshape(-1, 1) * t)).sum(axis=1).reshape(w.shape)
    return complex(h) if h.ndim == 0 else h


def log_decrement_damping(peaks) -> float:
    """Damping ratio from n successive peak amplitudes x_1..x_n (paper 001, eq. 31).

    delta = ln(x_1 / x_n) / (n - 1),   zeta = delta / sqrt(4 pi^2 + delta^2).

    Examples
    --------
    >>> import math
    >>> zeta = 0.05  # peaks one damped period apart decay by exp(-2 pi zeta / sqrt(1 - zeta^2))
    >>> peaks = [math.exp(-2 * math.pi * zeta * k / math.sqrt(1 - zeta**2)) for k in range(4)]
    >>> round(log_decrement_damping(peaks), 12)
    0.05
    """
    x = np.asarray(peaks, dtype=float).ravel()
    if x.size < 2:
        raise ValueError(f"peaks must hold at least 2 successive peak amplitudes, got {x.size}")
    if not np.all(np.isfinite(x)) or x[0] <= 0 or x[-1] <= 0:
        raise ValueError(f"peak amplitudes must be finite and > 0, got first {x[0]!r} and last {x[-1]!r}")
    delta = math.log(x[0] / x[-1]) / (x.size - 1)
    return delta / math.sqrt(4.0 * math.pi**2 + delta**2)


def settling_time(t, y, tolerance: float, final: float = 0.0) -> float:
    """First time after which |y - final| stays within ``tolerance`` until the end of the record.

    Paper 001 settles to 3 % of the initial vibration amplitude: pass ``tolerance=0.03 * x0``.
    Returns ``t[0]`` if the record starts settled and ``inf`` if it never settles.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0.0, 5.0, 501)  # exp(-t) is within 5 % from ln 20 = 2.996 s: the next sample
    >>> settling_time(t, np.exp(-t), 0.05)
    3.0
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if t.ndim != 1 or t.shape != y.shape or t.size == 0:
        raise ValueError(f"t and y must be 1-D of equal, non-zero length, got shapes {t.shape} and {y.shape}")
    tolerance = check_positive(tolerance, "tolerance")
    final = check_finite(final, "final")
    outside = np.flatnonzero(~(np.abs(y - final) <= tolerance))
    if outside.size == 0:
        return float(t[0])
    last = outside[-1]
    return math.inf if last == t.size - 1 else float(t[last + 1])
