"""Time-optimal rest-to-rest moves of a linear plant under |u| <= u_max, and shaped moves beside them.

``time_optimal`` finds the bang-bang input in three steps:

1. a feasible start: the shortest time, to a factor of 2, at which a linear program on a coarse
   grid of piecewise-constant inputs reaches the target (exact discretisation, scipy's HiGHS);
2. the structure: the shortest T on a fine uniform grid (``lp_transcription``: bisection on T of
   the least-peak LP, with the equality rows orthonormalised so that the ten pendula's nearly
   dependent modes are met too), whose grid input shows the sequence of bang levels and roughly
   where they switch. ``transcribe`` is the free-final-time alternative (CasADi + IPOPT), slower
   and, for the ten pendula, not converging; ``refine_transcription`` accepts either;
3. exact switch times: Newton / Levenberg-Marquardt on the switch instants and T, with the final
   state computed exactly for piecewise-constant input from matrix exponentials of the augmented
   matrix [[A, B], [0, 0]], expm of which holds e^{A t} and its integral times B. Where that
   Jacobian is nearly singular (closely spaced modes: the ten pendula, relative singular value
   ~1e-14) double precision fixes the switch times only to ~1e-4 and the fit slides to a longer
   move; ``refine_exact`` then solves the extremal's equations (rest at T, Pontryagin's switching
   function zero at every switch) for the switch times, T and the costate in 40-digit arithmetic.

``check_optimality`` tests the result against Pontryagin's switching function and a shorter T.
``compare_moves`` then sets the true optimum beside the rigid-body bang-bang of paper 002, eq. (2),
and the bang-bang convolved with impulse shapers (paper 002, eqs. 4 and 21), all simulated exactly.
"""

from __future__ import annotations

import io
import json
import math
import warnings
from pathlib import Path
from dataclasses import dataclass

import casadi as ca
import mpmath
import numpy as np
from scipy.linalg import expm, matrix_balance
from scipy.optimize import least_squares, linprog
from scipy.sparse.csgraph import connected_components

from shapefmu.plants import Plant, as_plant, rigid_part
from shapefmu.runtime.checks import check_finite, check_positive


# ---------------------------------------------------------------------------------------------
# Piecewise-constant commands and their exact simulation


@dataclass(frozen=True)
class Command:
    """A piecewise-constant input: ``levels[k]`` on [breaks[k], breaks[k+1]), then ``final`` for
    t >= breaks[-1] (0 for a plant with a rigid body, the holding input otherwise)."""

    breaks: tuple[float, ...]
    levels: tuple[float, ...]
    final: float = 0.0

    def __post_init__(self):
        if len(self.breaks) != len(self.levels) + 1 or not self.levels:
            raise ValueError(f"a command needs len(breaks) == len(levels) + 1 >= 2, got {len(self.breaks)} "
                             f"and {len(self.levels)}")
        if any(b < a for a, b in zip(self.breaks, self.breaks[1:])):
            raise ValueError(f"breaks must be non-decreasing, got {self.breaks}")

    @property
    def duration(self) -> float:
        return self.breaks[-1] - self.breaks[0]

    @property
    def peak(self) -> float:
        return max(abs(v) for v in self.levels)

    def __call__(self, t) -> np.ndarray:
        """u(t), right-continuous at the breaks."""
        t = np.asarray(t, dtype=float)
        index = np.searchsorted(self.breaks, t, side="right") - 1
        values = np.append(self.levels, self.final)
        u = np.where(index < 0, 0.0, values[np.clip(index, 0, len(self.levels))])
        return u

    def shaped(self, shaper) -> Command:
        """The command convolved with impulses A_i at t_i: sum_i A_i u(t - t_i), exactly.

        The result is piecewise constant again with breaks at every break + t_i (paper 002,
        eq. 4 for the four-impulse convolution shaper and eq. 21 for the three-impulse one).
        """
        times = np.asarray(shaper.times, dtype=float)
        amplitudes = np.asarray(shaper.amplitudes, dtype=float)
        breaks = np.unique((np.asarray(self.breaks)[:, None] + times).ravel())
        # Merge breaks closer than 1e-12 of the duration: sums of delays coincide in exact arithmetic.
        tol = 1e-12 * max(breaks[-1] - breaks[0], 1e-300)
        merged = [breaks[0]]
        for b in breaks[1:]:
            if b - merged[-1] > tol:
                merged.append(b)
        merged = np.array(merged)
        mid = 0.5 * (merged[:-1] + merged[1:])
        levels = sum(a * self(mid - ti) for ti, a in zip(times, amplitudes))
        final = self.final * float(amplitudes.sum())
        return Command(tuple(map(float, merged)), tuple(map(float, levels)), final)


def _augmented_expm(A, B, tau):
    """(e^{A tau}, integral_0^tau e^{A s} ds B) from one expm of [[A, B], [0, 0]] tau."""
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n] = A
    M[:n, n:] = B
    E = expm(M * tau)
    return E[:n, :n], E[:n, n:]


def simulate(plant, command: Command, t=None, x0=None):
    """States of the plant under a piecewise-constant command, exact (no sampling of the input).

    Returns the states at the command's breaks (shape (len(breaks), n)), and, if ``t`` is given
    (sorted, >= the first break), also at the times ``t`` (shape (len(t), n)). The single input is
    the plant's first input; after the last break it is ``command.final``.
    """
    plant = as_plant(plant)
    A, B = plant.A, plant.B[:, :1]
    x = np.zeros(plant.n_states) if x0 is None else np.asarray(x0, dtype=float)
    at_breaks = [x]
    for k, level in enumerate(command.levels):
        E, G = _augmented_expm(A, B, command.breaks[k + 1] - command.breaks[k])
        x = E @ x + G[:, 0] * level
        at_breaks.append(x)
    at_breaks = np.array(at_breaks)
    if t is None:
        return at_breaks
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or np.any(np.diff(t) < 0) or (t.size and t[0] < command.breaks[0]):
        raise ValueError(f"t must be a sorted 1-D array starting at or after {command.breaks[0]!r}")
    # Step through the union of t and the breaks, so that the input is constant on every step;
    # a uniform t repeats one step length, whose matrix exponential is computed once (the step
    # lengths are keyed to 12 significant digits, the accuracy of these sampled states).
    grid = np.union1d(t, command.breaks)
    values = command(grid[:-1])
    states = [at_breaks[0]]
    cache = {}
    for dt, level in zip(np.diff(grid), values):
        key = float(f"{dt:.12e}")
        if key not in cache:
            cache[key] = _augmented_expm(A, B, dt)
        E, G = cache[key]
        states.append(E @ states[-1] + G[:, 0] * level)
    return at_breaks, np.array(states)[np.searchsorted(grid, t)]


# ---------------------------------------------------------------------------------------------
# The problem: target rest state, checks, scaling


