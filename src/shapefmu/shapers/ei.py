"""Extra-insensitive (EI) shapers with one, two and three humps, exact for damping in [0, 0.3].

(Within the measured domain at the end of this docstring: for larger vtol the multi-hump designs
stop short of zeta = 0.3.)

Definition (Singhose, Seering & Singer; the vector-diagram formulation). An N-hump EI shaper has
N + 2 impulses. Its percent residual vibration V(nu) against the frequency ratio
nu = omega_actual / omega (same damping ratio) has, around nu = 1, an alternating sequence of
N + 1 zeros and N humps:

    zero, hump, zero, ..., hump, zero,     every hump a local maximum of height exactly vtol,

and V <= vtol between the outermost zeros. The design frequency sits on the middle element: the
middle hump for odd N (EI, three-hump EI: V(1) = vtol, the shaper tolerates vtol at the model
frequency to widen the band) and the middle zero for even N (two-hump EI: V(1) = 0).

Equations, with dimensionless times tau = omega t and
R(nu) = sum_k A_k exp(nu e_k), e_k = (zeta + j sqrt(1 - zeta^2)) tau_k - zeta tau_last, V = |R| / sum A:

    sum_k A_k = 1                                                   1
    |R(nu_h)|^2 = vtol^2,  d|R|^2/dnu (nu_h) = 0    for each hump   2N
    Re R(nu_z) = Im R(nu_z) = 0                      for each zero   2(N + 1)

Unknowns: N + 2 amplitudes, N + 1 times (tau_1 = 0), and the N + (N + 1) hump and zero
frequencies less the one pinned at nu = 1: 4N + 3 equations F(x, zeta) = 0 in 4N + 3 unknowns x.
The frequencies are carried as ln nu, so that an outermost zero running off to large nu costs few
continuation steps.

Continuation. At zeta = 0 the solution is known in closed form (times k pi, amplitudes in
``_undamped``). From there the solution curve y(s) = (x, zeta)(s) of F = 0 is followed by
pseudo-arclength continuation (Keller): a step of length h along the unit tangent t (the null
vector of [dF/dx, dF/dzeta], oriented to continue the previous one) predicts y + h t; Newton's
method (analytic Jacobian) corrects it on the hyperplane t . (y - y_pred) = 0. A step is accepted
when Newton closes every residual to 1e-10 within 8 iterations, lands within h/2 of the prediction
and turns the tangent by less than ~26 degrees; otherwise h is halved. Because arclength, not zeta,
is the parameter, the curve is followed through folds where zeta turns back (dF/dx singular), which
zeta-stepping cannot pass.

Which solution is returned. Some branches are S-shaped in zeta: three-hump vtol = 0.05 turns back
at zeta ~ 0.2756 and forward again at ~ 0.2751, so three designs exist for zeta between those.
Returned is the FIRST crossing of the requested zeta along the branch from zeta = 0: the continuous
deformation of the undamped design for every zeta below the first fold, and, beyond it, the first
solution the branch reaches. It is the one choice that needs no search beyond the first crossing
(the branch is traced only until it reaches zeta) and that depends only on the branch, not on step
sizes: a step whose end points lie below zeta across a fold is halved while the cubic Hermite
interpolant of zeta(s) through both ends says the fold may reach zeta, so a crossing just below a
fold is not stepped over. The shortest-duration solution, the alternative, would need the whole
branch traced to its end for every design, and jumps between branches all the same. Consequence: at the first fold the returned design jumps (for three-hump
vtol 0.05, the outermost zero moves from nu = 3.12 at zeta = 0.2756 to 3.57 at 0.27565).
Where the first crossing is found it is solved at the exact zeta (Newton with zeta fixed, to
rounding level). The runtime port ``shapefmu.runtime.ei`` runs the same algorithm in the standard
library and returns the same impulses (``tests/test_runtime_ei.py``).

Where the branch ends. For larger vtol the multi-hump branches end at a finite zeta: the outermost
zero runs off to infinite frequency while the last two impulses merge into a doublet (their spacing
is about pi / nu). The branch is followed while every hump and zero stays below nu = 50 (the last
two impulses then ~ T/100 apart); a zeta beyond that point is refused. A design is also refused
when, at the requested zeta, it is not an EI shape: an amplitude <= 0, or a residual-vibration peak
above vtol (1 + 1e-6) between the outermost zeros (for large vtol a further hump rises through vtol
before the branch ends). The ValueError then says which, how far the branch reached, and the domain
below.

Measured domain (``_DOMAIN``): zeta on a 0.005 grid for 23 values of vtol from 1e-4 to 0.25, the
thresholds by bisection in vtol at zeta = 0.3, the ends as the refusals report them; 300 random
designs inside it (half in the three-hump fold region) met every constraint to 7e-16:
    kind   every zeta in [0, 0.3] for   beyond: the branch ends at zeta =
    ei     every vtol in [1e-4, 0.25]   -
    ei2    vtol <= 0.1396               0.2994 (vtol 0.14), 0.2782 (0.16), 0.2594 (0.18),
                                        0.2424 (0.2), 0.2270 (0.22), 0.2062 (0.25)
    ei3    vtol <= 0.0596               0.2993 (vtol 0.06), 0.2830 (0.07), 0.2687 (0.08),
                                        0.2558 (0.09), 0.2441 (0.1), 0.2236 (0.12), 0.2060 (0.14),
                                        0.1906 (0.16), 0.1769 (0.18), 0.1647 (0.2), 0.1536 (0.22),
                                        0.1228 (0.25)

and for three-hump vtol >= ~0.17 a narrow zeta band below that end has no EI shape, because a
fourth peak rises through vtol between the outermost humps: zeta 0.1495-0.150 at vtol 0.18,
0.139-0.1405 at 0.2, 0.1295-0.1325 at 0.22, 0.1165-0.1225 at 0.25 (measured on a 0.0005 grid).
The runtime port refuses exactly the same designs with the same messages.

vtol below 1e-4 is refused: as vtol -> 0 every hump merges with its neighbouring zeros (the
undamped zeros sit about 2 sqrt(vtol) / pi from the hump), the constraint Jacobian turns singular
and the continuation needs steps of that size (one-hump EI at vtol 1e-6 takes ~450 steps, 2 s in
the runtime); an EI shaper of vtol < 0.01 % is in effect its zero-vibration parent (ZVD, ...).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from shapefmu.runtime.checks import check_omega, check_vtol, check_zeta
from shapefmu.shapers.impulse import ImpulseShaper

ZETA_MAX = 0.3
VTOL_MIN = 1e-4
VTOL_MAX = 0.25
# The branch is followed while every hump and zero frequency ratio stays below this.
NU_MAX = 50.0
_STEP_FIRST = 0.05
_STEP_MAX = 1.0
_STEP_MIN = 1e-7
_STEPS_MAX = 2000
_CORRECTOR_TOL = 1e-10
_CORRECTOR_ITERATIONS = 8
_RESIDUAL_TOL = 1e-12
_NEWTON_ITERATIONS = 40
_MIN_ALIGNMENT = 0.9
_HUMP_RTOL = 1e-6
_SHAPE_GRID = 0.02
# What the domain scan measured (module docstring); every refusal message ends with its kind's line.
_DOMAIN = {
    1: (
        "measured domain of the one-hump EI: every zeta in [0, 0.3] for every vtol in [1e-4, 0.25]"
    ),
    2: (
        "measured domain of the two-hump EI: every zeta in [0, 0.3] for vtol <= 0.1396; for "
        "larger vtol the branch ends earlier (zeta 0.2782 at vtol 0.16, 0.2424 at 0.2, 0.2062 "
        "at 0.25)"
    ),
    3: (
        "measured domain of the three-hump EI: every zeta in [0, 0.3] for vtol <= 0.0596; for "
        "larger vtol the branch ends earlier (zeta 0.2687 at vtol 0.08, 0.2441 at 0.1, 0.2060 "
        "at 0.14, 0.1647 at 0.2, 0.1228 at 0.25), and for vtol >= 0.17 a narrow zeta band "
        "below that end has no EI shape (0.1495-0.150 at vtol 0.18, 0.139-0.1405 at 0.2, "
        "0.1165-0.1225 at 0.25)"
    ),
}


def ei(omega: float, zeta: float = 0.0, vtol: float = 0.05) -> ImpulseShaper:
    """Extra-insensitive shaper: 3 impulses over one damped period, V(omega) = vtol.

    Undamped it is (1+V)/4, (1-V)/2, (1+V)/4 at 0, T/2, T; with damping the constraints in the
    module docstring are solved exactly. I(5 %) = 0.399 at zeta = 0 (ZVD: 0.287).
    """
    return _design(1, omega, zeta, vtol)


def ei2(omega: float, zeta: float = 0.0, vtol: float = 0.05) -> ImpulseShaper:
    """Two-hump EI: 4 impulses over 1.5 periods, zero at omega, humps of vtol either side."""
    return _design(2, omega, zeta, vtol)


def ei3(omega: float, zeta: float = 0.0, vtol: float = 0.05) -> ImpulseShaper:
    """Three-hump EI: 5 impulses over 2 periods, humps of vtol at omega and either side."""
    return _design(3, omega, zeta, vtol)


def _design(humps: int, omega, zeta, vtol) -> ImpulseShaper:
    omega = check_omega(omega)
    zeta = check_zeta(zeta)
    if zeta > ZETA_MAX:
        raise ValueError(f"zeta must be in [0, {ZETA_MAX}] for EI shapers, got {zeta!r}")
    vtol = check_vtol(vtol)
    if not VTOL_MIN <= vtol <= VTOL_MAX:
        raise ValueError(f"vtol must be in [{VTOL_MIN:g}, {VTOL_MAX:g}] for EI shapers, got {vtol!r}")
    tau, amplitudes = _dimensionless(humps, zeta, vtol)
    return ImpulseShaper(tuple(t / omega for t in tau), amplitudes)


def _undamped(humps: int, vtol: float):
    """Exact zeta = 0 solutions: times k*pi (half periods) and symmetric amplitudes."""
    v = vtol
    if humps == 1:
        a = [(1 + v) / 4, (1 - v) / 2, (1 + v) / 4]
    elif humps == 2:
        x = (v * v * (math.sqrt(1 - v * v) + 1)) ** (1 / 3)
        a1 = (3 * x * x + 2 * x + 3 * v * v) / (16 * x)
        a = [a1, 0.5 - a1, 0.5 - a1, a1]
    else:
        a1 = (1 + 3 * v + 2 * math.sqrt(2 * v * (v + 1))) / 16
        a2 = (1 - v) / 4
        a = [a1, a2, 1 - 2 * (a1 + a2), a2, a1]
    return np.arange(humps + 2) * math.pi, np.array(a)


def _response(nu, tau, amplitudes, zeta):
    """R(nu) and dR/dnu for the dimensionless impulse sequence (see module docstring)."""
    exponent = (zeta + 1j * math.sqrt(1 - zeta * zeta)) * tau - zeta * tau[-1]
    # Newton may probe huge nu near the end of a branch: let it see inf and shorten its step.
    with np.errstate(over="ignore", invalid="ignore"):
        terms = amplitudes * np.exp(np.multiply.outer(nu, exponent))
    return terms.sum(axis=-1), (terms * exponent).sum(axis=-1)


def _extrema(tau, amplitudes, zeta):
    """Zeros (local minima) and humps (local maxima) of V on (0.05, 2.5), from a fine grid."""
    nu = np.linspace(0.05, 2.5, 24501)
    v = np.abs(_response(nu, tau, amplitudes, zeta)[0])
    interior = slice(1, -1)
    minima = nu[interior][(v[1:-1] < v[:-2]) & (v[1:-1] <= v[2:])]
    maxima = nu[interior][(v[1:-1] > v[:-2]) & (v[1:-1] >= v[2:])]
    return minima, maxima


def _nearest(values, count, pinned=None):
    """The ``count`` values nearest to nu = 1, sorted, dropping the one pinned at 1."""
    chosen = np.sort(values[np.argsort(np.abs(values - 1.0))[:count]])
    if pinned:
        chosen = np.delete(chosen, np.argmin(np.abs(chosen - 1.0)))
    return chosen


class _Layout:
    """Where each unknown sits in y = (amplitudes, tau_2.., ln of the free hump and zero nu, zeta)."""

    def __init__(self, humps: int):
        self.humps = humps
        self.n = humps + 2  # impulses
        self.odd = humps % 2 == 1
        self.size = 4 * humps + 3  # unknowns x; y has one more, zeta
        free_humps = humps - 1 if self.odd else humps
        self.hump_columns = np.arange(2 * self.n - 1, 2 * self.n - 1 + free_humps)
        self.zero_columns = np.arange(2 * self.n - 1 + free_humps, self.size)
        self.frequencies = slice(2 * self.n - 1, self.size)


def _frequency_rows(nu, columns, y, layout):
    """R, dR/dnu and their gradients with respect to y (complex, one row per frequency)."""
    n, size = layout.n, layout.size
    amplitudes, zeta = y[:n], y[size]
    tau = np.concatenate([[0.0], y[n : 2 * n - 1]])
    damped = math.sqrt(1.0 - zeta * zeta)
    s = complex(zeta, damped)
    exponents = s * tau - zeta * tau[-1]
    d_exponents = complex(1.0, -zeta / damped) * tau - tau[-1]  # d e_k / d zeta
    with np.errstate(over="ignore", invalid="ignore"):
        phasors = np.exp(np.multiply.outer(nu, exponents))
        terms = amplitudes * phasors
        r = terms.sum(axis=1)
        r1 = (terms * exponents).sum(axis=1)
        r2 = (terms * exponents * exponents).sum(axis=1)
        g_r = np.zeros((nu.size, size + 1), complex)
        g_r1 = np.zeros((nu.size, size + 1), complex)
        g_r[:, :n] = phasors
        g_r1[:, :n] = phasors * exponents
        # tau_k moves e_k by s; the last time also moves every exponent by -zeta (the decay reference).
        g_r[:, n : 2 * n - 1] = nu[:, None] * s * terms[:, 1:]
        g_r1[:, n : 2 * n - 1] = s * terms[:, 1:] * (1.0 + nu[:, None] * exponents[1:])
        g_r[:, 2 * n - 2] -= nu * zeta * r
        g_r1[:, 2 * n - 2] -= zeta * (r + nu * r1)
        free = columns >= 0  # the pinned frequency nu = 1 is no unknown
        g_r[free, columns[free]] = r1[free]
        g_r1[free, columns[free]] = r2[free]
        g_r[:, size] = nu * (terms * d_exponents).sum(axis=1)
        g_r1[:, size] = (terms * d_exponents * (1.0 + nu[:, None] * exponents)).sum(axis=1)
    return r, r1, g_r, g_r1


def _system(y, layout, vtol):
    """Residuals F(y) (order: gain, hump levels, hump slopes, zero real, zero imaginary) and dF/dy."""
    n, size = layout.n, layout.size
    hump_nu, hump_columns = np.exp(y[layout.hump_columns]), layout.hump_columns
    zero_nu, zero_columns = np.exp(y[layout.zero_columns]), layout.zero_columns
    if layout.odd:
        hump_nu, hump_columns = np.append(hump_nu, 1.0), np.append(hump_columns, -1)
    else:
        zero_nu, zero_columns = np.append(zero_nu, 1.0), np.append(zero_columns, -1)
    hump_order, zero_order = np.argsort(hump_nu), np.argsort(zero_nu)
    r, r1, g_r, g_r1 = _frequency_rows(hump_nu[hump_order], hump_columns[hump_order], y, layout)
    z, _, g_z, _ = _frequency_rows(zero_nu[zero_order], zero_columns[zero_order], y, layout)
    with np.errstate(over="ignore", invalid="ignore"):
        residuals = np.concatenate(
            [[y[:n].sum() - 1.0], np.abs(r) ** 2 - vtol * vtol, 2.0 * np.real(np.conj(r) * r1), z.real, z.imag]
        )
        gain_row = np.zeros(size + 1)
        gain_row[:n] = 1.0
        jacobian = np.vstack(
            [
                gain_row,
                2.0 * np.real(np.conj(r)[:, None] * g_r),
                2.0 * np.real(np.conj(g_r) * r1[:, None] + np.conj(r)[:, None] * g_r1),
                g_z.real,
                g_z.imag,
            ]
        )
    # The unknowns are ln nu: d/d(ln nu) = nu d/dnu.
    jacobian[:, layout.frequencies] *= np.exp(y[layout.frequencies])
    return residuals, jacobian


def _evaluate(y, layout, vtol, border, level):
    """Residuals of F(y) = 0 bordered by border . y = level, their Jacobian, the squared norm."""
    if not abs(y[layout.size]) < 1.0:
        return None
    residuals, jacobian = _system(y, layout, vtol)
    with np.errstate(over="ignore", invalid="ignore"):
        residuals = np.append(residuals, border @ y - level)
        norm = float(residuals @ residuals)
    if not math.isfinite(norm) or not np.all(np.isfinite(jacobian)):
        return None
    return residuals, np.vstack([jacobian, border]), norm


def _newton(y, layout, vtol, border, level, tol, iterations, polish):
    """Damped Newton on the bordered system; (solution, iterations) or (None, iterations).

    Each step is halved (up to 10 times) until the sum of squared residuals falls. With ``polish``
    it keeps stepping past ``tol`` while the residual still falls fast: the last digits are what
    make the two implementations of these equations agree.
    """
    current = _evaluate(y, layout, vtol, border, level)
    if current is None:
        return None, 0
    for iteration in range(iterations):
        residuals, rows, norm = current
        if float(np.max(np.abs(residuals))) <= tol and not polish:
            return y, iteration
        try:
            step = np.linalg.solve(rows, residuals)
        except np.linalg.LinAlgError:
            break
        for halving in range(11):
            trial = y - 0.5**halving * step
            evaluated = _evaluate(trial, layout, vtol, border, level)
            if evaluated is not None and evaluated[2] < norm:
                break
        else:
            break  # no decrease along the Newton direction: at rounding level, or stuck
        y, current = trial, evaluated
        if polish and float(np.max(np.abs(current[0]))) <= tol and current[2] > 0.25 * norm:
            break
    if float(np.max(np.abs(current[0]))) <= tol:
        return y, iterations
    return None, iterations


def _tangent(y, layout, vtol, previous):
    """Unit null vector of dF/dy, oriented so that previous . t > 0."""
    _, jacobian = _system(y, layout, vtol)
    rhs = np.zeros(layout.size + 1)
    rhs[-1] = 1.0
    try:
        t = np.linalg.solve(np.vstack([jacobian, previous]), rhs)
    except np.linalg.LinAlgError:
        return None
    return t / np.linalg.norm(t)


def _hermite_peak(z_a, z_b, slope_a, slope_b):
    """Largest value on [0, 1] of the cubic with these end values and end slopes (per unit u)."""
    # p'(u) = c2 u^2 + c1 u + c0 for the cubic Hermite interpolant.
    c2 = 6.0 * (z_a - z_b) + 3.0 * (slope_a + slope_b)
    c1 = -6.0 * (z_a - z_b) - 4.0 * slope_a - 2.0 * slope_b
    c0 = slope_a
    if abs(c2) > 1e-300:
        disc = c1 * c1 - 4.0 * c2 * c0
        roots = [] if disc < 0 else [(-c1 + sign * math.sqrt(disc)) / (2.0 * c2) for sign in (1.0, -1.0)]
    else:
        roots = [-c0 / c1] if c1 != 0.0 else []
    peak = max(z_a, z_b)
    for u in roots:
        if 0.0 < u < 1.0:
            h00, h10 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u
            h01, h11 = -2 * u**3 + 3 * u**2, u**3 - u**2
            peak = max(peak, h00 * z_a + h10 * slope_a + h01 * z_b + h11 * slope_b)
    return peak


class _BranchEnd(Exception):
    """The branch from zeta = 0 cannot be followed to the requested zeta."""

    def __init__(self, reach, reason):
        super().__init__(reason)
        self.reach, self.reason = reach, reason


def _start(layout, vtol):
    """The undamped solution, its extrema polished by Newton at zeta = 0."""
    humps = layout.humps
    tau, amplitudes = _undamped(humps, vtol)
    minima, maxima = _extrema(tau, amplitudes, 0.0)
    y = np.concatenate(
        [
            amplitudes,
            tau[1:],
            np.log(_nearest(maxima, humps, pinned=layout.odd)),
            np.log(_nearest(minima, humps + 1, pinned=not layout.odd)),
            [0.0],
        ]
    )
    fix_zeta = np.zeros(layout.size + 1)
    fix_zeta[-1] = 1.0
    polished, _ = _newton(y, layout, vtol, fix_zeta, 0.0, _RESIDUAL_TOL, _NEWTON_ITERATIONS, True)
    return polished


def _follow(layout, zeta, vtol):
    """y = (x, zeta) at the first crossing of ``zeta`` along the branch from zeta = 0, or _BranchEnd."""
    size = layout.size
    y = _start(layout, vtol)
    if y is None:
        raise _BranchEnd(0.0, "turns singular")
    fix_zeta = np.zeros(size + 1)
    fix_zeta[-1] = 1.0
    if zeta == 0.0:
        return y
    t = _tangent(y, layout, vtol, fix_zeta)
    if t is None:
        raise _BranchEnd(0.0, "turns singular")
    h, reach = _STEP_FIRST, 0.0
    for _ in range(_STEPS_MAX):
        predicted = y + h * t
        new, iterations = _newton(
            predicted, layout, vtol, t, float(t @ predicted), _CORRECTOR_TOL, _CORRECTOR_ITERATIONS, False
        )
        t_new = None
        if new is not None and np.linalg.norm(new - predicted) <= 0.5 * h:
            t_new = _tangent(new, layout, vtol, t)
        if t_new is None or float(t_new @ t) < _MIN_ALIGNMENT:
            h /= 2
            if h < _STEP_MIN:
                raise _BranchEnd(reach, "turns singular")
            continue
        z_a, z_b = y[size], new[size]
        if z_b >= zeta:
            start = y + (zeta - z_a) / (z_b - z_a) * (new - y)
            start[size] = zeta
            solution, _ = _newton(start, layout, vtol, fix_zeta, zeta, _RESIDUAL_TOL, _NEWTON_ITERATIONS, True)
            if solution is not None:
                return solution
            h /= 2
            if h < _STEP_MIN:
                raise _BranchEnd(reach, "turns singular")
            continue
        chord = float(np.linalg.norm(new - y))
        if t[size] > 0.0 >= t_new[size] and h / 2 >= _STEP_MIN:
            # A fold between the two points: it may rise above zeta although both ends lie below.
            if _hermite_peak(z_a, z_b, t[size] * chord, t_new[size] * chord) >= zeta:
                h /= 2
                continue
        if float(np.max(new[layout.frequencies])) > math.log(NU_MAX):
            raise _BranchEnd(max(reach, _zeta_at_nu_max(y, new, layout, vtol)), "nu_max")
        if z_b < 0.0:
            raise _BranchEnd(reach, "returns to zeta = 0")
        y, t, reach = new, t_new, max(reach, z_b)
        h = min(2.0 * h if iterations <= 2 else 1.2 * h if iterations <= 4 else h, _STEP_MAX)
    raise _BranchEnd(reach, "turns singular")


def _zeta_at_nu_max(y, new, layout, vtol):
    """zeta where the outermost frequency reaches NU_MAX, between the branch points y and new."""
    column = layout.frequencies.start + int(np.argmax(new[layout.frequencies]))
    level = math.log(NU_MAX)
    start = y + (level - y[column]) / (new[column] - y[column]) * (new - y)
    border = np.zeros(layout.size + 1)
    border[column] = 1.0
    solution, _ = _newton(start, layout, vtol, border, level, _RESIDUAL_TOL, _NEWTON_ITERATIONS, True)
    return float(start[layout.size] if solution is None else solution[layout.size])


def _peak_between_zeros(tau, amplitudes, zeta, low, high):
    """(largest V, where) between nu = low and high: grid of step ~0.02, local maxima refined."""
    count = max(3, int(math.ceil((high - low) / _SHAPE_GRID)) + 1)
    spacing = (high - low) / (count - 1)
    nu = low + np.arange(count) * spacing
    v = np.abs(_response(nu, tau, amplitudes, zeta)[0])
    best, where = float(v.max()), float(nu[int(np.argmax(v))])
    for i in np.nonzero((v[1:-1] >= v[:-2]) & (v[1:-1] > v[2:]))[0] + 1:
        # Golden-section search for the maximum inside the bracketing grid cells.
        a, b = float(nu[i - 1]), float(nu[i + 1])
        ratio = (math.sqrt(5.0) - 1.0) / 2.0
        for _ in range(60):
            c, d = b - ratio * (b - a), a + ratio * (b - a)
            vc, vd = abs(_response(c, tau, amplitudes, zeta)[0]), abs(_response(d, tau, amplitudes, zeta)[0])
            if vc > vd:
                b = d
            else:
                a = c
        peak = float(abs(_response((a + b) / 2, tau, amplitudes, zeta)[0]))
        if peak > best:
            best, where = peak, (a + b) / 2
    return best, where


def _refusal(humps, zeta, vtol, what):
    asked = f"the {humps}-hump EI shaper with vtol = {vtol:g} cannot be designed for zeta = {zeta:g}"
    return ValueError(f"{asked}: {what}; {_DOMAIN[humps]}")


@functools.lru_cache(maxsize=256)
def _dimensionless(humps: int, zeta: float, vtol: float):
    layout = _Layout(humps)
    try:
        y = _follow(layout, zeta, vtol)
    except _BranchEnd as end:
        if end.reason == "nu_max":
            what = (
                f"its branch from the undamped design ends at zeta = {end.reach:.4f}, where its outermost "
                f"zero passes {NU_MAX:g} times the design frequency (the last two impulses merge)"
            )
        else:
            what = f"its branch from the undamped design {end.reason} after reaching zeta = {end.reach:.3f}"
        raise _refusal(humps, zeta, vtol, what) from None
    n = layout.n
    tau = np.concatenate([[0.0], y[n : 2 * n - 1]])
    amplitudes = y[:n]
    if np.any(np.diff(tau) <= 0) or np.any(amplitudes <= 0):
        raise _refusal(humps, zeta, vtol, "the solution has an amplitude <= 0 or times out of order")
    zeros = np.exp(y[layout.zero_columns])
    low, high = min(float(zeros.min()), 1.0), max(float(zeros.max()), 1.0)
    peak, where = _peak_between_zeros(tau, amplitudes, zeta, low, high)
    if peak > vtol * (1.0 + _HUMP_RTOL):
        what = f"the solution is no EI shape, its residual vibration rises to {peak:.4g} > vtol at nu = {where:.3f}"
        raise _refusal(humps, zeta, vtol, what)
    return tuple(float(t) for t in tau), tuple(float(a) for a in amplitudes)
