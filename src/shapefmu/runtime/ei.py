"""Extra-insensitive (EI) shapers with one, two and three humps, standard library only.

What a Shaper FMU designs at initialisation for ``kind`` ei, ei2, ei3. Same equations, same
continuation, same choice among several solutions, same domain and same messages as the design
layer ``shapefmu.shapers.ei`` (numpy), whose docstring states the definition, the measured domain
and why the first crossing is returned; ``tests/test_runtime_ei.py`` checks both give the same
impulses to 1e-10 and refuse the same designs with the same message.

API
---
``ei(omega, zeta=0.0, vtol=0.05)``, ``ei2(...)``, ``ei3(...)`` -> ``(times, amplitudes)``, two lists
of N + 2 floats for N = 1, 2, 3 humps: times in seconds (the first 0) and positive amplitudes
summing to 1. omega > 0 rad/s, zeta in [0, ZETA_MAX], vtol in [VTOL_MIN, VTOL_MAX].

Equations (Singhose, Seering & Singer's vector-diagram formulation), in dimensionless times
tau = omega t and R(nu) = sum_k A_k exp(nu e_k), e_k = (zeta + j sqrt(1 - zeta^2)) tau_k - zeta tau_last,
so that the percent residual vibration at the frequency ratio nu is V(nu) = |R(nu)| / sum A:

    sum_k A_k = 1                                                   1
    |R(nu_h)|^2 = vtol^2,  d|R|^2/dnu (nu_h) = 0    for each hump   2N
    Re R(nu_z) = Im R(nu_z) = 0                      for each zero   2(N + 1)

in the N + 2 amplitudes, the N + 1 times tau_2.. (tau_1 = 0) and the 2N + 1 hump and zero
frequencies less the one pinned at nu = 1 (the middle hump for odd N, the middle zero for even N),
carried as ln nu so that an outermost zero running off to large nu costs few steps: 4N + 3
equations F(x, zeta) = 0 and unknowns x. The hump and zero locations are unknowns of the system, so
no frequency scan is needed to solve it: at zeta = 0 they are known in closed form
(``_undamped_extrema``), and every Newton step uses the analytic Jacobian (``_system``, including
the column d/dzeta) in a Householder QR solve (``least_squares.solve_least_squares``).

Continuation (``_follow``): pseudo-arclength in y = (x, zeta) from the undamped solution. Predict
y + h t along the unit tangent t (null vector of dF/dy, oriented by the previous tangent); correct
by damped Newton on F = 0 bordered by t . (y - y_pred) = 0; accept when every residual is <= 1e-10
within 8 iterations, the correction is <= h/2 and the tangent turns by less than ~26 degrees, else
halve h (h from 0.05, at most 1, doubled after an easy step). The first accepted point at or past
the requested zeta brackets the first crossing, solved with zeta fixed to rounding level; a step
that lands below zeta across a fold is halved while the cubic Hermite interpolant of zeta(s) says
the fold may reach zeta (``_hermite_peak``). The branch ends when a frequency passes NU_MAX, when
h falls below 1e-7, or when zeta returns below 0; the returned design must further have positive
amplitudes, increasing times and V <= vtol (1 + 1e-6) between its outermost zeros
(``_peak_between_zeros``: a 0.02 grid in nu, every local maximum refined by golden section).
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
# What the domain scan measured (shapefmu.shapers.ei docstring); every refusal ends with its kind's line.
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
    """Residuals F(y) (ordered as the design layer's) and the Jacobian dF/dy as rows."""
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
    it keeps stepping past ``tol`` while the residual still falls fast: the last digits are what
    make the two implementations of these equations agree.
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
