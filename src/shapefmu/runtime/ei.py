"""Extra-insensitive (EI) shapers with one, two and three humps, exact for damping in [0, 0.3].

Standard library only: what a Shaper FMU designs at initialisation for ``kind`` ei, ei2, ei3, and
what the design layer ``shapefmu.shapers.ei`` returns as an ``ImpulseShaper`` (it calls this
module), so the shaper analysed is the one the FMU runs. (Within the measured domain at the end of
this docstring: for larger vtol the multi-hump designs stop short of zeta = 0.3.)

API
---
``ei(omega, zeta=0.0, vtol=0.05)``, ``ei2(...)``, ``ei3(...)`` -> ``(times, amplitudes)``, two lists
of N + 2 floats for N = 1, 2, 3 humps: times in seconds (the first 0) and positive amplitudes
summing to 1. omega > 0 rad/s, zeta in [0, ZETA_MAX], vtol in [VTOL_MIN, VTOL_MAX].

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
continuation steps. The hump and zero locations are unknowns of the system, so no frequency scan is
needed to solve it: at zeta = 0 they are known in closed form (``_undamped_extrema``), and every
Newton step uses the analytic Jacobian (``_system``, including the column d/dzeta) in a Householder
QR solve (``least_squares.solve_least_squares``).

Continuation (``_follow``). At zeta = 0 the solution is known in closed form (times k pi,
amplitudes in ``_undamped_amplitudes``). From there the solution curve y(s) = (x, zeta)(s) of F = 0
is followed by pseudo-arclength continuation (Keller): a step of length h along the unit tangent t
(the null vector of [dF/dx, dF/dzeta], oriented to continue the previous one) predicts y + h t;
damped Newton (analytic Jacobian) corrects it on the hyperplane t . (y - y_pred) = 0. A step is
accepted when Newton closes every residual to 1e-10 within 8 iterations, lands within h/2 of the
prediction and turns the tangent by less than ~26 degrees; otherwise h is halved (h from 0.05, at
most 1, doubled after an easy step). Because arclength, not zeta, is the parameter, the curve is
followed through folds where zeta turns back (dF/dx singular), which zeta-stepping cannot pass.

Which solution is returned. Some branches are S-shaped in zeta: three-hump vtol = 0.05 turns back
at zeta ~ 0.2756 and forward again at ~ 0.2751, so three designs exist for zeta between those.
Returned is the FIRST crossing of the requested zeta along the branch from zeta = 0: the continuous
deformation of the undamped design for every zeta below the first fold, and, beyond it, the first
solution the branch reaches. It is the one choice that needs no search beyond the first crossing
(the branch is traced only until it reaches zeta) and that depends only on the branch, not on step
sizes: a step whose end points lie below zeta across a fold is halved while the cubic Hermite
interpolant of zeta(s) through both ends says the fold may reach zeta (``_hermite_peak``), so a
crossing just below a fold is not stepped over. The shortest-duration solution, the alternative,
would need the whole branch traced to its end for every design, and jumps between branches all the
same. Consequence: at the first fold the returned design jumps (for three-hump vtol 0.05, the
outermost zero moves from nu = 3.12 at zeta = 0.2756 to 3.57 at 0.27565). Where the first crossing
is found it is solved at the exact zeta (Newton with zeta fixed, to rounding level).

Where the branch ends. For larger vtol the multi-hump branches end at a finite zeta: the outermost
zero runs off to infinite frequency while the last two impulses merge into a doublet (their spacing
is about pi / nu). The branch is followed while every hump and zero stays below nu = NU_MAX = 50
(the last two impulses then ~ T/100 apart); a zeta beyond that point is refused, as it is when h
falls below 1e-7 or zeta returns below 0. A design is also refused when, at the requested zeta, it
is not an EI shape: an amplitude <= 0 or times out of order, or a residual-vibration peak above
vtol (1 + 1e-6) between the outermost zeros (``_peak_between_zeros``: a 0.02 grid in nu, every
local maximum refined by golden section; for large vtol a further hump rises through vtol before
the branch ends). The ValueError then says which, how far the branch reached, and the domain below.

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

vtol below 1e-4 is refused: as vtol -> 0 every hump merges with its neighbouring zeros (the
undamped zeros sit about 2 sqrt(vtol) / pi from the hump), the constraint Jacobian turns singular
and the continuation needs steps of that size (one-hump EI at vtol 1e-6 takes ~450 steps, 2 s in
the runtime); an EI shaper of vtol < 0.01 % is in effect its zero-vibration parent (ZVD, ...).
"""

