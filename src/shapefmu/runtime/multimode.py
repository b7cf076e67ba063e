"""Simultaneous multi-mode impulse shaper (paper 002, eq. 20), solved with the standard library only.

A Shaper FMU designs this shaper from its mode parameters at the end of initialisation, in a host
Python that may have no numpy or scipy. The design layer (``shapefmu.shapers.multimode.simultaneous``)
calls ``shortest_positive_root`` of this module, so what is analysed is exactly what the FMU runs;
``tests/test_runtime_multimode.py`` checks the root against scipy's MINPACK Levenberg-Marquardt
from the same starts.

API
---
``simultaneous(modes, starts_per_axis=10) -> (times, amplitudes)``
    ``modes`` is a sequence of ``(omega, zeta)`` pairs, omega the undamped natural frequency in
    rad/s (> 0, all distinct) and zeta the damping ratio in [0, 1). Returns two lists of M + 1
    floats for M modes: impulse times in seconds (the first 0, strictly increasing) and positive
    amplitudes summing to 1. Raises ValueError naming the offending mode, or saying that no
    all-positive root exists (then use the convolution of single-mode shapers).
``shortest_positive_root(checked, starts_per_axis)`` -> ``(times, amplitudes)`` or None
    The same for modes already validated by ``check_modes``; None where no positive root exists.

Equations (paper 002, eq. 20), for M modes (sigma_j = zeta_j omega_j, omega_dj = omega_j sqrt(1 - zeta_j^2))
and M + 1 impulses a_i at t_i with t_1 = 0:

    sum_i a_i e^{-sigma_j (t_N - t_i)} cos(omega_dj t_i) = 0,
    sum_i a_i e^{-sigma_j (t_N - t_i)} sin(omega_dj t_i) = 0,     j = 1..M,
    sum_i a_i = 1,

2M + 1 equations in the M + 1 amplitudes and M free times. The system has many roots. It is solved
from a grid of ``starts_per_axis`` times per impulse over (0, 1.5 T_conv], T_conv = sum_j pi/omega_dj
the length of the convolution (ZV per mode) shaper, which is feasible, so the shortest root lies
below it. Each start takes its amplitudes from the linear least-squares fit for its times and is
refined by Levenberg-Marquardt with the analytic Jacobian. The shortest root whose amplitudes are
all positive and whose times are distinct is returned.
"""

import functools
import itertools
import math

from .checks import check_count, check_omega, check_zeta
from .least_squares import solve_least_squares

# A start counts as a root when every equation holds to this.
_ROOT_TOL = 1e-12
_MAX_ITERATIONS = 400


def check_modes(modes, minimum=1):
    """Validate a sequence of (omega, zeta) modes, naming the offending entry by its index."""
    try:
        pairs = [tuple(m) for m in modes]
    except TypeError:
        raise ValueError(f"modes must be a sequence of (omega, zeta) pairs, got {modes!r}") from None
    if len(pairs) < minimum:
        raise ValueError(f"modes must hold at least {minimum} (omega, zeta) pair(s), got {len(pairs)}")
    checked = []
    for i, pair in enumerate(pairs):
        if len(pair) != 2:
            raise ValueError(f"modes[{i}] must be an (omega, zeta) pair, got {pair!r}")
        checked.append((check_omega(pair[0], f"modes[{i}] omega"), check_zeta(pair[1], f"modes[{i}] zeta")))
    return checked


def simultaneous(modes, starts_per_axis=10):
    """Impulse times (s) and amplitudes of the simultaneous shaper for ``modes`` (see module docstring)."""
    checked = check_modes(modes)
    starts_per_axis = check_count(starts_per_axis, "starts_per_axis", minimum=len(checked))
    solution = shortest_positive_root(checked, starts_per_axis)
    if solution is None:
        raise no_positive_root(checked, "the convolution of single-mode shapers")
    return solution


def shortest_positive_root(checked, starts_per_axis):
    """(times in s, amplitudes) of the shortest all-positive root of eq. (20), or None if none is found.

    ``checked`` is a list of (omega, zeta) pairs as ``check_modes`` returns it; the frequencies must
    be distinct. Solutions are cached per mode set (``_solve``).
    """
    if len({w for w, _ in checked}) != len(checked):
        raise ValueError(f"modes must have distinct frequencies for the simultaneous method, got {checked}")
    # Time in units of 1/omega_max, so every unknown is of order one.
    scale = max(w for w, _ in checked)
    dimensionless = tuple(sorted((w / scale, z) for w, z in checked))
    solution = _solve(dimensionless, starts_per_axis)
    if solution is None:
        return None
    tau, amplitudes = solution
    return [t / scale for t in tau], list(amplitudes)


def no_positive_root(checked, instead):
    """The ValueError for modes without a positive root, advising ``instead``."""
    return ValueError(
        f"no simultaneous shaper with {len(checked) + 1} positive impulses found for modes {checked}; "
        f"use {instead} instead"
    )


