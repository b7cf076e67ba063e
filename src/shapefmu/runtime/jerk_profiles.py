"""Time-optimal jerk-limited profiles of one axis, from any state to any state (standard library only).

An axis is a triple integrator: jerk j(t) in [-J, J] drives acceleration, velocity and position,
with a in [a_min, a_max] and v in [v_min, v_max]. A profile is seven phases of constant jerk
(Berscheid & Kroeger, "Jerk-limited Real-time Trajectory Generation with Arbitrary Target States",
RSS 2021, Sec. IV): jerks (J, 0, -J, 0, -J, 0, J) for the direction "up" (J > 0) and the same with
-J for "down". Phase 2 holds the acceleration limit, phase 4 the velocity limit, phase 6 the other
acceleration limit; a phase that is not at a limit has zero length, and without phase 4 the third
and fifth phases join (the acceleration passes through zero without stopping).

``extremal_profiles`` lists every such profile that reaches the target within the limits: the
time-optimal one is the shortest, and the others bound the durations the axis cannot take (the
blocked intervals of the paper, Sec. IV-B: a moving axis that must turn round cannot end in some
window of durations). Each family is one equation in one unknown, derived here (with sympy, from
the phase integrals; the coefficients below are that derivation written out):

- velocity limit reached (phase 4 > 0): closed form, the cruise fills the distance;
- neither limit: u = duration of the joined phases 3 + 5; with a1 - a5 = J u and a1^2 - a5^2 = K,
  K = J (vf - v0) + (a0^2 - af^2) / 2, the position equation is u^2 times a quartic in u;
- acceleration limit a_max held (phase 2): a5 = a_max - J u, a quartic in u;
- a_min held (phase 6): a1 = a_min + J u, a quartic in u;
- both held: a quadratic in the length of phase 2.

The second step, a profile of the axis that lasts exactly T (to end together with a slower axis),
is ``runtime.jerk_duration``.
"""

import math

# A duration, acceleration or velocity this small relative to the problem's own scale is rounding.
_EPS = 1e-12


class Phases:
    """Constant-jerk phases ``(duration, jerk)`` from the state (p0, v0, a0); the states at the
    phase boundaries are accumulated once, so that ``state(t)`` is exact polynomials of the phase."""

    __slots__ = ("durations", "jerks", "p", "v", "a", "ends")

    def __init__(self, p0, v0, a0, durations, jerks):
        self.durations = list(durations)
        self.jerks = list(jerks)
        p, v, a = [p0], [v0], [a0]
        ends = [0.0]
        for t, j in zip(self.durations, self.jerks):
            p.append(p[-1] + t * (v[-1] + t * (a[-1] / 2.0 + t * j / 6.0)))
            v.append(v[-1] + t * (a[-1] + t * j / 2.0))
            a.append(a[-1] + t * j)
            ends.append(ends[-1] + t)
        self.p, self.v, self.a, self.ends = p, v, a, ends

    @property
    def duration(self):
        return self.ends[-1]

    def end(self):
        return self.p[-1], self.v[-1], self.a[-1]

    def state(self, t):
        """(p, v, a, j) at time t from the start; before 0 the start state, after the end the end
        state moving on with constant acceleration (jerk 0)."""
        ends = self.ends
        if t <= 0.0:
            return self.p[0], self.v[0], self.a[0], 0.0
        if t >= ends[-1]:
            s = t - ends[-1]
            a, v, p = self.a[-1], self.v[-1], self.p[-1]
            return p + s * (v + s * a / 2.0), v + s * a, a, 0.0
        k = phase_index(ends, t)
        s, j = t - ends[k], self.jerks[k]
        a, v, p = self.a[k], self.v[k], self.p[k]
        return p + s * (v + s * (a / 2.0 + s * j / 6.0)), v + s * (a + s * j / 2.0), a + s * j, j

    def extrema(self):
        """(v_low, v_high, a_low, a_high) over the whole profile, exactly: the acceleration is
        extreme at phase ends, the velocity there or where the acceleration crosses zero."""
        a_low, a_high = min(self.a), max(self.a)
        v_low, v_high = min(self.v), max(self.v)
        for k, (t, j) in enumerate(zip(self.durations, self.jerks)):
            a_start, a_end = self.a[k], self.a[k + 1]
            if j != 0.0 and a_start * a_end < 0.0:
                v_turn = self.v[k] - a_start * a_start / (2.0 * j)
                v_low, v_high = min(v_low, v_turn), max(v_high, v_turn)
        return v_low, v_high, a_low, a_high


