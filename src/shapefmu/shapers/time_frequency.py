"""Time-frequency localised motion profile (Zhou & Misawa, paper 004).

The acceleration is a sampled, truncated derivative of a Gaussian, the family that attains the
uncertainty bound of eq. (6). Its scale n is chosen so that the largest share of the acceleration's
energy lies below the first resonance: minimise 1 - J (eq. 18-20), J the fraction of the discrete
spectrum's energy in [0, omega_0], omega_0 = Omega_0 * Ts.

1 - J is computed as the energy above omega_0 over the total energy (``_leakage``), not as one
minus the share below: near the optimum 1 - J is 1e-5 (2.5 ms moves) to 1e-10 (5 ms), and one
minus a ratio would keep only its first few digits, too few to place n to 1e-6.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from shapefmu.runtime.checks import check_omega, check_positive
from shapefmu.shapers.profile import MotionProfile, from_acceleration
from shapefmu.shapers.sampled import SampledShaper

# Relative tolerance on move_time / ts being an integer number of samples M.
_RTOL = 1e-9


def phi(t, n: float) -> np.ndarray:
    """phi_n(t) = -t exp(-2^{2n} t^2 / 2) (paper 004, eq. 12); n = 0 is eq. (9).

    Its minimum -e^{-1/2} / 2^n sits at t_m = 2^{-n}, and |Phi_n| peaks at omega_m = 2^n (eq. 13).
    """
    t = np.asarray(t, dtype=float)
    return -t * np.exp(-0.5 * 4.0**n * t * t)


def _samples(move_time, ts):
    """M = move_time / ts, which must be an integer: eq. (15) samples k = 0..M."""
    move_time = check_positive(move_time, "move_time")
    ts = check_positive(ts, "ts")
    m_real = move_time / ts
    m = round(m_real)
    if m < 2 or abs(m_real - m) > _RTOL * m_real:
        lo, hi = max(2, math.floor(m_real)), max(2, math.ceil(m_real))
        raise ValueError(
            f"move_time / ts must be an integer M >= 2, got {move_time!r} / {ts!r} = {m_real:.6g}; the nearest "
            f"valid move times are {lo * ts:.10g} s (M = {lo}) and {hi * ts:.10g} s (M = {hi})"
        )
    return m


def sampled_phi(n: float, ts: float, move_time: float) -> np.ndarray:
    """g_{phi,n}[k] = phi_n((k - M/2) Ts), k = 0..M, M = move_time / ts (paper 004, eq. 15).

    Antisymmetric about M/2, so it sums to zero: as an acceleration it brings the velocity back
    to rest.
    """
    m = _samples(move_time, ts)
    return phi((np.arange(m + 1) - m / 2.0) * check_positive(ts, "ts"), n)


def scale_bounds(ts: float, move_time: float) -> tuple[float, float]:
    """Default search interval of n: the peak time t_m = 2^{-n} between one sample and half the move."""
    return math.log2(2.0 / check_positive(move_time, "move_time")), math.log2(1.0 / check_positive(ts, "ts"))


def _bounds(bounds, ts, move_time):
    lo, hi = scale_bounds(ts, move_time) if bounds is None else (float(bounds[0]), float(bounds[1]))
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ValueError(f"bounds must be finite with low < high, got {bounds!r}")
    return lo, hi


def _leakage(g, omega_0):
    """1 - J of eq. (19), as the energy above omega_0 over the total, both computed directly.

    Eq. (19)'s numerator int_0^pi |G|^2 - int_0^{omega_0} |G|^2 is int_{omega_0}^pi |G|^2, here a
    Gauss-Legendre sum of positive terms w_i |G(omega_i)|^2, with no cancellation; the denominator
    is pi sum g^2 (Parseval). With c_k = M/2 - k, |G(omega)| = |sum_k g_k exp(j omega c_k)|.
    |G|^2 is a trigonometric polynomial of degree M; on an interval of half-width h, exp(j M omega)
    has Legendre coefficients ~ j_l(M h), negligible once l > M h + 8 (M h)^(1/3), so a rule exact
    to degree 2 count - 1 above that integrates |G|^2 to rounding.
    """
    half_width = 0.5 * (math.pi - omega_0)
    reach = (g.size - 1) * half_width
    count = math.ceil(0.5 * (reach + 8.0 * reach ** (1.0 / 3.0))) + 16
    nodes, weights = np.polynomial.legendre.leggauss(count)
    phase = np.outer(omega_0 + half_width * (nodes + 1.0), 0.5 * (g.size - 1) - np.arange(g.size))
    power = (np.cos(phase) * g).sum(axis=1) ** 2 + (np.sin(phase) * g).sum(axis=1) ** 2
    return float(half_width * (weights @ power) / (math.pi * (g @ g)))


def _omega_0(first_resonance, ts):
    omega_0 = check_omega(first_resonance, "first_resonance") * check_positive(ts, "ts")
    if omega_0 >= math.pi:
        raise ValueError(
            f"first_resonance * ts must be in (0, pi) (below the Nyquist frequency), got {omega_0:.6g}"
        )
    return omega_0


def energy_leakage(n: float, first_resonance: float, ts: float, move_time: float) -> float:
    """1 - J (paper 004, eq. 18-19): share of the energy of g_{phi,n} above omega_0 = Omega_0 Ts.

    Parameters
    ----------
    n : float
        Scale of phi_n (eq. 12).
    first_resonance : float
        Omega_0, the first resonance of the structure, rad/s.
    ts : float
        Sampling period, s.
    move_time : float
        M Ts, the span of the samples k = 0..M of eq. (15); M must be an integer.

    Notes
    -----
    The integrals of eq. (18) are evaluated exactly (see ``_leakage``), not by a cumulative sum.
    """
    return _leakage(sampled_phi(n, ts, move_time), _omega_0(first_resonance, ts))


def optimal_scale(first_resonance: float, ts: float, move_time: float, bounds=None) -> tuple[float, float]:
    """The n minimising 1 - J (eq. 20) by bounded scalar minimisation, and that minimum.

    ``bounds`` defaults to :func:`scale_bounds`. The paper uses Matlab's ``fminbnd``; this is
    ``scipy.optimize.minimize_scalar(method='bounded')``, the same Brent-on-an-interval method.
    """
    omega_0 = _omega_0(first_resonance, ts)
    lo, hi = _bounds(bounds, ts, move_time)
    m = _samples(move_time, ts)
    t = (np.arange(m + 1) - m / 2.0) * ts
    result = minimize_scalar(
        lambda n: _leakage(phi(t, n), omega_0), bounds=(lo, hi), method="bounded", options={"xatol": 1e-6}
    )
    return float(result.x), float(result.fun)


def tradeoff_curve(first_resonance: float, ts: float, move_times) -> tuple[np.ndarray, np.ndarray]:
    """Optimal n and minimal 1 - J against move time (paper 004, Fig. 13)."""
    pairs = [optimal_scale(first_resonance, ts, mt) for mt in np.atleast_1d(move_times)]
    n, leak = np.array(pairs).T
    return n, leak


@dataclass(frozen=True)
class TimeFrequencyProfile:
    """A paper-004 design: the scale n, its energy leakage 1 - J and the rest-to-rest profile."""

    n: float
    leakage: float
    first_resonance: float
    profile: MotionProfile


def time_frequency_profile(
    first_resonance: float, ts: float, move_time: float, distance: float, n=None, *, bounds=None
) -> TimeFrequencyProfile:
    """Rest-to-rest move over ``distance`` with acceleration K g_{phi,n}[k] (paper 004, eq. 15).

    Parameters
    ----------
    first_resonance : float
        Omega_0, rad/s.
    ts : float
        Sampling period, s.
    move_time : float
        M Ts with M an integer; the held acceleration lasts (M + 1) Ts.
    distance : float
        Distance to cover, > 0.
    n : float, optional
        Scale; by default the optimum of eq. (20) within ``bounds``. A given n must lie in bounds.
    bounds : (float, float), optional
        Search interval of n; defaults to :func:`scale_bounds`.

    Returns
    -------
    TimeFrequencyProfile
        ``profile.kernel`` is the unscaled g_{phi,n}; the acceleration is K times it, K chosen
        (sect. II, "a constant gain K") so that the position ends at ``distance``.

    Examples
    --------
    >>> design = time_frequency_profile(9.68e3, 2e-5, 2.5e-3, 1.0)
    >>> round(design.n, 1)
    11.4
    """
    distance = check_positive(distance, "distance")
    lo, hi = _bounds(bounds, ts, move_time)
    if n is None:
        n, leakage = optimal_scale(first_resonance, ts, move_time, (lo, hi))
    else:
        n = float(n)
        if not lo <= n <= hi:
            raise ValueError(f"n must be in [{lo:.6g}, {hi:.6g}] (the searched bounds), got {n!r}")
        leakage = energy_leakage(n, first_resonance, ts, move_time)
    g = sampled_phi(n, ts, move_time)
    unit = from_acceleration(g, ts)
    if not unit.position[-1] > 0.0:
        raise ValueError(f"n = {n!r} makes g_phi,n vanish on the grid; choose n within the bounds")
    profile = from_acceleration(g * (distance / unit.position[-1]), ts, kernel=SampledShaper(g, ts))
    return TimeFrequencyProfile(n, leakage, float(first_resonance), profile)