def _rows(tau, modes):
    """Rows of eq. (20) as functions of the times, their derivatives d/dtau_i, and each row's sigma.

    Entries are e^{-sigma (tau_N - tau_i)} cos(omega_d tau_i) and the same with sin; the derivative
    with respect to their own tau_i is (sigma cos - omega_d sin) e^{...} (sin/cos swapped for the
    sin row). tau_N also sits in every entry's decay factor, which the Jacobian adds separately.
    """
    rows, d_rows, sigmas = [], [], []
    last = tau[-1]
    for w, z in modes:
        sigma, omega_d = z * w, w * math.sqrt(1.0 - z * z)
        decay = [math.exp(-sigma * (last - t)) for t in tau]
        cos = [math.cos(omega_d * t) for t in tau]
        sin = [math.sin(omega_d * t) for t in tau]
        rows.append([e * c for e, c in zip(decay, cos)])
        rows.append([e * s for e, s in zip(decay, sin)])
        d_rows.append([e * (sigma * c - omega_d * s) for e, c, s in zip(decay, cos, sin)])
        d_rows.append([e * (sigma * s + omega_d * c) for e, c, s in zip(decay, cos, sin)])
        sigmas += [sigma, sigma]
    rows.append([1.0] * len(tau))
    d_rows.append([0.0] * len(tau))
    sigmas.append(0.0)
    return rows, d_rows, sigmas


def _evaluate(x, modes):
    """Residuals of eq. (20) and their Jacobian for x = (a_1..a_{M+1}, tau_2..tau_{M+1})."""
    m = len(modes)
    amplitudes, tau = x[: m + 1], [0.0] + x[m + 1 :]
    rows, d_rows, sigmas = _rows(tau, modes)
    values = [math.fsum(r * a for r, a in zip(row, amplitudes)) for row in rows]
    residuals = values[:]
    residuals[-1] -= 1.0
    jacobian = []
    for row, d_row, sigma, value in zip(rows, d_rows, sigmas, values):
        d_tau = [d * a for d, a in zip(d_row[1:], amplitudes[1:])]
        # tau_N in the decay factor e^{-sigma (tau_N - tau_i)} of every entry, its own included.
        d_tau[-1] -= sigma * value
        jacobian.append(row + d_tau)
    return residuals, jacobian


def _levenberg_marquardt(x, modes):
    """Refine x by Levenberg-Marquardt; returns the last accepted x and its residuals.

    Each step solves [J; sqrt(lambda) D] dx = [-r; 0] by QR, D the running maximum of J's column
    norms (More's scaling, as MINPACK): the step is invariant to the units of the unknowns.
    """
    residuals, jacobian = _evaluate(x, modes)
    cost = math.fsum(r * r for r in residuals)
    n = len(x)
    scaling = [0.0] * n
    damping = 1e-3
    for _ in range(_MAX_ITERATIONS):
        if cost == 0.0:
            break
        for j in range(n):
            scaling[j] = max(scaling[j], math.sqrt(math.fsum(row[j] * row[j] for row in jacobian)), 1e-300)
        root = math.sqrt(damping)
        augmented = jacobian + [[root * scaling[j] if k == j else 0.0 for k in range(n)] for j in range(n)]
        step = solve_least_squares(augmented, [-r for r in residuals] + [0.0] * n)
        if step is None:
            break
        candidate = [a + b for a, b in zip(x, step)]
        try:
            new_residuals, new_jacobian = _evaluate(candidate, modes)
            new_cost = math.fsum(r * r for r in new_residuals)
        except (OverflowError, ValueError):
            # A long trial step can put e^{sigma (tau_N - tau_i)} beyond float range: reject it.
            new_cost = math.inf
        if new_cost < cost:
            x, residuals, jacobian, cost = candidate, new_residuals, new_jacobian, new_cost
            damping = max(damping / 3.0, 1e-20)
            size = math.sqrt(math.fsum((s * d) ** 2 for s, d in zip(step, scaling)))
            if size <= 1e-15 * math.sqrt(math.fsum((v * d) ** 2 for v, d in zip(x, scaling))):
                break
        else:
            damping *= 4.0
            if damping > 1e20:
                break
    return x, residuals


@functools.lru_cache(maxsize=64)
def _solve(modes, starts_per_axis):
    m = len(modes)
    t_conv = math.fsum(math.pi / (w * math.sqrt(1.0 - z * z)) for w, z in modes)
    grid = [1.5 * t_conv * i / starts_per_axis for i in range(1, starts_per_axis + 1)]
    target = [0.0] * (2 * m) + [1.0]
    best = None
    for times in itertools.combinations(grid, m):
        tau = [0.0, *times]
        start = solve_least_squares(_rows(tau, modes)[0], target)
        if start is None:
            continue
        x, residuals = _levenberg_marquardt(list(start) + list(times), modes)
        if not max(abs(r) for r in residuals) <= _ROOT_TOL:
            continue
        impulses = sorted(zip([0.0] + x[m + 1 :], x[: m + 1]))
        tau = [t for t, _ in impulses]
        amplitudes = [a for _, a in impulses]
        if tau[0] != 0.0 or any(b - a < 1e-6 * t_conv for a, b in zip(tau, tau[1:])):
            continue
        if any(a <= 0.0 for a in amplitudes):
            continue
        if best is None or tau[-1] < best[0][-1] - 1e-12 * t_conv:
            best = (tuple(tau), tuple(amplitudes))
    return best