def _single_input(plant: Plant) -> None:
    if plant.B.shape[1] != 1:
        raise ValueError(f"plant {plant.name!r} has {plant.B.shape[1]} inputs; time_optimal needs exactly one")


def _u_max(plant: Plant, u_max) -> float:
    if u_max is None:
        if plant.inputs[0] not in plant.limits:
            raise ValueError(f"u_max not given and plant {plant.name!r} declares no limit for input {plant.inputs[0]!r}")
        u_max = plant.limits[plant.inputs[0]]
    return check_positive(u_max, "u_max")


def _output_index(plant: Plant, output) -> int:
    if isinstance(output, str):
        if output not in plant.outputs:
            raise ValueError(f"output must be one of {plant.outputs}, got {output!r}")
        return plant.outputs.index(output)
    if not (isinstance(output, int) and 0 <= output < len(plant.outputs)):
        raise ValueError(f"output must be an index in [0, {len(plant.outputs)}) or a name, got {output!r}")
    return output


def rest_state(plant: Plant, distance: float, output=0) -> tuple[np.ndarray, float]:
    """The equilibrium (x_f, u_f) with A x_f + B u_f = 0 and output y = distance.

    For a plant with a rigid body u_f = 0; for a plant without an integrator (the closed-loop LSM
    of paper 001, eq. 33) the input has to be held at u_f = distance / G(0) after the move.
    Raises ValueError if no such rest state exists or it is not unique.
    """
    j = _output_index(plant, output)
    n = plant.n_states
    M = np.block([[plant.A, plant.B[:, :1]], [plant.C[j : j + 1], plant.D[j : j + 1, :1]]])
    rhs = np.zeros(n + 1)
    rhs[-1] = distance
    if np.linalg.cond(M) > 1e12:
        raise ValueError(
            f"unreachable target: plant {plant.name!r} has no unique rest state with output {plant.outputs[j]!r} = "
            f"{distance:g} (the matrix [[A, B], [C, D]] is singular: a zero at s = 0, or an output that does not "
            "settle at rest)"
        )
    z = np.linalg.solve(M, rhs)
    return z[:n], float(z[n])


def check_controllable(plant: Plant) -> None:
    """PBH test: rank [A - lambda I, B] = n at every eigenvalue, else ValueError naming the mode."""
    # Balance first (diagonal similarity): companion forms with entries from 1 to 1e8 would
    # otherwise make a controllable mode look uncontrollable at any fixed tolerance.
    _, (d, _) = matrix_balance(plant.A, permute=False, separate=True)
    A = plant.A * d[None, :] / d[:, None]
    B = plant.B[:, :1] / d[:, None]
    n = plant.n_states
    scale = max(np.linalg.norm(A, 2), np.linalg.norm(B), 1e-300)
    for lam in np.linalg.eigvals(A):
        s = np.linalg.svd(np.hstack([A - lam * np.eye(n), B]), compute_uv=False)
        if s[-1] <= 1e-10 * scale:
            raise ValueError(
                f"plant {plant.name!r} is not controllable: the mode at s = {lam:.6g} cannot be moved by input "
                f"{plant.inputs[0]!r}, so a rest-to-rest move cannot be planned"
            )


def _grid_maps(A, B, T, N):
    """Exact discretisation on N equal steps: x_N = Gamma u for x_0 = 0, and the step maps."""
    Ad, Bd = _augmented_expm(A, B, T / N)
    n = A.shape[0]
    Gamma = np.empty((n, N))
    column = Bd[:, 0]
    for k in range(N - 1, -1, -1):
        Gamma[:, k] = column
        column = Ad @ column
    return Ad, Bd, Gamma


def _grid_states(A, B, T, u):
    """States at the N + 1 grid points of [0, T] under the grid input u (N steps), from rest."""
    Ad, Bd, _ = _grid_maps(A, B, T, len(u))
    x = [np.zeros(A.shape[0])]
    for uk in u:
        x.append(Ad @ x[-1] + Bd[:, 0] * uk)
    return np.array(x)


def _min_norm_grid_input(A, B, x_f, T, N):
    """The grid input of least peak |u| that reaches x_f at T from rest: (peak, u), by LP (HiGHS).

    The rows of x_N = Gamma u are replaced by the equivalent orthonormal rows V^T u = S^-1 U^T x_f
    (Gamma = U S V^T): closely spaced modes (the ten pendula) make Gamma's singular values span
    15 decades, and a tolerance on the raw rows would let the LP miss the weak directions by far
    more than the rest state allows.
    """
    _, _, Gamma = _grid_maps(A, B, T, N)
    U, S, Vt = np.linalg.svd(Gamma, full_matrices=False)
    n = S.size
    # Variables (u_1..u_N, s): minimise s with -s <= u_k <= s.
    cost = np.zeros(N + 1)
    cost[-1] = 1.0
    eye = np.eye(N)
    A_ub = np.block([[eye, -np.ones((N, 1))], [-eye, -np.ones((N, 1))]])
    result = linprog(cost, A_ub=A_ub, b_ub=np.zeros(2 * N), A_eq=np.hstack([Vt, np.zeros((n, 1))]),
                     b_eq=(U.T @ x_f) / S, bounds=[(None, None)] * N + [(0.0, None)], method="highs")
    if result.status != 0:
        return math.inf, None
    return float(result.x[-1]), result.x[:N]


def _feasible_grid_input(A, B, x_f, u_max, T, N):
    """A grid input with |u| <= u_max reaching x_f at T from rest (None if the LP is infeasible)."""
    peak, u = _min_norm_grid_input(A, B, x_f, T, N)
    return u if peak <= u_max else None


def _bracket(A, B, x_f, u_max, N):
    """The shortest T = T0 * 2^k at which the LP on N steps is feasible, with its input."""
    radius = float(np.max(np.abs(np.linalg.eigvals(A))))
    T = 1.0 / radius if radius > 0 else 1.0
    u = _feasible_grid_input(A, B, x_f, u_max, T, N)
    step = 0.5 if u is not None else 2.0
    for _ in range(200):
        T_next = T * step
        u_next = _feasible_grid_input(A, B, x_f, u_max, T_next, N)
        if step == 0.5 and u_next is None:
            return T, u
        T, u = T_next, u_next
        if step == 2.0 and u is not None:
            return T, u
    raise ValueError("unreachable target: no move time between 2^-200 and 2^200 s was found feasible")


