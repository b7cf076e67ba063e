"""The true minimum time of a jerk-limited move with residual-vibration bounds (``jerk_limited_optimum``),
bracketed between a feasible move and a certified lower bound, to judge the planner of
``shapefmu.motion`` on the same problem.

The problem (one axis; several axes to rest end together at the largest of their minima, since an
axis that has arrived can wait at rest while its mode only decays): the jerk j(t), |j| <= J,
drives (p, v, a) from (p0, v0, a0) to rest at pf in the time T, with v and a within their limits
and, for every mode of the axis and every frequency of its band, the residual amplitude
|S(omega)| / (omega^2 omega_d) at most the bound, where S(omega) = integral j(t) s e^{s (T - t)} dt
is the sum of the jerk steps of ``runtime.jerk_vibration`` written as an integral (s = -zeta omega
+ i omega_d).

Upper bound. On a grid of N equal intervals with constant jerk, every constraint is linear in the N
jerks: a, v at the grid points, the end state, and |S| <= b through a regular polygon of M sides
inscribed in the circle (Re(S e^{-i theta_m}) <= b cos(pi / M), so the polygon's feasible S lie in
the circle). A linear program (HiGHS) finds the least peak jerk that meets them; bisection on T
finds the shortest T at which that peak is at most J: a move that meets every bound (between grid
points v can pass its limit by at most J h^2 / 2, which the result reports).

Lower bound (the certificate). For any jerk j(t), not only a grid one: if y are multipliers of the
equalities (end state) and z >= 0 of the inequalities (a, v at the grid points, the circumscribed
polygon Re(S e^{-i theta_m}) <= b, a relaxation of |S| <= b), every feasible j satisfies
integral psi(t) j(t) dt <= y.e + z.g with psi = sum y_i c_i + sum z_i c_i (c_i the kernels: 1,
t_m - t, (t_m - t)^2 / 2 before t_m, and Re(e^{-i theta} s e^{s (T - t)})); since the left side is
at least -J integral |psi|, no move of that T exists when -(y.e + z.g) / integral |psi| > J (weak
duality). The multipliers are the grid LP's duals at the lower T, and integral |psi| is integrated
on 32 points per interval.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog

from shapefmu.runtime.checks import check_positive


@dataclass(frozen=True)
class AxisOptimum:
    """The bracket of one axis: ``upper`` (a grid move meets every bound), ``lower`` (no move of
    that duration exists: its ``violation_at_lower`` bound is > 0; 0 when none was certified),
    the grid's jerk at ``upper``, and the most v can pass its limit between grid points (J h^2 / 2).

    Examples
    --------
    A bracket is certified when the violation bound at its lower end is positive:

    >>> axis = AxisOptimum(upper=0.0928, lower=0.0836, jerk=(2000.0, -2000.0), n_intervals=2,
    ...                    violation_at_lower=0.4, j_max=2000.0, velocity_slack=1e-3)
    >>> axis.certified
    True
    """

    upper: float
    lower: float
    jerk: tuple[float, ...]
    n_intervals: int
    violation_at_lower: float
    j_max: float
    velocity_slack: float

    @property
    def certified(self) -> bool:
        return self.violation_at_lower > 0.0


@dataclass(frozen=True)
class JerkOptimum:
    """The multi-axis optimum: T between ``lower`` and ``upper`` (the largest of the axes').

    Examples
    --------
    The axes end together, so the slowest axis bounds the move from both sides:

    >>> fast = AxisOptimum(0.5, 0.4, (1.0,), 1, 0.1, 1.0, 0.0)
    >>> slow = AxisOptimum(0.9, 0.8, (1.0,), 1, 0.0, 1.0, 0.0)
    >>> optimum = JerkOptimum((fast, slow))
    >>> optimum.lower, optimum.upper, optimum.certified
    (0.8, 0.9, False)
    """

    axes: tuple[AxisOptimum, ...]

    @property
    def upper(self) -> float:
        return max(a.upper for a in self.axes)

    @property
    def lower(self) -> float:
        return max(a.lower for a in self.axes)

    @property
    def certified(self) -> bool:
        return all(a.certified for a in self.axes)


def _constraints(T, N, state, target_p, limits, residuals, sides, inscribed):
    """The grid problem's rows over the N interval jerks, each scaled to be dimensionless:
    (G, g, kernels of G, E, e, kernels of E); a kernel is how its row reads for any j(t)."""
    v_max, a_max, v_min, a_min = limits
    p0, v0, a0 = state
    h = T / N
    edges = np.arange(N + 1) * h
    lo, hi = edges[:-1], edges[1:]
    G, g, k_G, E, e, k_E = [], [], [], [], [], []
    p_scale = max(abs(target_p - p0), v_max * T)
    for m in range(1, N + 1):
        tm = edges[m]
        inside = (np.arange(N) < m).astype(float)
        for order, free in ((0, a0), (1, v0 + a0 * tm), (2, p0 + v0 * tm + a0 * tm * tm / 2)):
            # integral over interval k < m of (tm - t)^order / order! dt
            row = ((tm - lo) ** (order + 1) - (tm - hi) ** (order + 1)) / math.factorial(order + 1) * inside
            kernel = ("poly", order, tm)
            if m == N:  # the end: at rest at the target
                scale = (a_max, v_max, p_scale)[order]
                E.append(row / scale)
                e.append(((0.0, 0.0, target_p)[order] - free) / scale)
                k_E.append((kernel, 1.0 / scale))
            elif order < 2:
                high, low = (a_max, a_min) if order == 0 else (v_max, v_min)
                scale = max(high, -low)
                G += [row / scale, -row / scale]
                g += [(high - free) / scale, (free - low) / scale]
                k_G += [(kernel, 1.0 / scale), (kernel, -1.0 / scale)]
    factor = math.cos(math.pi / sides) if inscribed else 1.0
    for omega, zeta, bound in residuals:
        s = complex(-zeta * omega, omega * math.sqrt(1 - zeta * zeta))
        # integral over interval k of s e^{s (T - t)} dt
        column = np.exp(s * (T - lo)) - np.exp(s * (T - hi))
        b_S = bound * omega * omega * omega * math.sqrt(1 - zeta * zeta)
        for m in range(sides):
            rotation = np.exp(-2j * math.pi * m / sides)
            G.append((column * rotation).real / b_S)
            g.append(factor)
            k_G.append((("exp", s, rotation, T), 1.0 / b_S))
    return np.array(G), np.array(g), k_G, np.array(E), np.array(e), k_E, edges


def _least_peak(T, N, state, target_p, limits, residuals, sides):
    """(least peak jerk, grid jerks) of the grid problem with the inscribed polygons (inf, None
    when no grid jerk meets the constraints)."""
    G, g, _, E, e, _, _ = _constraints(T, N, state, target_p, limits, residuals, sides, True)
    # Variables (j_1..j_N, s): minimise s with -s <= j_k <= s.
    peak = np.hstack([np.vstack([np.eye(N), -np.eye(N)]), -np.ones((2 * N, 1))])
    A_ub = np.vstack([np.hstack([G, np.zeros((len(G), 1))]), peak])
    b_ub = np.concatenate([g, np.zeros(2 * N)])
    cost = np.zeros(N + 1)
    cost[-1] = 1.0
    result = linprog(cost, A_ub=A_ub, b_ub=b_ub, A_eq=np.hstack([E, np.zeros((len(E), 1))]), b_eq=e,
                     bounds=[(None, None)] * N + [(0.0, None)], method="highs")
    if result.status != 0:
        return math.inf, None
    return float(result.x[-1]), result.x[:N]


def _violation_bound(T, N, state, target_p, limits, j_max, residuals, sides):
    """A lower bound, valid for every jerk j(t) with |j| <= J (not only grid ones), on the largest
    violation t of the relaxed constraints (circumscribed polygons): > 0 proves that no move
    lasts T. From the grid LP min t s.t. G j - t <= g, E j = e, |j_k| <= J, whose duals z >= 0
    (sum z <= 1) and y give t >= -(z.g + y.e) - J integral |psi| for any j (weak duality)."""
    G, g, k_G, E, e, k_E, edges = _constraints(T, N, state, target_p, limits, residuals, sides, False)
    A_ub = np.hstack([G, -np.ones((len(G), 1))])
    cost = np.zeros(N + 1)
    cost[-1] = 1.0
    result = linprog(cost, A_ub=A_ub, b_ub=g, A_eq=np.hstack([E, np.zeros((len(E), 1))]), b_eq=e,
                     bounds=[(-j_max, j_max)] * N + [(None, None)], method="highs")
    if result.status != 0:
        return -math.inf
    z = -np.asarray(result.ineqlin.marginals)
    y = -np.asarray(result.eqlin.marginals)
    fine = (edges[:-1, None] + (edges[1] - edges[0]) * (np.arange(32) + 0.5)[None, :] / 32).ravel()
    psi = np.zeros(fine.size)
    for multiplier, (kernel, scale) in list(zip(z, k_G)) + list(zip(y, k_E)):
        if multiplier == 0.0:
            continue
        if kernel[0] == "poly":
            _, order, tm = kernel
            psi += multiplier * scale * np.where(fine < tm, (tm - fine) ** order / math.factorial(order), 0.0)
        else:
            _, s, rotation, T_ = kernel
            psi += multiplier * scale * (rotation * s * np.exp(s * (T_ - fine))).real
    integral = float(np.sum(np.abs(psi)) * (edges[1] - edges[0]) / 32)
    return float(-(np.dot(z, g) + np.dot(y, e)) - j_max * integral)


def axis_optimum(state, target_p, limits, j_max, residuals, n_intervals=300, sides=16, rel_tol=1e-4,
                 start=None) -> AxisOptimum:
    """The ``AxisOptimum`` of one axis from ``state`` (p, v, a) to rest at ``target_p``.

    ``limits`` is (v_max, a_max, v_min, a_min); ``residuals`` [(omega, zeta, bound)] the amplitude
    bound at every frequency of every band. ``start`` a duration known to be feasible (the
    planner's), else one is found by doubling.

    Examples
    --------
    Issue 36's 40 Hz example on a coarse grid of 40 steps (10 mm at 0.3 m/s, 5 m/s^2, 2000 m/s^3; the
    mode may ring 7.833e-7 m, 1 % of the rigid move's 78.33 um): the planner's 92.82 ms lies inside.

    >>> import math
    >>> axis = axis_optimum((0.0, 0.0, 0.0), 0.01, (0.3, 5.0, -0.3, -5.0), 2000.0,
    ...                     [(2 * math.pi * 40.0, 0.05, 7.833e-7)], n_intervals=40)
    >>> axis.certified, round(1e3 * axis.lower, 1), round(1e3 * axis.upper, 1)
    (True, 83.6, 92.8)
    """
    j_max = check_positive(j_max, "j_max")
    N = int(n_intervals)

    def feasible(T):
        return _least_peak(T, N, state, target_p, limits, residuals, sides)[0] <= j_max

    high = start if start is not None else 0.1
    for _ in range(60):
        if feasible(high):
            break
        high *= 2.0
    else:
        raise ValueError("no feasible duration below 2^60 times the start: the target is out of reach")
    low = high / 2.0
    while feasible(low) and low > 1e-9:
        high, low = low, low / 2.0
    while high - low > rel_tol * high:
        middle = 0.5 * (low + high)
        if feasible(middle):
            high = middle
        else:
            low = middle
    _, jerk = _least_peak(high, N, state, target_p, limits, residuals, sides)
    # The certified lower end: the longest of these durations whose violation bound is > 0.
    lower, margin = 0.0, -math.inf
    for fraction in (1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.3):
        candidate = high * (1.0 - fraction)
        margin = _violation_bound(candidate, N, state, target_p, limits, j_max, residuals, sides)
        if margin > 0.0:
            lower = candidate
            break
    h = high / N
    return AxisOptimum(float(high), float(lower), tuple(map(float, jerk)), N, float(margin), j_max, 0.5 * j_max * h * h)


def jerk_limited_optimum(states, targets, limits, modes, n_intervals=300, sides=16, band_points=9) -> JerkOptimum:
    """The ``JerkOptimum`` of axes from ``states`` [(p, v, a)] to rest at ``targets`` [p].

    ``limits`` per axis (v_max, a_max, j_max, v_min, a_min); ``modes`` per axis
    [(omega, zeta, delta, bound)], bound the amplitude the mode may ring with after the move (the
    planner's vtol times the rigid move's, ``shapefmu.motion.Trajectory.residuals``).

    Examples
    --------
    The 40 Hz example of ``axis_optimum`` as one axis of a move:

    >>> import math
    >>> best = jerk_limited_optimum([(0.0, 0.0, 0.0)], [0.01], [(0.3, 5.0, 2000.0, -0.3, -5.0)],
    ...                             [[(2 * math.pi * 40.0, 0.05, 0.0, 7.833e-7)]], n_intervals=40)
    >>> best.certified, round(1e3 * best.lower, 1), round(1e3 * best.upper, 1)
    (True, 83.6, 92.8)
    """
    axes = []
    for state, target, (v_max, a_max, j_max, v_min, a_min), axis_modes in zip(states, targets, limits, modes):
        residuals = []
        for omega, zeta, delta, bound in axis_modes:
            count = 1 if delta == 0 else band_points
            for k in range(count):
                w = omega if count == 1 else omega * (1 - delta + 2 * delta * k / (count - 1))
                residuals.append((w, zeta, bound))
        axes.append(axis_optimum(state, target, (v_max, a_max, v_min, a_min), j_max, residuals, n_intervals, sides))
    return JerkOptimum(tuple(axes))