def phase_index(ends, t):
    """The k with ends[k] <= t < ends[k + 1] (the last phase for t past the end)."""
    low, high = 0, len(ends) - 2
    while low < high:
        middle = (low + high + 1) // 2
        if ends[middle] <= t:
            low = middle
        else:
            high = middle - 1
    return low


class Limits:
    """Velocity, acceleration and jerk limits of one axis; v_min and a_min are negative."""

    __slots__ = ("v_max", "v_min", "a_max", "a_min", "j_max")

    def __init__(self, v_max, a_max, j_max, v_min=None, a_min=None):
        self.v_max, self.a_max, self.j_max = v_max, a_max, j_max
        self.v_min = -v_max if v_min is None else v_min
        self.a_min = -a_max if a_min is None else a_min

    def oriented(self, up):
        """(vU, aU, aL, J) of the direction "up" (J > 0) or "down" (everything mirrored)."""
        if up:
            return self.v_max, self.a_max, self.a_min, self.j_max
        return self.v_min, self.a_min, self.a_max, -self.j_max


# ---------------------------------------------------------------------------------------------
# Polynomial roots (real, in an interval)


def _evaluate(coefficients, x):
    value = 0.0
    for c in coefficients:
        value = value * x + c
    return value


def _derivative(coefficients):
    n = len(coefficients) - 1
    return [c * (n - k) for k, c in enumerate(coefficients[:-1])]


def real_roots(coefficients, low, high):
    """The real roots in [low, high] of the polynomial with ``coefficients`` (highest power first).

    The roots of the derivative split [low, high] into pieces on which the polynomial is monotone;
    a piece whose ends differ in sign holds one root, found by bisection to the last bit. A
    derivative root where the polynomial is within rounding of zero is a double root (a tangency,
    where two extremal profiles meet) and is returned too.
    """
    scale = max((abs(c) for c in coefficients), default=0.0)
    while coefficients and abs(coefficients[0]) <= 1e-14 * scale:
        coefficients = coefficients[1:]
    if len(coefficients) < 2 or scale == 0.0:
        return []
    if len(coefficients) == 2:
        x = -coefficients[1] / coefficients[0]
        return [x] if low <= x <= high else []
    turns = real_roots(_derivative(coefficients), low, high)
    points = [low, *turns, high]
    values = [_evaluate(coefficients, x) for x in points]
    size = max(abs(c) * max(abs(low), abs(high), 1.0) ** (len(coefficients) - 1 - k)
               for k, c in enumerate(coefficients))
    roots = []
    for x0, x1, f0, f1 in zip(points, points[1:], values, values[1:]):
        if f0 == 0.0:
            roots.append(x0)
        elif f0 * f1 < 0.0:
            roots.append(_bisect(coefficients, x0, x1, f0))
    if values[-1] == 0.0:
        roots.append(points[-1])
    for x, f in zip(turns, values[1:-1]):
        if f != 0.0 and abs(f) <= 1e-13 * size:
            roots.append(x)
    return sorted(roots)


def _bisect(coefficients, x0, x1, f0):
    for _ in range(200):
        middle = 0.5 * (x0 + x1)
        if middle in (x0, x1):
            break
        f = _evaluate(coefficients, middle)
        if f == 0.0:
            return middle
        if (f < 0.0) == (f0 < 0.0):
            x0, f0 = middle, f
        else:
            x1 = middle
    return 0.5 * (x0 + x1)


# ---------------------------------------------------------------------------------------------
# Step 1: the extremal profiles (time-optimal and the ends of the blocked intervals)