def lp_transcription(plant, distance: float, u_max: float | None = None, n_intervals: int = 100, output=0,
                     rel_tol: float = 1e-6):
    """The shortest move time on a uniform grid of piecewise-constant inputs, by bisection on T of
    the least-peak LP (``_min_norm_grid_input``), and that grid input: a ``Transcription``.

    The grid has max(``n_intervals``, 50 per state) steps, enough for the ten-pendula comb's 21
    switches to fall in separate steps. The grid restricts the input, so its T bounds the true
    minimum from above; its partial steps mark the switches that ``refine`` makes exact.
    """
    plant = as_plant(plant)
    u_max = _u_max(plant, u_max)
    distance = check_finite(distance, "distance")
    if distance == 0.0:
        raise ValueError("distance must be non-zero: a move of 0 takes no time")
    if int(n_intervals) < 2:
        raise ValueError(f"n_intervals must be >= 2, got {n_intervals!r}")
    plant, x_f, _ = _checked_problem(plant, distance, u_max, output)
    A, B = plant.A, plant.B[:, :1]
    N = max(int(n_intervals), 50 * plant.n_states)
    hi, _ = _bracket(A, B, x_f, u_max, min(N, 60))
    peak, u = _min_norm_grid_input(A, B, x_f, hi, N)
    solves = 1
    while peak > u_max:  # the coarse bracket's grid is not this one
        hi *= 2.0
        peak, u = _min_norm_grid_input(A, B, x_f, hi, N)
        solves += 1
    lo = hi / 2.0
    while _min_norm_grid_input(A, B, x_f, lo, N)[0] <= u_max:
        hi, lo = lo, lo / 2.0
        solves += 1
    while hi - lo > rel_tol * hi:
        mid = 0.5 * (lo + hi)
        peak_mid, u_mid = _min_norm_grid_input(A, B, x_f, mid, N)
        solves += 1
        if peak_mid <= u_max:
            hi, u = mid, u_mid
        else:
            lo = mid
    _, u = _min_norm_grid_input(A, B, x_f, hi, N)
    return Transcription(float(hi), np.clip(u, -u_max, u_max), N, solves, distance, u_max,
                         _output_index(plant, output))


# ---------------------------------------------------------------------------------------------
# Direct transcription (CasADi + IPOPT)


@dataclass(frozen=True)
class Transcription:
    """Result of the direct transcription: move time and the grid input (N equal intervals) of the
    move of ``output`` by ``distance`` under |u| <= ``u_max``."""

    T: float
    u: np.ndarray
    n_intervals: int
    iterations: int
    distance: float
    u_max: float
    output: int


def _checked_problem(plant, distance, u_max, output):
    plant = as_plant(plant)
    _single_input(plant)
    check_controllable(plant)
    x_f, u_f = rest_state(plant, distance, output)
    if abs(u_f) >= u_max:
        raise ValueError(f"unreachable target: holding output at {distance:g} needs |u| = {abs(u_f):.6g} >= u_max = "
                         f"{u_max:g}")
    return plant, x_f, u_f


def transcribe(plant, distance: float, u_max: float | None = None, n_intervals: int = 100, output=0,
               tol: float = 1e-10) -> Transcription:
    """Time-optimal move on a uniform grid of ``n_intervals`` piecewise-constant inputs, free T.

    Multiple shooting in dimensionless variables: time in units of a feasible move time t_s (from
    the LP bracket), input in units of u_max and each state in units of its peak on the LP's
    feasible move; the step map e^{theta h A} is its Taylor series of order 12 in the free scaled
    time theta = T / t_s (the grid is refined until |theta h A| <= 0.5, truncation < 1e-12).
    """
    plant = as_plant(plant)
    u_max = _u_max(plant, u_max)
    distance = check_finite(distance, "distance")
    if distance == 0.0:
        raise ValueError("distance must be non-zero: a move of 0 takes no time")
    plant, x_f, _ = _checked_problem(plant, distance, u_max, output)
    A, B = plant.A, plant.B[:, :1]
    N = int(n_intervals)
    if N < 2:
        raise ValueError(f"n_intervals must be >= 2, got {n_intervals!r}")
    t_s, u_lp = _bracket(A, B, x_f, u_max, min(N, 60))
    peak = np.max(np.abs(_grid_states(A, B, t_s, u_lp)), axis=0)
    scale = np.maximum(np.maximum(peak, np.abs(x_f)), 1e-9 * max(peak.max(), abs(distance)))
    # z = x / scale, v = u / u_max, tau = t / t_s: dz/dtau = theta (Ahat z + Bhat v).
    Ahat = t_s * A * scale[None, :] / scale[:, None]
    Bhat = t_s * u_max * B[:, 0] / scale
    theta_max = 1.5
    radius = max(np.linalg.norm(Ahat, 2), 1e-300)
    N = max(N, int(math.ceil(2.0 * theta_max * radius)))
    h = 1.0 / N
    order = 12
    # e^{theta h Ahat} = sum_j theta^j (h Ahat)^j / j!, its integral times Bhat likewise.
    powers = [np.eye(plant.n_states)]
    for j in range(1, order + 2):
        powers.append(powers[-1] @ (h * Ahat) / j)

    opti = ca.Opti()
    theta = opti.variable()
    V = opti.variable(N)
    Z = opti.variable(plant.n_states, N + 1)
    P = sum(theta**j * ca.DM(powers[j]) for j in range(order + 1))
    Q = sum(theta ** (j + 1) * ca.DM(h * powers[j] @ Bhat / (j + 1)) for j in range(order + 1))
    opti.subject_to(Z[:, 0] == 0)
    for k in range(N):
        opti.subject_to(Z[:, k + 1] == ca.mtimes(P, Z[:, k]) + Q * V[k])
    opti.subject_to(Z[:, N] == ca.DM(x_f / scale))
    opti.subject_to(opti.bounded(-1, V, 1))
    opti.subject_to(opti.bounded(0.01, theta, theta_max))
    opti.minimize(theta)
    # Start from the LP's feasible move at theta = 1, resampled onto this grid.
    u0 = np.interp((np.arange(N) + 0.5) / N, (np.arange(u_lp.size) + 0.5) / u_lp.size, u_lp)
    opti.set_initial(theta, 1.0)
    opti.set_initial(V, u0 / u_max)
    opti.set_initial(Z, (_grid_states(A, B, t_s, u0) / scale).T)
    opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "sb": "yes", "tol": tol, "max_iter": 3000})
    try:
        solution = opti.solve()
    except RuntimeError as error:
        raise ValueError(f"the transcription of the move of {distance:g} on plant {plant.name!r} did not converge "
                         f"({error}); try more n_intervals") from None
    stats = solution.stats()
    return Transcription(float(solution.value(theta)) * t_s, np.atleast_1d(solution.value(V)) * u_max, N,
                         int(stats.get("iter_count", -1)), distance, u_max, _output_index(plant, output))