import cmath
import functools
import math

from .checks import check_omega, check_vtol, check_zeta
from .least_squares import solve_least_squares

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


def ei(omega, zeta=0.0, vtol=0.05):
    """Extra-insensitive shaper: 3 impulses over one damped period, V(omega) = vtol.

    Undamped it is (1+V)/4, (1-V)/2, (1+V)/4 at 0, T/2, T.
    """
    return _design(1, omega, zeta, vtol)


def ei2(omega, zeta=0.0, vtol=0.05):
    """Two-hump EI: 4 impulses over 1.5 periods, zero at omega, humps of vtol either side."""
    return _design(2, omega, zeta, vtol)


def ei3(omega, zeta=0.0, vtol=0.05):
    """Three-hump EI: 5 impulses over 2 periods, humps of vtol at omega and either side."""
    return _design(3, omega, zeta, vtol)


def _design(humps, omega, zeta, vtol):
    omega = check_omega(omega)
    zeta = check_zeta(zeta)
    if zeta > ZETA_MAX:
        raise ValueError(f"zeta must be in [0, {ZETA_MAX}] for EI shapers, got {zeta!r}")
    vtol = check_vtol(vtol)
    if not VTOL_MIN <= vtol <= VTOL_MAX:
        raise ValueError(f"vtol must be in [{VTOL_MIN:g}, {VTOL_MAX:g}] for EI shapers, got {vtol!r}")
    tau, amplitudes = _dimensionless(humps, zeta, vtol)
    return [t / omega for t in tau], list(amplitudes)


def _undamped_amplitudes(humps, v):
    """Exact zeta = 0 amplitudes (times are k pi, half periods), symmetric about the middle."""
    if humps == 1:
        return [(1 + v) / 4, (1 - v) / 2, (1 + v) / 4]
    if humps == 2:
        x = (v * v * (math.sqrt(1 - v * v) + 1)) ** (1 / 3)
        a1 = (3 * x * x + 2 * x + 3 * v * v) / (16 * x)
        return [a1, 0.5 - a1, 0.5 - a1, a1]
    a1 = (1 + 3 * v + 2 * math.sqrt(2 * v * (v + 1))) / 16
    a2 = (1 - v) / 4
    return [a1, a2, 1 - 2 * (a1 + a2), a2, a1]