class Problem:
    """One axis from (p0, v0, a0) to (pf, vf, af) within ``limits``, with the tolerances its
    scale allows."""

    __slots__ = ("p0", "v0", "a0", "pf", "vf", "af", "limits", "pd", "tol_p", "tol_v", "tol_a", "tol_t")

    def __init__(self, p0, v0, a0, pf, vf, af, limits):
        self.p0, self.v0, self.a0, self.pf, self.vf, self.af = p0, v0, a0, pf, vf, af
        self.limits = limits
        self.pd = pf - p0
        lim = limits
        v_scale = max(lim.v_max, -lim.v_min, abs(v0), abs(vf))
        a_scale = max(lim.a_max, -lim.a_min, abs(a0), abs(af))
        # A time scale of the problem: its moves last at least about this long.
        t_scale = max(a_scale / lim.j_max, v_scale / a_scale, math.sqrt(abs(self.pd) / a_scale))
        self.tol_t = 1e-12 * t_scale
        self.tol_a = 1e-10 * a_scale
        self.tol_v = 1e-9 * v_scale
        self.tol_p = 1e-9 * max(abs(self.pd), v_scale * t_scale, abs(p0), abs(pf))

    def accept(self, durations, jerks):
        """The ``Phases`` if these durations make a profile that reaches the target within the
        limits, else None. Durations negative by rounding only are taken as zero."""
        tol_t = self.tol_t
        if any(t < -tol_t or t != t for t in durations):
            return None
        durations = [t if t > 0.0 else 0.0 for t in durations]
        phases = Phases(self.p0, self.v0, self.a0, durations, jerks)
        p, v, a = phases.end()
        if abs(p - self.pf) > self.tol_p or abs(v - self.vf) > self.tol_v or abs(a - self.af) > self.tol_a:
            return None
        v_low, v_high, a_low, a_high = phases.extrema()
        lim = self.limits
        if (a_high > lim.a_max + self.tol_a or a_low < lim.a_min - self.tol_a
                or v_high > lim.v_max + self.tol_v or v_low < lim.v_min - self.tol_v):
            return None
        return phases


def velocity_change(v0, a0, v1, a1, a_max, a_min, j_max):
    """The time-optimal phases [(duration, jerk), ...] from (v0, a0) to (v1, a1), position free.

    Up (J = j_max) or down (J = -j_max) to a peak ap and back: the velocity gained is
    (ap^2 - a0^2) / 2J + ap t_hold + (ap^2 - a1^2) / 2J; without a hold ap^2 = J (v1 - v0) +
    (a0^2 + a1^2) / 2, and an ap past the acceleration limit is held at the limit instead.
    The direction is up when the velocity wanted exceeds what the direct ramp a0 -> a1 gives.
    """
    if a1 == a0:
        direct = 0.0
    else:
        direct = (a1 * a1 - a0 * a0) / (2.0 * math.copysign(j_max, a1 - a0))
    # Within rounding of the direct ramp (a state sampled where a move brakes onto a limit) the
    # ramp itself: the form whose first phase has no length.
    if abs(v1 - v0 - direct) <= 1e-12 * (abs(v0) + abs(v1) + (a0 * a0 + a1 * a1) / j_max):
        up = a1 < a0
    else:
        up = v1 - v0 > direct
    J = j_max if up else -j_max
    limit = a_max if up else a_min
    square = J * (v1 - v0) + 0.5 * (a0 * a0 + a1 * a1)
    peak = math.copysign(math.sqrt(max(square, 0.0)), J)
    hold = 0.0
    if (peak - limit) * J > 0.0:
        peak = limit
        hold = (v1 - v0 - (2.0 * peak * peak - a0 * a0 - a1 * a1) / (2.0 * J)) / peak
    return [((peak - a0) / J, J), (hold, 0.0), ((peak - a1) / J, -J)]


def _with_cruise(problem, up):
    """The profiles of direction ``up`` that cruise at the velocity limit (phase 4 > 0)."""
    lim = problem.limits
    vU, aU, aL, J = lim.oriented(up)
    accelerate = velocity_change(problem.v0, problem.a0, vU, 0.0, lim.a_max, lim.a_min, lim.j_max)
    decelerate = velocity_change(vU, 0.0, problem.vf, problem.af, lim.a_max, lim.a_min, lim.j_max)
    # Only the up-then-down velocity changes belong to this direction's seven phases.
    if accelerate[0][1] != J and accelerate[0][0] > problem.tol_t or decelerate[0][1] != -J and decelerate[0][0] > problem.tol_t:
        return None
    durations = [accelerate[0][0], accelerate[1][0], accelerate[2][0], 0.0,
                 decelerate[0][0], decelerate[1][0], decelerate[2][0]]
    jerks = [J, 0.0, -J, 0.0, -J, 0.0, J]
    without = Phases(problem.p0, problem.v0, problem.a0, durations, jerks)
    durations[3] = (problem.pf - without.p[-1]) / vU
    if durations[3] <= problem.tol_t:
        return None
    return problem.accept(durations, jerks)