def _structure(u: np.ndarray, T: float, u_max: float) -> tuple[list[float], list[float]]:
    """Bang levels and estimated switch instants from a transcription's grid input.

    Saturated runs (|u| within 1e-3 of u_max) are the bangs. Between two runs of different sign
    the intermediate intervals hold one switch, placed where the integral of the input matches;
    between two runs of the same sign they hold a short pulse of the other sign, of the width and
    at the centre that the integral gives. Intermediate intervals at either end join the first /
    last run.
    """
    N = u.size
    h = T / N
    v = u / u_max
    saturated = np.abs(v) > 1.0 - 1e-3
    if not saturated.any():
        raise ValueError("the transcription's input never reaches the limit: not a bang-bang move")
    runs = []  # (first interval, last interval, sign)
    for k in np.flatnonzero(saturated):
        s = 1.0 if v[k] > 0 else -1.0
        if runs and runs[-1][1] == k - 1 and runs[-1][2] == s:
            runs[-1][1] = k
        else:
            runs.append([k, k, s])
    levels = [runs[0][2]]
    switches = []
    for (a0, a1, s1), (b0, b1, s2) in zip(runs, runs[1:]):
        gap = v[a1 + 1 : b0]
        start = (a1 + 1) * h
        if s1 != s2:
            # s1 (t - start) + s2 (start + len*h - t) = h sum(gap)  ->  t
            switches.append(start + h * float(np.sum((gap - s2) / (s1 - s2))))
            levels.append(s2)
        else:
            width = h * float(np.sum((s1 - gap) / 2.0))
            weights = (s1 - gap) / 2.0
            centre = start + h * (float(np.sum(weights * (np.arange(gap.size) + 0.5)) / max(weights.sum(), 1e-300)))
            switches += [centre - width / 2.0, centre + width / 2.0]
            levels += [-s1, s1]
    return [l * u_max for l in levels], switches


# ---------------------------------------------------------------------------------------------
# Switching-time refinement


def _final_state(A, B, switches, T, levels):
    """x(T) from rest and its Jacobian with respect to (switches..., T), exactly.

    x(T) = sum_k L_k (Phi(T - s_k) - Phi(T - s_{k+1})), Phi(tau) = int_0^tau e^{A s} ds B, so
    dx/ds_k = (L_{k-1} - L_k) e^{A (T - s_k)} B and dx/dT = A x(T) + B L_last.
    """
    edges = np.concatenate([[0.0], switches, [T]])
    x = np.zeros(A.shape[0])
    J = np.zeros((A.shape[0], len(switches) + 1))
    for k, level in enumerate(levels):
        E_a, G_a = _augmented_expm(A, B, T - edges[k])
        G_b = _augmented_expm(A, B, T - edges[k + 1])[1]
        x += level * (G_a[:, 0] - G_b[:, 0])
        if k > 0:
            J[:, k - 1] = (levels[k - 1] - level) * (E_a @ B[:, 0])
    J[:, -1] = A @ x + B[:, 0] * levels[-1]
    return x, J


def refine(plant, x_f, levels, switches, T, scale):
    """Switch times and T with x(T) = x_f exactly (to rounding), by Levenberg-Marquardt.

    Unknowns and residuals are dimensionless (times / T, states / ``scale``) so that the
    tolerances mean relative accuracy.
    """
    A, B = plant.A, plant.B[:, :1]
    t0 = float(T)

    def residual(p):
        return (_final_state(A, B, p[:-1] * t0, p[-1] * t0, levels)[0] - x_f) / scale

    def jacobian(p):
        return _final_state(A, B, p[:-1] * t0, p[-1] * t0, levels)[1] * t0 / scale[:, None]

    p0 = np.append(np.asarray(switches, dtype=float), T) / t0
    # Levenberg-Marquardt needs at least as many residuals as unknowns; more switches than states
    # (fast oscillatory modes over a long move) leave a family of solutions: trust region then.
    method = "lm" if p0.size <= x_f.size else "trf"
    fit = least_squares(residual, p0, jac=jacobian, method=method, xtol=1e-15, ftol=1e-15, gtol=1e-15,
                        max_nfev=100 * p0.size)
    p = fit.x * t0
    return list(p[:-1]), float(p[-1])


# ---------------------------------------------------------------------------------------------
# Exact (extended-precision) propagation, for plants whose modes are closely spaced


_EXACT_DIGITS = 40


def _divided_difference(f, df, l1, l2):
    """f[l1, l2] = (f(l1) - f(l2)) / (l1 - l2), f'(l1) when l1 == l2 (Newton form of a 2x2 f(M))."""
    if l1 == l2:
        return df(l1)
    with mpmath.workdps(2 * mpmath.mp.dps):  # the difference of nearly equal values loses digits
        return (f(l1) - f(l2)) / (l1 - l2)