def _undamped_extrema(humps, a):
    """Free hump and zero frequencies of the undamped shaper, in closed form, nu = 1 left out.

    Undamped, R(nu) = exp(j nu pi (N + 1) / 2) P(nu) with P real, because the amplitudes are
    symmetric about the middle of the times k pi: P(nu) = sum_k A_k cos(nu pi (k - (N + 1)/2)).
    With c the cosine of the smallest of those angles, P is a polynomial in c, and its zeros and
    the zeros of dP/dc are where V has its zeros and humps (dc/dnu vanishes only at nu = 0, 2, or
    at nu = 1 for odd N, which is the pinned middle hump). Each c gives nu and 2 - nu.
    """

    def pair(angle, scale):  # nu = scale * angle / pi and its mirror 2 - nu
        nu = scale * angle / math.pi
        return [nu, 2.0 - nu]

    if humps == 1:
        # P = 2 A_1 cos(pi nu) + A_2, with c = cos(pi nu).
        return [], pair(math.acos(-a[1] / (2 * a[0])), 1.0)
    if humps == 2:
        # P = 2 a1 cos(3x) + 2 a2 cos(x), x = pi nu / 2: P = c (8 a1 c^2 + 1 - 8 a1), c = cos x.
        a1 = a[0]
        zero = math.sqrt((8 * a1 - 1) / (8 * a1))
        hump = math.sqrt((8 * a1 - 1) / (24 * a1))
        return pair(math.acos(hump), 2.0), pair(math.acos(zero), 2.0)
    # P = 2 a1 cos(2 pi nu) + 2 a2 cos(pi nu) + a3 = 4 a1 c^2 + 2 a2 c + a3 - 2 a1, c = cos(pi nu).
    a1, a2, a3 = a[0], a[1], a[2]
    root = math.sqrt(a2 * a2 - 4 * a1 * (a3 - 2 * a1))
    zeros = pair(math.acos((-a2 + root) / (4 * a1)), 1.0) + pair(math.acos((-a2 - root) / (4 * a1)), 1.0)
    return pair(math.acos(-a2 / (4 * a1)), 1.0), zeros


class _Layout:
    """Where each unknown sits in y: amplitudes, times tau_2.., ln of free humps and zeros, zeta."""

    def __init__(self, humps):
        self.humps = humps
        self.n = humps + 2  # impulses
        self.odd = humps % 2 == 1
        self.free_humps = humps - 1 if self.odd else humps
        self.free_zeros = humps + 1 if self.odd else humps
        self.size = 4 * humps + 3  # unknowns x; y has one more, zeta
        self.first_frequency = 2 * self.n - 1

    def split(self, y):
        """(amplitudes, tau, humps [(nu, column or None)], zeros [(nu, column or None)], zeta)."""
        n = self.n
        amplitudes = y[:n]
        tau = [0.0, *y[n : 2 * n - 1]]
        start = self.first_frequency
        humps = [(math.exp(y[start + i]), start + i) for i in range(self.free_humps)]
        start += self.free_humps
        zeros = [(math.exp(y[start + i]), start + i) for i in range(self.free_zeros)]
        if self.odd:
            humps.append((1.0, None))
        else:
            zeros.append((1.0, None))
        return amplitudes, tau, humps, zeros, y[self.size]


def _response(nu, tau, amplitudes, zeta):
    """Exponents e_k, d e_k / d zeta, exp(nu e_k), terms E_k = A_k exp(nu e_k), R, dR/dnu, d2R/dnu2."""
    damped = math.sqrt(1.0 - zeta * zeta)
    s = complex(zeta, damped)
    ds = complex(1.0, -zeta / damped)
    exponents = [s * t - zeta * tau[-1] for t in tau]
    d_exponents = [ds * t - tau[-1] for t in tau]
    phasors = [cmath.exp(nu * e) for e in exponents]
    terms = [a * p for a, p in zip(amplitudes, phasors)]
    r = sum(terms)
    r1 = sum(t * e for t, e in zip(terms, exponents))
    r2 = sum(t * e * e for t, e in zip(terms, exponents))
    return s, exponents, d_exponents, phasors, terms, r, r1, r2


