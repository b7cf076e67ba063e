"""Multi-mode impulse shapers: the convolution method and the simultaneous method (paper 002).

A mode is an ``(omega, zeta)`` pair: undamped natural frequency in rad/s and damping ratio.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable, Sequence

import numpy as np
from scipy.optimize import least_squares

from shapefmu.runtime.multimode import check_modes
from shapefmu.shapers.impulse import ImpulseShaper, zv

Mode = tuple[float, float]


def convolve_modes(
    modes: Sequence[Mode], base: Callable[[float, float], ImpulseShaper] = zv
) -> ImpulseShaper:
    """Convolution method (paper 002, section II-A): one ``base`` shaper per mode, convolved.

    With ``base=zv`` and M modes this gives 2^M impulses at sums of the half periods
    pi/omega_di, with products of the ZV amplitudes (eq. 3) as amplitudes; it is exactly zero at
    every mode because the product of spectra vanishes wherever one factor does.
    """
    checked = check_modes(modes)
    return functools.reduce(ImpulseShaper.convolve, (base(w, z) for w, z in checked))


def simultaneous(modes: Sequence[Mode], starts_per_axis: int = 10) -> ImpulseShaper:
    """Simultaneous method (paper 002, eq. 20): M + 1 impulses for M modes, solved together.

    Unknowns: the M + 1 amplitudes and the times t_2..t_{M+1} (t_1 = 0); equations: for every
    mode j, sum_i a_i e^{-sigma_j (t_N - t_i)} cos(omega_dj t_i) = 0 and the same with sin, and
    sum_i a_i = 1: 2M + 1 of each. The system has many roots. This solves it from a grid of
    ``starts_per_axis`` times per impulse spread over (0, 1.5 T_conv], T_conv = sum pi/omega_dj the
    convolution shaper's length (a feasible length, so the shortest root lies below it), with the
    amplitudes of each start taken from the linear least-squares fit for those times, and returns
    the shortest root whose amplitudes are all positive and whose times are distinct.

    For the disk drive of paper 002 (2.0 and 3.0 kHz, zeta = 0.01) this gives the paper's
    amplitudes 0.2848, 0.4471, 0.2681 at 0, 2.0030e-4, 4.0002e-4 s. The paper prints the times as
    2.0135e-4 and 4.0461e-4 s, which leave 1.1 % and 1.7 % residual vibration at its own modes: they
    are not a root of eq. (20); the root here is exact (residual ~1e-16) and 4.6 us shorter.

    Raises ValueError when no positive root exists (for instance two modes so close that M + 1
    impulses cannot separate them): use ``convolve_modes`` then.
    """
    checked = check_modes(modes)
    if len({w for w, _ in checked}) != len(checked):
        raise ValueError(f"modes must have distinct frequencies for the simultaneous method, got {checked}")
    # Work in time units of 1/omega_max so that every unknown is of order one.
    scale = max(w for w, _ in checked)
    dimensionless = tuple(sorted((w / scale, z) for w, z in checked))
    solution = _solve_simultaneous(dimensionless, starts_per_axis)
    if solution is None:
        raise ValueError(
            f"no simultaneous shaper with {len(checked) + 1} positive impulses found for modes {checked}; "
            "use convolve_modes instead"
        )
    tau, amplitudes = solution
    return ImpulseShaper(tuple(t / scale for t in tau), amplitudes)


def _constraints(tau, modes, derivative=False):
    """Rows of eq. (20) for given times, A(tau) a = e_last; with ``derivative``, also dA/dtau_i.

    Row entries are e^{-sigma (tau_N - tau_i)} cos(omega_d tau_i) and the same with sin. Their
    derivative with respect to their own tau_i is (sigma cos - omega_d sin) e^{...} (and sin/cos
    swapped); tau_N also scales every entry of its row by -sigma, handled by the caller.
    """
    rows, d_rows, sigmas = [], [], []
    for w, z in modes:
        sigma, omega_d = z * w, w * math.sqrt(1.0 - z * z)
        decay = np.exp(-sigma * (tau[-1] - tau))
        cos, sin = np.cos(omega_d * tau), np.sin(omega_d * tau)
        rows += [decay * cos, decay * sin]
        d_rows += [decay * (sigma * cos - omega_d * sin), decay * (sigma * sin + omega_d * cos)]
        sigmas += [sigma, sigma]
    rows.append(np.ones_like(tau))
    if not derivative:
        return np.array(rows)
    d_rows.append(np.zeros_like(tau))
    sigmas.append(0.0)
    return np.array(rows), np.array(d_rows), np.array(sigmas)


def _residuals(x, modes):
    m = len(modes)
    amplitudes, tau = x[: m + 1], np.concatenate([[0.0], x[m + 1 :]])
    target = np.zeros(2 * m + 1)
    target[-1] = 1.0
    return _constraints(tau, modes) @ amplitudes - target


def _jacobian(x, modes):
    m = len(modes)
    amplitudes, tau = x[: m + 1], np.concatenate([[0.0], x[m + 1 :]])
    rows, d_rows, sigmas = _constraints(tau, modes, derivative=True)
    d_tau = d_rows[:, 1:] * amplitudes[1:]
    # tau_N sits in every entry's decay factor e^{-sigma (tau_N - tau_i)}, its own included.
    d_tau[:, -1] -= sigmas * (rows @ amplitudes)
    return np.hstack([rows, d_tau])


@functools.lru_cache(maxsize=64)
def _solve_simultaneous(modes: tuple[Mode, ...], starts_per_axis: int):
    m = len(modes)
    t_conv = sum(math.pi / (w * math.sqrt(1.0 - z * z)) for w, z in modes)
    grid = np.linspace(0.0, 1.5 * t_conv, starts_per_axis + 1)[1:]
    best = None
    for times in itertools.combinations(grid, m):
        tau = np.concatenate([[0.0], times])
        a0 = np.linalg.lstsq(_constraints(tau, modes), np.eye(2 * m + 1)[-1], rcond=None)[0]
        fit = least_squares(
            _residuals,
            np.concatenate([a0, times]),
            jac=_jacobian,
            args=(modes,),
            method="lm",
            xtol=1e-15,
            ftol=1e-15,
            gtol=1e-15,
        )
        amplitudes, tau = fit.x[: m + 1], np.concatenate([[0.0], fit.x[m + 1 :]])
        if np.max(np.abs(_residuals(fit.x, modes))) > 1e-12:
            continue
        order = np.argsort(tau)
        tau, amplitudes = tau[order], amplitudes[order]
        if tau[0] != 0.0 or np.any(np.diff(tau) < 1e-6 * t_conv) or np.any(amplitudes <= 0):
            continue
        if best is None or tau[-1] < best[0][-1] - 1e-12 * t_conv:
            best = (tau, amplitudes)
    if best is None:
        return None
    return tuple(map(float, best[0])), tuple(map(float, best[1]))
