"""The transcriptions of a time-optimal move on a uniform grid of piecewise-constant inputs: the
least-peak linear program (``lp_transcription``) and the free-final-time CasADi + IPOPT program
(``transcribe``), and the bang-bang structure (levels, switch estimates) read from either."""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np
from scipy.optimize import linprog

from shapefmu.optimal.moves import _augmented_expm, _output_index, _single_input, _u_max, check_controllable, rest_state
from shapefmu.plants import as_plant
from shapefmu.runtime.checks import check_finite


# ---------------------------------------------------------------------------------------------
# Linear program on a uniform grid (exact discretisation, HiGHS)


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
    with np.errstate(divide="ignore", invalid="ignore"):
        b_eq = (U.T @ x_f) / S
    if not np.all(np.isfinite(b_eq)):  # T so short (or x_f so small) that Gamma underflows
        raise ValueError(f"the grid's reachability map is singular at T = {T:.3g} s")
    result = linprog(cost, A_ub=A_ub, b_ub=np.zeros(2 * N), A_eq=np.hstack([Vt, np.zeros((n, 1))]),
                     b_eq=b_eq, bounds=[(None, None)] * N + [(0.0, None)], method="highs")
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

    Examples
    --------
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(1.0, u_max=1.0)  # x'' = u, |u| <= 1: T = 2 sqrt(X / (b U)) = 2 for X = 1
    >>> grid = lp_transcription(plant, 1.0)  # 100 steps: the switch at 1 s falls on the grid
    >>> grid.T, grid.n_intervals
    (2.0, 100)
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
    try:
        return _bisect_move_time(A, B, x_f, u_max, N, rel_tol, distance, _output_index(plant, output))
    except ValueError as error:
        # A move far longer or shorter than the plant's modes is out of the LP's numerical reach:
        # name the two values that set the move, not only the solver's complaint.
        raise ValueError(f"no time-optimal move found for distance = {distance!r} with u_max = {u_max!r} on "
                         f"plant {plant.name!r} ({error}); a move that lasts many thousand or a tiny fraction "
                         f"of the plant's mode periods is out of the transcription's numerical range") from None


def _bisect_move_time(A, B, x_f, u_max, N, rel_tol, distance, output_index) -> Transcription:
    """The bisection on T of ``lp_transcription`` (its docstring)."""
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
    return Transcription(float(hi), np.clip(u, -u_max, u_max), N, solves, distance, u_max, output_index)


# ---------------------------------------------------------------------------------------------
# Direct transcription (CasADi + IPOPT)


@dataclass(frozen=True)
class Transcription:
    """Result of the direct transcription: move time and the grid input (N equal intervals) of the
    move of ``output`` by ``distance`` under |u| <= ``u_max``.

    Examples
    --------
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(1.0, u_max=1.0)  # x'' = u, |u| <= 1: T = 2 sqrt(X / (b U)) = 2 for X = 1
    >>> grid = transcribe(plant, 1.0, n_intervals=20)
    >>> round(grid.T, 6), grid.u.size
    (2.0, 20)
    """

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

    Examples
    --------
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(1.0, u_max=1.0)  # x'' = u, |u| <= 1: T = 2 sqrt(X / (b U)) = 2 for X = 1
    >>> round(transcribe(plant, 1.0, n_intervals=20).T, 6)
    2.0
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