class _ExactPlant:
    """e^{A tau} B and Phi(tau) = int_0^tau e^{A s} ds B to ``_EXACT_DIGITS`` digits (mpmath).

    Closely spaced modes (the ten pendula) make the final state's dependence on the switch times
    nearly singular (relative singular values ~1e-14): double precision then fixes the switch
    times only to ~1e-4 and lets an iteration slide along the weak directions. In 40 digits those
    directions are resolved to ~1e-26. A is split into the blocks that no entry couples (a modal or
    physical-coordinate model is block diagonal), and each block of size <= 2 is evaluated in
    closed form, f(M) = f(l1) I + f[l1, l2] (M - l1 I) (Newton's form of Sylvester's formula) with
    f(l) = e^{l tau} and f(l) = (e^{l tau} - 1) / l; larger blocks use mpmath's expm of the
    augmented matrix [[A, B], [0, 0]].
    """

    def __init__(self, A, B):
        n = A.shape[0]
        _, labels = connected_components(np.abs(A) + np.abs(A.T) > 0, directed=False)
        self.n = n
        self.blocks = []
        for label in np.unique(labels):
            index = np.flatnonzero(labels == label)
            M = mpmath.matrix(A[np.ix_(index, index)].tolist())
            b = mpmath.matrix(B[index, 0].tolist())
            if index.size == 1:
                eigenvalues = (M[0, 0], M[0, 0])
            elif index.size == 2:
                half = (M[0, 0] + M[1, 1]) / 2
                root = mpmath.sqrt(mpmath.mpc(half**2 - (M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0])))
                eigenvalues = (half + root, half - root)
            else:
                eigenvalues = None
            self.blocks.append((index, M, b, eigenvalues))
        self.A = mpmath.matrix(A.tolist())
        self.B = mpmath.matrix(B[:, 0].tolist())

    def _block(self, M, b, eigenvalues, f, df):
        l1, l2 = eigenvalues
        if M.rows == 1:
            return mpmath.matrix([mpmath.re(f(l1)) * b[0]])
        c0, c1 = f(l1), _divided_difference(f, df, l1, l2)
        Mb = M * b
        return mpmath.matrix([mpmath.re(c0 * b[i] + c1 * (Mb[i] - l1 * b[i])) for i in range(M.rows)])

    def propagate(self, tau):
        """(e^{A tau} B, Phi(tau)) as mpmath vectors."""
        tau = mpmath.mpf(tau)
        E, P = mpmath.matrix(self.n, 1), mpmath.matrix(self.n, 1)
        for index, M, b, eigenvalues in self.blocks:
            if eigenvalues is None:
                k = M.rows
                aug = mpmath.zeros(k + 1, k + 1)
                for i in range(k):
                    aug[i, k] = b[i] * tau
                    for j in range(k):
                        aug[i, j] = M[i, j] * tau
                Z = mpmath.expm(aug)
                e_block = mpmath.matrix([sum(Z[i, j] * b[j] for j in range(k)) for i in range(k)])
                p_block = mpmath.matrix([Z[i, k] for i in range(k)])
            else:
                exp = lambda l: mpmath.exp(l * tau)
                dexp = lambda l: tau * mpmath.exp(l * tau)
                phi = lambda l: mpmath.expm1(l * tau) / l if l != 0 else tau
                dphi = lambda l: (l * tau * mpmath.exp(l * tau) - mpmath.expm1(l * tau)) / l**2 if l != 0 else tau**2 / 2
                e_block = self._block(M, b, eigenvalues, exp, dexp)
                p_block = self._block(M, b, eigenvalues, phi, dphi)
            for i, row in enumerate(index):
                E[int(row)], P[int(row)] = e_block[i], p_block[i]
        return E, P

    def switching_function(self, eta):
        """sigma(tau) = eta^T e^{A tau} B as a function of the time to go tau, in closed form per block:
        eta_b^T f(M) b = f(l1) eta_b^T b + f[l1, l2] eta_b^T (M - l1 I) b with f(l) = e^{l tau}."""
        terms = []
        for index, M, b, eigenvalues in self.blocks:
            e = [eta[int(i)] for i in index]
            if eigenvalues is None:
                terms.append((None, M, b, e))
            else:
                Mb = M * b
                along_b = sum(e[i] * b[i] for i in range(M.rows))
                along_m = sum(e[i] * (Mb[i] - eigenvalues[0] * b[i]) for i in range(M.rows)) if M.rows == 2 else 0
                terms.append((eigenvalues, along_b, along_m, None))

        def sigma(tau):
            tau = mpmath.mpf(tau)
            exp = lambda l: mpmath.exp(l * tau)
            dexp = lambda l: tau * mpmath.exp(l * tau)
            total = mpmath.mpf(0)
            for eigenvalues, first, second, e in terms:
                if eigenvalues is None:  # first, second = M, b of a block larger than 2
                    total += sum(ei * value for ei, value in zip(e, mpmath.expm(first * tau) * second))
                else:
                    l1, l2 = eigenvalues
                    total += mpmath.re(first * exp(l1) + second * _divided_difference(exp, dexp, l1, l2))
            return total

        return sigma

    def final_state(self, switches, T, levels):
        """x(T) from rest, its Jacobian in (switches..., T) as in ``_final_state``, and the columns
        e^{A (T - s)} B at s = 0, the switches and T, exactly."""
        edges = [mpmath.mpf(0), *switches, T]
        phis, columns = [], []
        for edge in edges:
            E, P = self.propagate(T - edge)
            phis.append(P)
            columns.append(E)
        x = mpmath.matrix(self.n, 1)
        for k, level in enumerate(levels):
            x += level * (phis[k] - phis[k + 1])
        J = mpmath.matrix(self.n, len(switches) + 1)
        for k in range(1, len(levels)):
            for i in range(self.n):
                J[i, k - 1] = (levels[k - 1] - levels[k]) * columns[k][i]
        rate = self.A * x + self.B * levels[-1]
        for i in range(self.n):
            J[i, len(switches)] = rate[i]
        return x, J, columns


def _rest_state_exact(plant: Plant, distance: float, output: int):
    """``rest_state`` in extended precision (a double solve leaves ~1e-17 in the modal targets,
    which the weak directions would amplify)."""
    j = output
    M = np.block([[plant.A, plant.B[:, :1]], [plant.C[j : j + 1], plant.D[j : j + 1, :1]]])
    rhs = mpmath.matrix(M.shape[0], 1)
    rhs[M.shape[0] - 1] = mpmath.mpf(distance)
    return mpmath.lu_solve(mpmath.matrix(M.tolist()), rhs)[: plant.n_states, 0]


def refine_exact(plant, distance: float, output: int, levels, switches, T, max_iterations: int = 40):
    """Switch times, T and the costate eta of a bang-bang extremal, by Newton's method in
    ``_EXACT_DIGITS`` digits: x(T) = x_f, sigma(s_k) = eta^T e^{A (T - s_k)} B = 0 at every switch
    and eta^T x_f = 1 (n + m + 1 equations in the m switches, T and the n costate components).

    With the costate among the unknowns the system is square for any number of switches m (the
    ten pendula's longer moves need n + 1). Returns (switches, T) rounded to double, or None if
    Newton does not converge, reorders the switches or meets a singular Jacobian.
    """
    plant = as_plant(plant)
    n, m = plant.n_states, len(switches)
    with mpmath.workdps(_EXACT_DIGITS):
        exact = _ExactPlant(plant.A, plant.B[:, :1])
        x_f = _rest_state_exact(plant, distance, output)
        levels = [mpmath.mpf(level) for level in levels]
        # Initial costate: the direction nearest to orthogonal to e^{A (T - s_k)} B at every switch.
        rows = mpmath.zeros(m + 1, n)
        for k, s in enumerate(switches):
            column = exact.propagate(mpmath.mpf(T) - s)[0]
            for i in range(n):
                rows[k, i] = column[i]
        eta = mpmath.svd_r(rows, full_matrices=True)[2][n - 1, :].T
        along = sum(eta[i] * x_f[i] for i in range(n))
        if along == 0:
            return None
        p = mpmath.matrix([*map(mpmath.mpf, switches), mpmath.mpf(T), *(eta / along)])
        for _ in range(max_iterations):
            s, t_end, eta = list(p[:m]), p[m], p[m + 1 :]
            x, J_x, columns = exact.final_state(s, t_end, levels)
            F = mpmath.zeros(n + m + 1, 1)
            J = mpmath.zeros(n + m + 1, n + m + 1)
            for i in range(n):
                F[i] = x[i] - x_f[i]
                for j in range(m + 1):
                    J[i, j] = J_x[i, j]
            for k in range(m):
                column = columns[k + 1]
                rate = exact.A * column
                F[n + k] = sum(eta[i] * column[i] for i in range(n))
                slope = sum(eta[i] * rate[i] for i in range(n))
                J[n + k, k], J[n + k, m] = -slope, slope
                for i in range(n):
                    J[n + k, m + 1 + i] = column[i]
            F[n + m] = sum(eta[i] * x_f[i] for i in range(n)) - 1
            for i in range(n):
                J[n + m, m + 1 + i] = x_f[i]
            try:
                step = mpmath.lu_solve(J, -F)
            except ZeroDivisionError:
                return None
            p += step
            edges = [0.0, *(float(v) for v in p[: m + 1])]
            if any(b <= a for a, b in zip(edges[:-1], edges[1:])):
                return None
            if mpmath.norm(step[: m + 1]) <= mpmath.mpf(10) ** (16 - _EXACT_DIGITS) * p[m]:
                x = exact.final_state(list(p[:m]), p[m], levels)[0]
                if mpmath.norm(x - x_f) > mpmath.mpf(10) ** (20 - _EXACT_DIGITS) * mpmath.norm(x_f):
                    return None
                return [float(v) for v in p[:m]], float(p[m])
        return None


