"""Time-optimal rest-to-rest moves of a linear plant under |u| <= u_max, and shaped moves beside them.

``time_optimal`` finds the bang-bang input in three steps:

1. a feasible start: the shortest time, to a factor of 2, at which a linear program on a coarse
   grid of piecewise-constant inputs reaches the target (exact discretisation, scipy's HiGHS);
2. the structure: a direct transcription with free final time (CasADi + IPOPT), in dimensionless
   time, input and states, whose grid input shows the sequence of bang levels and roughly where
   they switch;
3. exact switch times: Newton / Levenberg-Marquardt on the switch instants and T, with the final
   state computed exactly for piecewise-constant input from matrix exponentials of the augmented
   matrix [[A, B], [0, 0]], expm of which holds e^{A t} and its integral times B.

``compare_moves`` then sets the true optimum beside the rigid-body bang-bang of paper 002, eq. (2),
and the bang-bang convolved with impulse shapers (paper 002, eqs. 4 and 21), all simulated exactly.
"""

from __future__ import annotations

import io
import json
import math
import warnings
from dataclasses import dataclass

import casadi as ca
import numpy as np
from scipy.linalg import expm, matrix_balance
from scipy.optimize import least_squares, linprog

from shapefmu.plants.model import Plant, as_plant, rigid_part
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


def _feasible_grid_input(A, B, x_f, u_max, T, N):
    """A grid input with |u| <= u_max reaching x_f at T from rest (None if the LP is infeasible)."""
    _, _, Gamma = _grid_maps(A, B, T, N)
    # Rows scaled to unit size: the rigid-body and modal rows differ by orders of magnitude.
    row = np.maximum(np.abs(Gamma).max(axis=1), 1e-300)
    result = linprog(np.zeros(N), A_eq=Gamma / row[:, None], b_eq=x_f / row, bounds=[(-u_max, u_max)] * N,
                     method="highs")
    return result.x if result.status == 0 else None


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
    fit = least_squares(residual, p0, jac=jacobian, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15)
    p = fit.x * t0
    return list(p[:-1]), float(p[-1])


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
    (x_f, u_f) the rest state of ``rest_state``. The transcription (``transcribe``, ``n_intervals``
    steps) finds the bang-bang structure; ``refine`` makes the switch times exact.

    Raises ValueError for u_max <= 0, a plant that is not controllable from its input, or a
    target that has no rest state within the limit. Warns (RuntimeWarning) if the refined move
    misses the rest state by more than ``tolerance`` (relative to each state's peak).
    """
    plant = as_plant(plant)
    grid = transcribe(plant, distance, u_max, n_intervals, output)
    return refine_transcription(plant, grid, n_samples, tolerance)


def refine_transcription(plant, grid: Transcription, n_samples: int = 2001,
                         tolerance: float = 1e-9) -> TimeOptimalSolution:
    """The exact time-optimal move from the bang-bang structure of a transcription (``refine``)."""
    plant = as_plant(plant)
    distance, u_max, output = grid.distance, grid.u_max, grid.output
    x_f, u_f = rest_state(plant, distance, output)
    levels, switches = _structure(grid.u, grid.T, u_max)
    command = Command((0.0, *switches, grid.T), tuple(levels), u_f)
    _, states = simulate(plant, command, np.linspace(0.0, grid.T, 201))
    scale = _peak_scale(states, x_f, distance)
    switches, T = refine(plant, x_f, levels, switches, grid.T, scale)
    edges = np.concatenate([[0.0], switches, [T]])
    if np.any(np.diff(edges) < -1e-12 * T):
        raise ValueError(f"switch-time refinement of the move of {distance:g} on plant {plant.name!r} reordered the "
                         f"switches ({edges}); the transcription's structure is wrong: raise n_intervals")
    command = Command(tuple(map(float, edges)), tuple(levels), u_f)
    t = np.union1d(np.linspace(0.0, T, n_samples), edges)
    at_breaks, x = simulate(plant, command, t)
    error = at_breaks[-1] - x_f
    residual = float(np.max(np.abs(error) / _peak_scale(x, x_f, distance)))
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


def optimal_report(path, distance: float, u_max: float | None = None, plot=None) -> str:
    """The text of ``shapefmu optimal FILE --distance X [--u-max U] [--plot out.png]``."""
    plant = as_plant(path)
    comparison = compare_moves(plant, distance, u_max)
    optimal = comparison.optimal
    lines = [comparison.table(), "",
             f"time-optimal: T = {optimal.T:.12g} s, {len(optimal.switch_times)} switches at "
             + ", ".join(f"{s:.10g}" for s in optimal.switch_times),
             f"refined final-state residual {optimal.residual:.3e} (transcription T = {optimal.transcription_T:.10g} s)"]
    if plot is not None:
        plot_comparison(comparison, plant, plot)
        lines.append(f"plot written to {plot}")
    return "\n".join(lines)