def _frequency_rows(nu, column, tau, amplitudes, zeta, layout):
    """R, dR/dnu and the gradients of both with respect to every entry of y, at one frequency."""
    s, exponents, d_exponents, phasors, terms, r, r1, r2 = _response(nu, tau, amplitudes, zeta)
    n = layout.n
    g_r = [0j] * (layout.size + 1)
    g_r1 = [0j] * (layout.size + 1)
    for k in range(n):
        g_r[k] = phasors[k]
        g_r1[k] = phasors[k] * exponents[k]
    # tau_k moves e_k by s; the last time also moves every exponent by -zeta (the decay reference).
    for k in range(1, n):
        g_r[n + k - 1] = nu * s * terms[k]
        g_r1[n + k - 1] = s * terms[k] * (1.0 + nu * exponents[k])
    last = n + n - 2
    g_r[last] -= nu * zeta * r
    g_r1[last] -= zeta * (r + nu * r1)
    if column is not None:  # the unknown is ln nu: d/d(ln nu) = nu d/dnu
        g_r[column] = nu * r1
        g_r1[column] = nu * r2
    g_r[layout.size] = nu * sum(t * d for t, d in zip(terms, d_exponents))
    g_r1[layout.size] = sum(t * d * (1.0 + nu * e) for t, d, e in zip(terms, d_exponents, exponents))
    return r, r1, g_r, g_r1


def _system(y, layout, vtol):
    """Residuals F(y) (gain, hump levels, hump slopes, zero real, zero imaginary) and dF/dy as rows."""
    amplitudes, tau, humps, zeros, zeta = layout.split(y)
    size = layout.size
    residuals = [math.fsum(amplitudes) - 1.0]
    rows = [[1.0] * layout.n + [0.0] * (size + 1 - layout.n)]
    level, slope, level_rows, slope_rows = [], [], [], []
    for nu, column in sorted(humps, key=lambda pair: pair[0]):
        r, r1, g_r, g_r1 = _frequency_rows(nu, column, tau, amplitudes, zeta, layout)
        level.append(abs(r) ** 2 - vtol * vtol)
        slope.append(2.0 * (r.conjugate() * r1).real)
        level_rows.append([2.0 * (r.conjugate() * g).real for g in g_r])
        slope_rows.append([2.0 * (g.conjugate() * r1 + r.conjugate() * g1).real for g, g1 in zip(g_r, g_r1)])
    real, imag, real_rows, imag_rows = [], [], [], []
    for nu, column in sorted(zeros, key=lambda pair: pair[0]):
        r, _, g_r, _ = _frequency_rows(nu, column, tau, amplitudes, zeta, layout)
        real.append(r.real)
        imag.append(r.imag)
        real_rows.append([g.real for g in g_r])
        imag_rows.append([g.imag for g in g_r])
    return residuals + level + slope + real + imag, rows + level_rows + slope_rows + real_rows + imag_rows


def _dot(a, b):
    return math.fsum(p * q for p, q in zip(a, b))


def _evaluate(y, layout, vtol, border, level):
    """(residuals, rows, squared norm) of F(y) = 0 bordered by border . y = level, or None."""
    if not abs(y[layout.size]) < 1.0:
        return None
    try:
        residuals, rows = _system(y, layout, vtol)
    except OverflowError:  # a step sent a frequency so far out that exp overflows
        return None
    residuals.append(_dot(border, y) - level)
    rows.append(list(border))
    try:
        norm = math.fsum(f * f for f in residuals)
    except OverflowError:
        return None
    if not math.isfinite(norm) or not all(math.isfinite(v) for row in rows for v in row):
        return None
    return residuals, rows, norm


def _newton(y, layout, vtol, border, level, tol, iterations, polish):
    """Damped Newton on the bordered system; (solution, iterations) or (None, iterations).

    Each step is halved (up to 10 times) until the sum of squared residuals falls. With ``polish``
    it keeps stepping past ``tol`` while the residual still falls fast: a returned design meets its
    constraints to rounding level, whatever point of the branch Newton started from.
    """
    current = _evaluate(y, layout, vtol, border, level)
    if current is None:
        return None, 0
    for iteration in range(iterations):
        residuals, rows, norm = current
        if max(abs(f) for f in residuals) <= tol and not polish:
            return y, iteration
        step = solve_least_squares(rows, residuals)
        if step is None:
            break
        for halving in range(11):
            scale = 0.5**halving
            trial = [a - scale * b for a, b in zip(y, step)]
            evaluated = _evaluate(trial, layout, vtol, border, level)
            if evaluated is not None and evaluated[2] < norm:
                break
        else:
            break  # no decrease along the Newton direction: at rounding level, or stuck
        y, current = trial, evaluated
        if polish and max(abs(f) for f in current[0]) <= tol and current[2] > 0.25 * norm:
            break
    if max(abs(f) for f in current[0]) <= tol:
        return y, iterations
    return None, iterations