# ---------------------------------------------------------------------------------------------
# The solution object


@dataclass(frozen=True)
class TimeOptimalSolution:
    """A time-optimal rest-to-rest move.

    ``levels[k]`` is the input on [switch_k, switch_{k+1}) with switch_0 = 0 and switch_last = T;
    after T the input is ``u_final``. ``t``, ``u``, ``x`` sample the exact solution (with every
    switch instant in ``t``). ``final_error`` is x(T) - x_f from the exact propagation of the
    refined switch times; ``residual`` is max_i |final_error_i| / peak_i, the peak of |x_i| over
    the move. ``transcription_T`` is the move time of the grid transcription that found the
    structure.
    """

    T: float
    switch_times: tuple[float, ...]
    levels: tuple[float, ...]
    t: np.ndarray
    u: np.ndarray
    x: np.ndarray
    distance: float
    u_max: float
    u_final: float
    final_error: tuple[float, ...]
    residual: float
    states: tuple[str, ...]
    transcription_T: float

    @property
    def command(self) -> Command:
        return Command((0.0, *self.switch_times, self.T), self.levels, self.u_final)

    def to_dict(self) -> dict:
        return {
            "kind": "time_optimal",
            "T": self.T,
            "switch_times": list(self.switch_times),
            "levels": list(self.levels),
            "u_final": self.u_final,
            "distance": self.distance,
            "u_max": self.u_max,
            "final_error": list(self.final_error),
            "residual": self.residual,
            "states": list(self.states),
            "transcription_T": self.transcription_T,
        }

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2)

    def to_csv(self) -> str:
        """Signal table ``time,u`` of the piecewise-constant input: each row's value holds from its
        time until the next row's (zero-order hold), rows at 0, each exact switch instant and T
        (where the input becomes ``u_final``). Times are printed with 17 significant digits."""
        out = io.StringIO()
        out.write("time,u\n")
        for time, level in zip((0.0, *self.switch_times, self.T), (*self.levels, self.u_final)):
            out.write(f"{time:.17g},{level:.17g}\n")
        return out.getvalue()


def _peak_scale(x, x_f, distance):
    peak = np.maximum(np.max(np.abs(x), axis=0), np.abs(x_f))
    return np.maximum(peak, 1e-12 * abs(distance))


def time_optimal(plant, distance: float, u_max: float | None = None, output=0, n_intervals: int = 100,
                 n_samples: int = 2001, tolerance: float = 1e-9) -> TimeOptimalSolution:
    """The minimum-time rest-to-rest move of ``output`` by ``distance`` with |u| <= u_max.

    ``plant`` is a ``Plant``, a python-control LTI or a model file with one input; ``u_max``
    defaults to the plant's declared input limit. Every mode ends at rest: x(T) = x_f with
    (x_f, u_f) the rest state of ``rest_state``. The grid transcription (``lp_transcription``, at
    least ``n_intervals`` steps) finds the bang-bang structure; ``refine`` makes the switch times
    exact; ``check_optimality`` verifies the result.

    Raises ValueError for u_max <= 0, a plant that is not controllable from its input, or a
    target that has no rest state within the limit. Warns (RuntimeWarning) if the refined move
    misses the rest state by more than ``tolerance`` (relative to each state's peak), or is longer
    than the grid's move (then it rests but is not the optimum: the structure was wrong).
    """
    plant = as_plant(plant)
    grid = lp_transcription(plant, distance, u_max, n_intervals, output)
    return refine_transcription(plant, grid, n_samples, tolerance)


def _ill_conditioned(plant, levels, switches, T, scale, threshold: float = 1e-8) -> bool:
    """True if the final state's Jacobian in (switches, T), dimensionless, has a singular value
    below ``threshold`` of its largest: double precision then leaves the switch times uncertain
    by ~1e-16 / threshold (closely spaced modes)."""
    J = _final_state(plant.A, plant.B[:, :1], np.asarray(switches, dtype=float), T, levels)[1] * T / scale[:, None]
    s = np.linalg.svd(J, compute_uv=False)
    return bool(s[-1] < threshold * s[0])


def refine_transcription(plant, grid: Transcription, n_samples: int = 2001,
                         tolerance: float = 1e-9) -> TimeOptimalSolution:
    """The exact time-optimal move from the bang-bang structure of a transcription (``refine``,
    and ``refine_exact`` where the double-precision fit is ill-conditioned)."""
    plant = as_plant(plant)
    distance, u_max, output = grid.distance, grid.u_max, grid.output
    x_f, u_f = rest_state(plant, distance, output)
    levels, switches = _structure(grid.u, grid.T, u_max)
    command = Command((0.0, *switches, grid.T), tuple(levels), u_f)
    _, states = simulate(plant, command, np.linspace(0.0, grid.T, 201))
    scale = _peak_scale(states, x_f, distance)
    start = (list(switches), grid.T)
    switches, T = refine(plant, x_f, levels, switches, grid.T, scale)
    if _ill_conditioned(plant, levels, switches, T, scale):
        # The double-precision fit has only ~1e-4 of the switch times right; redo it in extended
        # precision from the transcription's estimate, else from that fit. An extremal that
        # reaches x_f is the optimum (``check_optimality`` verifies it), so the first one is kept.
        for guess in (start, (switches, T)):
            exact = refine_exact(plant, distance, output, levels, *guess)
            if exact is not None:
                switches, T = exact
                break
    edges = np.concatenate([[0.0], switches, [T]])
    if np.any(np.diff(edges) < -1e-12 * T):
        raise ValueError(f"switch-time refinement of the move of {distance:g} on plant {plant.name!r} reordered the "
                         f"switches ({edges}); the transcription's structure is wrong: raise n_intervals")
    command = Command(tuple(map(float, edges)), tuple(levels), u_f)
    t = np.union1d(np.linspace(0.0, T, n_samples), edges)
    at_breaks, x = simulate(plant, command, t)
    error = at_breaks[-1] - x_f
    residual = float(np.max(np.abs(error) / _peak_scale(x, x_f, distance)))
    if T > grid.T * (1.0 + 1e-9):
        # The grid's move is feasible, so the optimum is no longer than grid.T: the refinement has
        # slid along a nearly singular direction (closely spaced modes) to a longer extremal.
        warnings.warn(f"time_optimal: the refined move ({T:.10g} s) is longer than the grid transcription's "
                      f"({grid.T:.10g} s) on plant {plant.name!r}; it rests but is not time-optimal to "
                      f"{T / grid.T - 1:.2g}", RuntimeWarning, stacklevel=3)
    if residual > tolerance:
        # Closely spaced modes (the ten pendula) can call for pulses shorter than the grid resolves;
        # the refined move then misses the target by ``residual``, which the solution reports.
        warnings.warn(f"time_optimal: the {len(switches)}-switch structure found by the transcription leaves a "
                      f"final-state residual of {residual:.3g} > {tolerance:g} on plant {plant.name!r}; "
                      "the move is not exactly rest-to-rest", RuntimeWarning, stacklevel=3)
    return TimeOptimalSolution(
        T=float(T), switch_times=tuple(map(float, switches)), levels=tuple(map(float, levels)), t=t, u=command(t),
        x=x, distance=distance, u_max=u_max, u_final=u_f, final_error=tuple(map(float, error)), residual=residual,
        states=plant.states, transcription_T=grid.T,
    )


