"""The certificate that a bang-bang move is time-optimal, not only feasible (``check_optimality``):
Pontryagin's switching function and a shorter-time test."""

from __future__ import annotations

from dataclasses import dataclass

import mpmath
import numpy as np

from shapefmu.optimal.moves import rest_state, simulate
from shapefmu.optimal.refinement import _EXACT_DIGITS, _ExactPlant, _rest_state_exact
from shapefmu.optimal.solution import TimeOptimalSolution, _peak_scale
from shapefmu.optimal.transcription import _min_norm_grid_input
from shapefmu.plants import Plant, as_plant
from shapefmu.runtime.checks import check_positive


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

    Examples
    --------
    >>> OptimalityCheck((1.0, 0.0), 0.0, 0.01, 1e-4, 1.0002, 1.0001, 1.0, 200).time_optimal
    True
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

    Examples
    --------
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(1.0, u_max=1.0)  # x'' = u, |u| <= 1: T = 2 sqrt(X / (b U)) = 2 for X = 1
    >>> from shapefmu.optimal import time_optimal
    >>> check = check_optimality(plant, time_optimal(plant, 1.0))
    >>> check.time_optimal, check.sign_margin > 0.0
    (True, True)
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