def _tangent(y, layout, vtol, previous):
    """Unit null vector of dF/dy, oriented so that previous . t > 0."""
    try:
        _, rows = _system(y, layout, vtol)
    except OverflowError:
        return None
    t = solve_least_squares([*rows, list(previous)], [0.0] * layout.size + [1.0])
    if t is None:
        return None
    norm = math.sqrt(_dot(t, t))
    return [v / norm for v in t]


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


def _unit(size, index):
    e = [0.0] * size
    e[index] = 1.0
    return e


def _start(layout, vtol):
    """The undamped solution (closed form), polished by Newton at zeta = 0."""
    amplitudes = _undamped_amplitudes(layout.humps, vtol)
    tau = [k * math.pi for k in range(layout.n)]
    free_humps, free_zeros = _undamped_extrema(layout.humps, amplitudes)
    frequencies = [math.log(v) for v in (*sorted(free_humps), *sorted(free_zeros))]
    y = [*amplitudes, *tau[1:], *frequencies, 0.0]
    fix_zeta = _unit(layout.size + 1, layout.size)
    polished, _ = _newton(y, layout, vtol, fix_zeta, 0.0, _RESIDUAL_TOL, _NEWTON_ITERATIONS, True)
    return polished


def _follow(layout, zeta, vtol):
    """y = (x, zeta) at the first crossing of ``zeta`` along the branch from zeta = 0, or _BranchEnd."""
    size = layout.size
    y = _start(layout, vtol)
    if y is None:
        raise _BranchEnd(0.0, "turns singular")
    fix_zeta = _unit(size + 1, size)
    if zeta == 0.0:
        return y
    t = _tangent(y, layout, vtol, fix_zeta)
    if t is None:
        raise _BranchEnd(0.0, "turns singular")
    h, reach = _STEP_FIRST, 0.0
    for _ in range(_STEPS_MAX):
        predicted = [a + h * b for a, b in zip(y, t)]
        new, iterations = _newton(
            predicted, layout, vtol, t, _dot(t, predicted), _CORRECTOR_TOL, _CORRECTOR_ITERATIONS, False
        )
        t_new = None
        if new is not None and math.dist(new, predicted) <= 0.5 * h:
            t_new = _tangent(new, layout, vtol, t)
        if t_new is None or _dot(t_new, t) < _MIN_ALIGNMENT:
            h /= 2
            if h < _STEP_MIN:
                raise _BranchEnd(reach, "turns singular")
            continue
        z_a, z_b = y[size], new[size]
        if z_b >= zeta:
            fraction = (zeta - z_a) / (z_b - z_a)
            start = [a + fraction * (b - a) for a, b in zip(y, new)]
            start[size] = zeta
            solution, _ = _newton(start, layout, vtol, fix_zeta, zeta, _RESIDUAL_TOL, _NEWTON_ITERATIONS, True)
            if solution is not None:
                return solution
            h /= 2
            if h < _STEP_MIN:
                raise _BranchEnd(reach, "turns singular")
            continue
        chord = math.dist(new, y)
        if t[size] > 0.0 >= t_new[size] and h / 2 >= _STEP_MIN:
            # A fold between the two points: it may rise above zeta although both ends lie below.
            if _hermite_peak(z_a, z_b, t[size] * chord, t_new[size] * chord) >= zeta:
                h /= 2
                continue
        if max(new[layout.first_frequency : size]) > math.log(NU_MAX):
            raise _BranchEnd(max(reach, _zeta_at_nu_max(y, new, layout, vtol)), "nu_max")
        if z_b < 0.0:
            raise _BranchEnd(reach, "returns to zeta = 0")
        y, t, reach = new, t_new, max(reach, z_b)
        h = min(2.0 * h if iterations <= 2 else 1.2 * h if iterations <= 4 else h, _STEP_MAX)
    raise _BranchEnd(reach, "turns singular")