# ---------------------------------------------------------------------------------------------
# Optimality check (Pontryagin's switching function and a shorter-time test)


@dataclass(frozen=True)
class OptimalityCheck:
    """Evidence that a bang-bang move is time-optimal, not only feasible.

    Pontryagin: u(t) = u_max sign(sigma(t)) with sigma(t) = eta^T e^{A (T - t)} B, eta the final
    costate. ``costate`` is eta (unit length, in the plant's states divided by their peaks over the
    move), the right singular vector of [e^{A (T - t_k)} B]^T over the switches t_k, so that sigma
    vanishes at every switch; unique when there are >= n - 1 switches. ``sigma_at_switches`` is
    max |sigma(t_k)| / max |sigma|; ``sign_margin`` the least of level * sigma / max |sigma| over
    50 interior points of every arc (> 0: sigma changes sign exactly at the switches and nowhere
    else, so the move maximises eta^T x(T) and its end lies on the boundary of the reachable set).
    ``dual_peak_at_shorter`` is eta^T x_f / int_0^T' |eta^T e^{A s} B| ds at T' = T (1 - shorter):
    by weak duality every input that reaches x_f at T' needs a peak at least this, so a value above
    u_max proves that no move is that much shorter. ``lp_peak_at_shorter`` is the least peak of a
    grid input (``n_intervals`` steps, LP) reaching x_f at T', above u_max when the grid is infeasible.
    """

    costate: tuple[float, ...]
    sigma_at_switches: float
    sign_margin: float
    shorter: float
    dual_peak_at_shorter: float
    lp_peak_at_shorter: float
    u_max: float
    n_intervals: int

    @property
    def time_optimal(self) -> bool:
        return (self.sign_margin > 0.0 and self.dual_peak_at_shorter > self.u_max
                and self.lp_peak_at_shorter > self.u_max)


def _planned_rest_state(plant: Plant, solution: TimeOptimalSolution):
    """The rest state the move was planned for, in extended precision: ``rest_state`` of the first
    output whose rest state matches x(T) - final_error (the output is not stored)."""
    x_f = simulate(plant, solution.command)[-1] - np.asarray(solution.final_error)
    tolerance = 1e-9 * max(float(np.max(np.abs(x_f))), abs(solution.distance))
    for j in range(len(plant.outputs)):
        try:
            candidate, _ = rest_state(plant, solution.distance, j)
        except ValueError:
            continue
        if np.max(np.abs(candidate - x_f)) <= tolerance:
            return x_f, _rest_state_exact(plant, solution.distance, j)
    return x_f, mpmath.matrix(x_f.tolist())


def check_optimality(plant, solution: TimeOptimalSolution, shorter: float = 1e-4,
                     n_intervals: int | None = None) -> OptimalityCheck:
    """Pontryagin's switching function of ``solution`` and the shorter-time tests (``OptimalityCheck``).

    The costate, sigma and the dual bound are computed in ``_EXACT_DIGITS`` digits (``_ExactPlant``):
    for closely spaced modes the costate's modal components are ~1e12 times its rigid-body ones and
    cancel in sigma, which double precision would leave with no correct digit.
    ``n_intervals`` defaults to 100 per state for the grid LP at T (1 - ``shorter``).
    """
    plant = as_plant(plant)
    shorter = check_positive(shorter, "shorter")
    if shorter >= 1.0:
        raise ValueError(f"shorter must be in (0, 1), got {shorter!r}")
    T = solution.T
    switches = np.asarray(solution.switch_times, dtype=float)
    levels = np.sign(solution.levels)
    edges = np.concatenate([[0.0], switches, [T]])
    T_short = T * (1.0 - shorter)
    with mpmath.workdps(_EXACT_DIGITS):
        x_f, x_f_exact = _planned_rest_state(plant, solution)
        # Peak-scaled states: the modal rows would otherwise dominate the singular vectors.
        scale = _peak_scale(solution.x, x_f, solution.distance)
        exact = _ExactPlant(plant.A, plant.B[:, :1])
        n = plant.n_states
        rows = mpmath.zeros(len(switches) + 1, n)
        for k, t in enumerate(switches):
            column = exact.propagate(T - t)[0]
            for i in range(n):
                rows[k, i] = column[i] / scale[i]
        eta = mpmath.svd_r(rows, full_matrices=True)[2][n - 1, :]
        # sigma in the peak-scaled states is (eta / scale)^T e^{A (T - t)} B.
        eta_physical = [eta[i] / scale[i] for i in range(n)]
        sigma_of_time_to_go = exact.switching_function(eta_physical)
        fractions = (np.arange(50) + 0.5) / 50
        samples = [(level, a + fractions * (c - a)) for level, a, c in zip(levels, edges, edges[1:]) if level != 0]
        sigma = [(level, np.array([float(sigma_of_time_to_go(T - ti)) for ti in t])) for level, t in samples]
        peak = max(float(np.max(np.abs(values))) for _, values in sigma)
        sign = 1.0 if sigma[0][0] * sigma[0][1][0] >= 0 else -1.0  # free sign: u = +u_max where sigma > 0
        margin = min(float(np.min(level * sign * values)) for level, values in sigma) / peak
        at_switches = max((abs(float(sigma_of_time_to_go(T - t))) for t in switches), default=0.0) / peak
        # int_0^T' |sigma| over time-to-go s = T - t: sigma's roots are the switches' s_k = T - t_k.
        cuts = np.concatenate([[0.0], np.sort(T - switches), [T]])
        cuts = np.append(cuts[cuts < T_short], T_short)
        Phi = [exact.propagate(c)[1] for c in cuts]
        integral = sum(abs(sum(eta_physical[i] * (p1[i] - p0[i]) for i in range(n))) for p0, p1 in zip(Phi, Phi[1:]))
        dual_peak = float(abs(sum(eta_physical[i] * x_f_exact[i] for i in range(n))) / integral)
        costate = tuple(float(sign * value) for value in eta)
    N = 100 * plant.n_states if n_intervals is None else int(n_intervals)
    lp_peak, _ = _min_norm_grid_input(plant.A, plant.B[:, :1], x_f, T_short, N)
    return OptimalityCheck(costate, at_switches, margin, shorter, dual_peak, lp_peak, solution.u_max, N)