def _without_cruise(problem, up):
    """The profiles of direction ``up`` whose acceleration passes zero without a cruise."""
    lim = problem.limits
    _, aU, aL, J = lim.oriented(up)
    a0, v0, af, vf, pd = problem.a0, problem.v0, problem.af, problem.vf, problem.pd
    J2, J3, J4 = J * J, J * J * J, J ** 4
    jerks = [J, 0.0, -J, 0.0, -J, 0.0, J]
    found = []
    u_high = (aU - aL) / J  # a1 - a5 = J u cannot exceed the span of the acceleration limits
    # Neither acceleration limit: u^2 (u^4 + c2 u^2 + c1 u + c0) = 0.
    K = J * (vf - v0) + 0.5 * (a0 * a0 - af * af)
    quartic = [1.0, 0.0, 2.0 * (2.0 * J * (v0 + vf) - a0 * a0 - af * af) / J2,
               -4.0 * (3.0 * J2 * pd + 3.0 * J * (a0 * v0 - af * vf) - a0 ** 3 + af ** 3) / (3.0 * J3),
               -(2.0 * J * (v0 - vf) - a0 * a0 + af * af) ** 2 / (4.0 * J4)]
    for u in real_roots(quartic, 0.0, u_high):
        if u <= 0.0:
            continue
        a1 = 0.5 * (J * u + K / (J * u))
        a5 = a1 - J * u
        found.append(problem.accept([(a1 - a0) / J, 0.0, *_through_zero(a1, a5, J), 0.0, (af - a5) / J], jerks))
    # a_max held (phase 2), a5 = aU - J u.
    c0 = (-24 * J2 * aU * pd - 12 * J2 * v0 * v0 + 12 * J2 * vf * vf + 12 * J * a0 * a0 * v0 - 24 * J * a0 * aU * v0
          + 12 * J * aU * aU * v0 - 12 * J * aU * aU * vf + 24 * J * aU * af * vf - 12 * J * af * af * vf - 3 * a0 ** 4
          + 8 * a0 ** 3 * aU - 6 * a0 * a0 * aU * aU + 6 * aU * aU * af * af - 8 * aU * af ** 3 + 3 * af ** 4)
    quartic = [12 * J4, -24 * J3 * aU, 12 * J2 * (2 * J * vf + aU * aU - af * af), 0.0, c0]
    for u in real_roots(quartic, 0.0, u_high):
        t2 = (2 * J2 * u * u - 4 * J * aU * u - 2 * J * v0 + 2 * J * vf + a0 * a0 - af * af) / (2 * J * aU)
        a5 = aU - J * u
        found.append(problem.accept([(aU - a0) / J, t2, *_through_zero(aU, a5, J), 0.0, (af - a5) / J], jerks))
    # a_min held (phase 6), a1 = aL + J u.
    c0 = (-24 * J2 * aL * pd - 12 * J2 * v0 * v0 + 12 * J2 * vf * vf + 12 * J * a0 * a0 * v0 - 24 * J * a0 * aL * v0
          + 12 * J * aL * aL * v0 - 12 * J * aL * aL * vf + 24 * J * aL * af * vf - 12 * J * af * af * vf - 3 * a0 ** 4
          + 8 * a0 ** 3 * aL - 6 * a0 * a0 * aL * aL + 6 * aL * aL * af * af - 8 * aL * af ** 3 + 3 * af ** 4)
    quartic = [-12 * J4, -24 * J3 * aL, -12 * J2 * (2 * J * v0 - a0 * a0 + aL * aL), 0.0, c0]
    for u in real_roots(quartic, 0.0, u_high):
        t6 = -(2 * J2 * u * u + 4 * J * aL * u + 2 * J * v0 - 2 * J * vf - a0 * a0 + af * af) / (2 * J * aL)
        a1 = aL + J * u
        found.append(problem.accept([(a1 - a0) / J, 0.0, *_through_zero(a1, aL, J), t6, (af - aL) / J], jerks))
    # Both held: a quadratic in t2.
    q2 = 12 * J2 * aU * (aL - aU)
    q1 = 12 * J * (aL - aU) * (2 * J * v0 - a0 * a0 - aL * aU + 2 * aU * aU)
    q0 = (-24 * J2 * aL * pd - 12 * J2 * v0 * v0 + 12 * J2 * vf * vf + 12 * J * a0 * a0 * v0 - 24 * J * a0 * aL * v0
          - 12 * J * aL * aL * v0 - 12 * J * aL * aL * vf + 48 * J * aL * aU * v0 + 24 * J * aL * af * vf
          - 24 * J * aU * aU * v0 - 12 * J * af * af * vf - 3 * a0 ** 4 + 8 * a0 ** 3 * aL + 6 * a0 * a0 * aL * aL
          - 24 * a0 * a0 * aL * aU + 12 * a0 * a0 * aU * aU - 12 * aL * aL * aU * aU + 6 * aL * aL * af * af
          + 24 * aL * aU ** 3 - 8 * aL * af ** 3 - 12 * aU ** 4 + 3 * af ** 4)
    for t2 in _quadratic_roots(q2, q1, q0):
        t6 = -(2 * J * aU * t2 + 2 * J * v0 - 2 * J * vf - a0 * a0 - 2 * aL * aL + 2 * aU * aU + af * af) / (2 * J * aL)
        found.append(problem.accept([(aU - a0) / J, t2, *_through_zero(aU, aL, J), t6, (af - aL) / J], jerks))
    return [phases for phases in found if phases is not None]


