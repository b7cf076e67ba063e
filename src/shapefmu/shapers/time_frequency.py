"""Time-frequency localised motion profile (Zhou & Misawa, paper 004).

The acceleration is a sampled, truncated derivative of a Gaussian, the family that attains the
uncertainty bound of eq. (6). Its scale n is chosen so that the largest share of the acceleration's
energy lies below the first resonance: minimise 1 - J (eq. 18-20), J the fraction of the discrete
spectrum's energy in [0, omega_0], omega_0 = Omega_0 * Ts.

1 - J is computed as the energy above omega_0 over the total energy, not as one minus the share
below: near the optimum 1 - J is 1e-5 (2.5 ms moves) to 1e-10 (5 ms), and one minus a ratio would
keep only its first few digits, too few to place n to 1e-6.

The computation is ``shapefmu.runtime.time_frequency`` (standard library, what a ProfileGenerator
or ShapeFilter FMU runs; its ``_leakage`` holds the quadrature), returned here as numpy arrays and a
``MotionProfile``: what is analysed is exactly what the FMU runs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shapefmu.runtime import time_frequency
from shapefmu.runtime.units import RadPerSecond
from shapefmu.shapers.profile import MotionProfile, from_acceleration
from shapefmu.shapers.sampled import SampledShaper


def phi(t, n: float) -> np.ndarray:
    """phi_n(t) = -t exp(-2^{2n} t^2 / 2) (paper 004, eq. 12); n = 0 is eq. (9).

    Its minimum -e^{-1/2} / 2^n sits at t_m = 2^{-n}, and |Phi_n| peaks at omega_m = 2^n (eq. 13).

    Examples
    --------
    >>> import math
    >>> math.isclose(float(phi(0.5, 1)), -math.exp(-0.5) / 2)  # the minimum of phi_1, at t = 1/2
    True
    """
    t = np.asarray(t, dtype=float)
    return -t * np.exp(-0.5 * 4.0**n * t * t)


def sampled_phi(n: float, ts: float, move_time: float) -> np.ndarray:
    """g_{phi,n}[k] = phi_n((k - M/2) Ts), k = 0..M, M = move_time / ts (paper 004, eq. 15).

    Antisymmetric about M/2, so it sums to zero: as an acceleration it brings the velocity back
    to rest.

    Examples
    --------
    >>> g = sampled_phi(11.4, 2e-5, 2.5e-3)  # M = 125: samples k = 0..125
    >>> g.size, abs(float(g.sum())) < 1e-15
    (126, True)
    """
    return np.array(time_frequency.sampled_phi(n, ts, move_time))


def scale_bounds(ts: float, move_time: float) -> tuple[float, float]:
    """Default search interval of n: the peak time t_m = 2^{-n} between one sample and half the move.

    Examples
    --------
    >>> import math
    >>> low, high = scale_bounds(2e-5, 2.5e-3)  # 2^-n from half the move to one sample
    >>> math.isclose(low, math.log2(2 / 2.5e-3)), math.isclose(high, math.log2(1 / 2e-5))
    (True, True)
    """
    return time_frequency.scale_bounds(ts, move_time)


def energy_leakage(n: float, first_resonance: RadPerSecond, ts: float, move_time: float) -> float:
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
    The integrals of eq. (18) are evaluated exactly (see ``shapefmu.runtime.time_frequency._leakage``),
    not by a cumulative sum.

    Examples
    --------
    >>> f"{energy_leakage(11.4, 9.68e3, 2e-5, 2.5e-3):.3e}"  # paper 004's hard-disk case, Fig. 12
    '2.070e-05'
    """
    return time_frequency.energy_leakage(n, first_resonance, ts, move_time)


def optimal_scale(first_resonance: RadPerSecond, ts: float, move_time: float, bounds=None) -> tuple[float, float]:
    """The n minimising 1 - J (eq. 20) by bounded scalar minimisation, and that minimum.

    ``bounds`` defaults to :func:`scale_bounds`. The paper uses Matlab's ``fminbnd``; this is
    ``shapefmu.runtime.scalar_search.minimize_bounded`` (n to 1e-6), the same Brent-on-an-interval
    method as ``fminbnd`` and ``scipy.optimize.minimize_scalar(method='bounded')``.

    Examples
    --------
    >>> n, leakage = optimal_scale(9.68e3, 2e-5, 2.5e-3)
    >>> round(n, 2), f"{leakage:.3e}"
    (11.41, '2.023e-05')
    """
    return time_frequency.optimal_scale(first_resonance, ts, move_time, bounds)


def tradeoff_curve(first_resonance: RadPerSecond, ts: float, move_times) -> tuple[np.ndarray, np.ndarray]:
    """Optimal n and minimal 1 - J against move time (paper 004, Fig. 13).

    Examples
    --------
    >>> n, leakage = tradeoff_curve(9.68e3, 2e-5, [2.5e-3, 5e-3])  # a longer move leaks less
    >>> [round(float(x), 2) for x in n], bool(leakage[1] < leakage[0])
    ([11.41, 10.93], True)
    """
    pairs = [optimal_scale(first_resonance, ts, mt) for mt in np.atleast_1d(move_times)]
    n, leak = np.array(pairs).T
    return n, leak


@dataclass(frozen=True)
class TimeFrequencyProfile:
    """A paper-004 design: the scale n, its energy leakage 1 - J and the rest-to-rest profile.

    Examples
    --------
    >>> design = time_frequency_profile(9.68e3, 2e-5, 2.5e-3, 1.0)
    >>> round(design.profile.distance, 9), abs(float(design.profile.velocity[-1])) < 1e-9  # at rest at the end
    (1.0, True)
    """

    n: float
    leakage: float
    first_resonance: float
    profile: MotionProfile


def time_frequency_profile(
    first_resonance: RadPerSecond, ts: float, move_time: float, distance: float, n=None, *, bounds=None
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
    design = time_frequency.time_frequency_profile(first_resonance, ts, move_time, distance, n, bounds=bounds)
    # The held acceleration K g[k] (the runtime's levels), integrated on the grid.
    profile = from_acceleration(design.motion.levels, design.ts, kernel=SampledShaper(design.kernel, design.ts))
    return TimeFrequencyProfile(design.n, design.leakage, float(first_resonance), profile)