# ---------------------------------------------------------------------------------------------
# Comparison of moves


@dataclass(frozen=True)
class Move:
    """One move of a comparison: its command, length, residual vibration and peak input."""

    name: str
    command: Command
    duration: float
    residual: float
    peak: float


@dataclass(frozen=True)
class MoveComparison:
    plant: str
    distance: float
    u_max: float
    moves: tuple[Move, ...]
    optimal: TimeOptimalSolution

    def table(self) -> str:
        width = max(len(move.name) for move in self.moves)
        lines = [f"plant {self.plant}: move of {self.distance:g} with |u| <= {self.u_max:g}",
                 f"{'move':<{width}} {'time [s]':>14} {'vs optimal':>11} {'residual':>11} {'peak |u|':>10}"]
        for move in self.moves:
            lines.append(f"{move.name:<{width}} {move.duration:14.8g} {move.duration / self.optimal.T:11.5f} "
                         f"{move.residual:11.3e} {move.peak:10.4g}")
        return "\n".join(lines)


def residual_after_move(plant, command: Command, distance: float, output=0) -> float:
    """Vibration left after a move, relative to the distance.

    The largest |y_j(t) - y_j,f| over every output j and t from the end of the command through one
    period of the slowest oscillatory mode (the free response from the exact final state is
    evaluated at 400 points of that window), divided by |distance|. A move that ends exactly at
    rest has residual 0.
    """
    plant = as_plant(plant)
    x_f, _ = rest_state(plant, distance, output)
    x_end = simulate(plant, command)[-1]
    oscillatory = [m.omega for m in plant.modes() if m.oscillatory]
    window = 2.0 * math.pi / min(oscillatory) if oscillatory else 0.0
    error = x_end - x_f
    step = expm(plant.A * (window / 399))
    peak = 0.0
    for _ in range(400):
        peak = max(peak, float(np.max(np.abs(plant.C @ error))))
        error = step @ error
    return peak / abs(distance)


def rigid_bang_bang(plant, distance: float, u_max: float | None = None, output=0) -> Command:
    """The time-optimal bang-bang of the plant's rigid part alone (paper 002, eq. 2 for b2/s^2):
    the unshaped command that the shapers are convolved with."""
    plant = as_plant(plant)
    rigid = time_optimal(rigid_part(plant), distance, _u_max(plant, u_max), output, n_intervals=40, n_samples=2)
    return rigid.command


def compare_moves(plant, distance: float, u_max: float | None = None, shapers=None, output=0) -> MoveComparison:
    """Move time and residual vibration of the rigid bang-bang, of it convolved with each shaper,
    and of the time-optimal move, all simulated exactly on the full plant.

    ``shapers`` maps a name to an ``ImpulseShaper``; by default the convolution (ZV per mode) and
    simultaneous shapers of paper 002 (Sec. II) for the plant's oscillatory modes.
    """
    from shapefmu.shapers import convolve_modes, simultaneous

    plant = as_plant(plant)
    u_max = _u_max(plant, u_max)
    if shapers is None:
        modes = plant.flexible_modes()
        shapers = {"convolution (ZV per mode)": convolve_modes(modes), "simultaneous": simultaneous(modes)}
    rigid = rigid_bang_bang(plant, distance, u_max, output)
    optimal = time_optimal(plant, distance, u_max, output)
    candidates = [("rigid bang-bang", rigid)]
    candidates += [(f"bang-bang * {name}", rigid.shaped(shaper)) for name, shaper in shapers.items()]
    candidates.append(("time-optimal", optimal.command))
    moves = tuple(
        Move(name, command, command.duration, residual_after_move(plant, command, distance, output), command.peak)
        for name, command in candidates
    )
    return MoveComparison(plant.name, distance, u_max, moves, optimal)


def plot_comparison(comparison: MoveComparison, plant, path) -> None:
    """Save u(t) of every move (top), the moved output (middle) and the other outputs, the modal
    deflections for the plants of paper 002 (bottom), under the time-optimal move, to ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plant = as_plant(plant)
    panels = 3 if len(plant.outputs) > 1 else 2
    fig, axes = plt.subplots(panels, 1, sharex=True, figsize=(8, 2.6 * panels))
    for move in comparison.moves:
        t = np.array(move.command.breaks)
        axes[0].step(t, np.append(move.command.levels, move.command.final), where="post", label=move.name)
    axes[0].set_ylabel(f"input {plant.inputs[0]}")
    axes[0].legend(fontsize="small")
    optimal = comparison.optimal
    y = optimal.x @ plant.C.T + np.outer(optimal.u, plant.D[:, 0])
    axes[1].plot(optimal.t, y[:, 0], label=f"{plant.outputs[0]} (time-optimal)")
    axes[1].set_ylabel(plant.outputs[0])
    axes[1].legend(fontsize="small")
    if panels == 3:
        for j, name in enumerate(plant.outputs[1:], start=1):
            axes[2].plot(optimal.t, y[:, j], label=name)
        axes[2].set_ylabel("other outputs (time-optimal)")
        axes[2].legend(fontsize="small")
    axes[-1].set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def optimal_report(path, distance: float, u_max: float | None = None, plot=None, json_path=None,
                   csv_path=None) -> str:
    """The text of ``shapefmu optimal FILE --distance X [--u-max U] [--plot out.png] [--json s.json]
    [--csv u.csv]``; the JSON and CSV files are the solution's ``to_json`` and ``to_csv``, which
    ``shapefmu build reference`` plays back."""
    plant = as_plant(path)
    comparison = compare_moves(plant, distance, u_max)
    optimal = comparison.optimal
    lines = [comparison.table(), "",
             f"time-optimal: T = {optimal.T:.12g} s, {len(optimal.switch_times)} switches at "
             + ", ".join(f"{s:.10g}" for s in optimal.switch_times),
             f"refined final-state residual {optimal.residual:.3e} (transcription T = {optimal.transcription_T:.10g} s)"]
    for target, text, what in ((json_path, optimal.to_json, "solution"), (csv_path, optimal.to_csv, "signal table")):
        if target is not None:
            Path(target).parent.mkdir(parents=True, exist_ok=True)
            Path(target).write_text(text())
            lines.append(f"{what} written to {target}")
    if plot is not None:
        plot_comparison(comparison, plant, plot)
        lines.append(f"plot written to {plot}")
    return "\n".join(lines)