def _zeta_at_nu_max(y, new, layout, vtol):
    """zeta where the outermost frequency reaches NU_MAX, between the branch points y and new."""
    frequencies = new[layout.first_frequency : layout.size]
    column = layout.first_frequency + frequencies.index(max(frequencies))
    level = math.log(NU_MAX)
    fraction = (level - y[column]) / (new[column] - y[column])
    start = [a + fraction * (b - a) for a, b in zip(y, new)]
    border = _unit(layout.size + 1, column)
    solution, _ = _newton(start, layout, vtol, border, level, _RESIDUAL_TOL, _NEWTON_ITERATIONS, True)
    return start[layout.size] if solution is None else solution[layout.size]


def _vibration(nu, tau, amplitudes, zeta):
    """|R(nu)|, the percent residual vibration of the dimensionless sequence (gain 1)."""
    damped = math.sqrt(1.0 - zeta * zeta)
    s = complex(zeta, damped)
    return abs(sum(a * cmath.exp(nu * (s * t - zeta * tau[-1])) for a, t in zip(amplitudes, tau)))


def _peak_between_zeros(tau, amplitudes, zeta, low, high):
    """(largest V, where) between nu = low and high: grid of step ~0.02, local maxima refined."""
    count = max(3, int(math.ceil((high - low) / _SHAPE_GRID)) + 1)
    spacing = (high - low) / (count - 1)
    nu = [low + i * spacing for i in range(count)]
    v = [_vibration(x, tau, amplitudes, zeta) for x in nu]
    best = max(v)
    where = nu[v.index(best)]
    for i in range(1, count - 1):
        if not (v[i] >= v[i - 1] and v[i] > v[i + 1]):
            continue
        # Golden-section search for the maximum inside the bracketing grid cells.
        a, b = nu[i - 1], nu[i + 1]
        ratio = (math.sqrt(5.0) - 1.0) / 2.0
        for _ in range(60):
            c, d = b - ratio * (b - a), a + ratio * (b - a)
            if _vibration(c, tau, amplitudes, zeta) > _vibration(d, tau, amplitudes, zeta):
                b = d
            else:
                a = c
        peak = _vibration((a + b) / 2, tau, amplitudes, zeta)
        if peak > best:
            best, where = peak, (a + b) / 2
    return best, where


def _refusal(humps, zeta, vtol, what):
    asked = f"the {humps}-hump EI shaper with vtol = {vtol:g} cannot be designed for zeta = {zeta:g}"
    return ValueError(f"{asked}: {what}; {_DOMAIN[humps]}")


@functools.lru_cache(maxsize=256)
def _dimensionless(humps, zeta, vtol):
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
    amplitudes, tau, _, zeros, _ = layout.split(y)
    if any(b <= a for a, b in zip(tau, tau[1:])) or any(a <= 0 for a in amplitudes):
        raise _refusal(humps, zeta, vtol, "the solution has an amplitude <= 0 or times out of order")
    low = min(min(nu for nu, _ in zeros), 1.0)
    high = max(max(nu for nu, _ in zeros), 1.0)
    peak, where = _peak_between_zeros(tau, amplitudes, zeta, low, high)
    if peak > vtol * (1.0 + _HUMP_RTOL):
        what = f"the solution is no EI shape, its residual vibration rises to {peak:.4g} > vtol at nu = {where:.3f}"
        raise _refusal(humps, zeta, vtol, what)
    return tuple(tau), tuple(amplitudes)