def _through_zero(a1, a5, J):
    """Phases 3, 4, 5 of a ramp from a1 to a5 at jerk -J: split where the acceleration passes
    zero (phase 4, of zero length, is where a cruise would go), else all of it in phase 3."""
    if a1 * J > 0.0 and a5 * J < 0.0:
        return a1 / J, 0.0, -a5 / J
    return (a1 - a5) / J, 0.0, 0.0


def _quadratic_roots(a, b, c):
    if a == 0.0:
        return [] if b == 0.0 else [-c / b]
    discriminant = b * b - 4.0 * a * c
    if discriminant < 0.0:
        return []
    # The cancellation-free pair: q = -(b + sign(b) sqrt(D)) / 2, roots q / a and c / q.
    q = -0.5 * (b + math.copysign(math.sqrt(discriminant), b))
    return [q / a] if q == 0.0 else [q / a, c / q]


def extremal_profiles(problem):
    """Every seven-phase profile (both directions, every set of limits reached) that takes the
    axis to its target within the limits, shortest first, near-duplicates removed."""
    found = []
    for up in (True, False):
        cruise = _with_cruise(problem, up)
        if cruise is not None:
            found.append(cruise)
        found.extend(_without_cruise(problem, up))
    if problem.pd == 0.0 and problem.v0 == problem.vf == 0.0 and problem.a0 == problem.af == 0.0:
        found.append(Phases(problem.p0, 0.0, 0.0, [0.0] * 7, [0.0] * 7))
    found.sort(key=lambda phases: phases.duration)
    distinct = []
    for phases in found:
        if not distinct or phases.duration - distinct[-1].duration > 1e3 * problem.tol_t:
            distinct.append(phases)
    return distinct


class Block:
    """The durations an axis can take: [t_min, inf) but for at most two open intervals."""

    __slots__ = ("fastest", "intervals")

    def __init__(self, fastest, intervals):
        self.fastest = fastest          # Phases of the time-optimal profile
        self.intervals = intervals      # [(left, right, Phases that lasts `right`)]

    @property
    def t_min(self):
        return self.fastest.duration

    def blocked(self, t):
        return t < self.t_min or any(left < t < right for left, right, _ in self.intervals)

    def profile_at(self, t):
        """The extremal profile that lasts exactly t, if t is t_min or an interval's right end."""
        if t == self.t_min:
            return self.fastest
        for _, right, phases in self.intervals:
            if t == right:
                return phases
        return None


def block(problem):
    """The ``Block`` of one axis from its extremal profiles (the paper, Sec. IV-B): the shortest
    is t_min; the others pair up into the blocked intervals between them. With two, the axis
    cannot end between them (they are the two ends of one interval beginning at t_min)."""
    profiles = extremal_profiles(problem)
    if not profiles:
        raise ValueError("unreachable target: no jerk-limited profile reaches it within the limits")
    fastest, rest = profiles[0], profiles[1:]
    if len(rest) == 1:
        return Block(fastest, [(fastest.duration, rest[0].duration, rest[0])])
    if len(rest) == 2:
        return Block(fastest, [(rest[0].duration, rest[1].duration, rest[1])])
    if len(rest) == 4:
        return Block(fastest, [(rest[0].duration, rest[1].duration, rest[1]),
                               (rest[2].duration, rest[3].duration, rest[3])])
    if len(rest) == 3:  # two coincide at a tangency: keep the outer pair
        return Block(fastest, [(rest[0].duration, rest[2].duration, rest[2])])
    return Block(fastest, [])
