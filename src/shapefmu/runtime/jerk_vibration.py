"""Residual vibration of a flexible mode after a jerk-limited move, and moves that keep it under a
bound (standard library only).

The mode. A mode (omega, zeta) carried by an axis obeys y'' + 2 sigma y' + omega^2 y = -a(t),
sigma = zeta omega, with a(t) the axis's acceleration. Before the move the acceleration has held
its initial value a0 (jerk 0), so the mode sits at its quasi-static deflection -a0 / omega^2 and does
not ring. While the acceleration is linear in time, a = alpha + beta t, the deflection is the
quasi-static y_p = -(alpha + beta t) / omega^2 + 2 sigma beta / omega^4 plus a free oscillation; a
jump of the jerk by dj changes y_p and y_p' by 2 sigma dj / omega^4 and -dj / omega^2, and the free
oscillation takes the opposite jump. Written as the complex amplitude w = e - i (e' + sigma e) /
omega_d of the free part e (which evolves as w e^{s t}, s = -sigma + i omega_d), each jump adds
dj kappa with |kappa| = 1 / (omega^2 omega_d). So after a move of duration T whose jerk steps by
dj_k at the instants t_k (the start, every phase boundary and the end, where the jerk returns to 0)
the mode rings about its new quasi-static deflection with amplitude

    A(omega) = |S(omega)| / (omega^2 omega_d),   S(omega) = sum_k dj_k e^{s (T - t_k)}.

This is the impulse-shaper residual of Singer & Seering with the jerk steps as the impulses.

The measure. "The residual after the move, percent of the unshaped one" is here

    V = max over the band of A_move(omega) / max over the band of A_rigid(omega),

A_rigid that of the time-optimal rigid move (the Ruckig-equal one) from the same state to the same
target, the band [f (1 - delta), f (1 + delta)]. A ratio per frequency, A_move / A_rigid, would divide
by zero where the rigid move happens to leave no vibration (its jerk steps cancel at some frequency
of the band); the worst case over the band of each keeps the reference finite wherever the rigid
move rings at all. A shaper with residual V_s(omega) <= vtol on the band, convolved with the rigid
jerk, leaves V_s(omega) A_rigid(omega) <= vtol max A_rigid: it meets the bound.

The moves. ``shaped_phases`` convolves an axis's jerk with an impulse shaper (that is what "Ruckig
followed by a shaper" means from a moving start: the shaper filters the jerk, so the shaped move
leaves from the same position, velocity and acceleration with the jerk and acceleration within the
rigid move's; the rigid target is corrected, by a fixed point, so that the shaped move ends in the
target). ``cancel`` is the planner's own: it keeps the phases of the rigid move, inserts in its
longest holds jerk doublets (-J, +J) (one per frequency to cancel, two for a band), and solves the
phase durations for a duration T: final acceleration, velocity, position, the sum of durations, the
holds the rigid move had on a limit kept there, and S = 0 at every design frequency (the mode's; for
a band its centre and 0.75 delta either side), by Gauss-Newton steps of least norm from the rigid
phases. The planner tries increasing T from the rigid duration and keeps the first move that passes
the exact checks (limits, end state, the bound over the band).
"""

import math

from .jerk_profiles import Phases, phase_index

# Frequencies per unit of (band width in rad/s) x (move time) at which the band is checked: the
# phase of S turns by about that product across the band, so 20 points per radian resolve it.
_BAND_POINTS_PER_RADIAN = 20.0
_MAX_BAND_POINTS = 401


class Mode:
    """A mode (omega rad/s, zeta) with its band (+- delta, a fraction of omega) and bound vtol."""

    __slots__ = ("omega", "zeta", "delta", "vtol")

    def __init__(self, omega, zeta, delta=0.0, vtol=0.01):
        self.omega, self.zeta, self.delta, self.vtol = omega, zeta, delta, vtol

    def band(self, duration):
        """The frequencies at which the band is checked for a move lasting ``duration``."""
        if self.delta == 0.0:
            return [self.omega]
        width = 2.0 * self.delta * self.omega
        count = min(_MAX_BAND_POINTS, max(9, int(math.ceil(width * duration * _BAND_POINTS_PER_RADIAN)) + 1))
        low = self.omega * (1.0 - self.delta)
        return [low + width * k / (count - 1) for k in range(count)]

    def design_frequencies(self):
        """The frequencies at which ``cancel`` makes S = 0: the mode's for a single frequency;
        for a band, its centre and 0.75 delta either side (zeros spread over the band, as the
        extra-insensitive shapers place theirs; the planner checks the humps between them)."""
        if self.delta == 0.0:
            return [self.omega]
        return [self.omega * (1.0 + x * self.delta) for x in (-0.75, 0.0, 0.75)]


def _exp(z):
    """e^z as exp(Re z) (cos Im z, sin Im z), the formula the C twin repeats."""
    scale = math.exp(z.real)
    return complex(scale * math.cos(z.imag), scale * math.sin(z.imag))


def jerk_sum(durations, jerks, T, omega, zeta, ringing=None):
    """S(omega) of the module docstring for phases of ``durations`` and ``jerks`` lasting T.

    ``ringing(omega, zeta)``, if given, is S of the jerk steps before the start, seen at the
    start (a move re-planned while the mode still rings from the move before): it decays and
    turns with the mode, e^{s T}, and adds to the steps of this move."""
    sigma = zeta * omega
    s = complex(-sigma, omega * math.sqrt(1.0 - zeta * zeta))
    total = ringing(omega, zeta) * _exp(s * T) if ringing is not None else 0j
    previous, t = 0.0, 0.0
    for d, j in zip(durations, jerks):
        if j != previous:
            total += (j - previous) * _exp(s * (T - t))
            previous = j
        t += d
    if previous != 0.0:
        total -= previous * _exp(s * (T - t))
    return total


def amplitude(durations, jerks, T, omega, zeta, ringing=None):
    """A(omega): the amplitude the mode rings with after the move (module docstring)."""
    omega_d = omega * math.sqrt(1.0 - zeta * zeta)
    return abs(jerk_sum(durations, jerks, T, omega, zeta, ringing)) / (omega * omega * omega_d)


def worst_amplitude(phases, T, mode, ringing=None):
    """The largest A(omega) over the mode's band for ``phases`` ending at T."""
    return max(amplitude(phases.durations, phases.jerks, T, omega, mode.zeta, ringing) for omega in mode.band(T))


def padded(phases, T):
    """``phases`` followed by a hold of the final state up to T (an axis that arrives early)."""
    rest = T - phases.duration
    if rest <= 0.0:
        return phases
    return Phases(phases.p[0], phases.v[0], phases.a[0], phases.durations + [rest], phases.jerks + [0.0])


# ---------------------------------------------------------------------------------------------
# Ruckig followed by a shaper: the rigid jerk convolved with impulses


def convolve_jerk(phases, times, amplitudes):
    """Phases of the jerk sum_i A_i j(t - t_i) from the same start state."""
    edges = [0.0]
    for d in phases.durations:
        edges.append(edges[-1] + d)
    cuts = sorted({e + t for e in edges for t in times})
    span = max(cuts[-1] - cuts[0], 1e-300)
    merged = [cuts[0]]
    for c in cuts[1:]:
        if c - merged[-1] > 1e-13 * span:
            merged.append(c)
    durations, jerks = [], []
    for left, right in zip(merged, merged[1:]):
        middle = 0.5 * (left + right)
        j = 0.0
        for t, A in zip(times, amplitudes):
            local = middle - t
            if 0.0 <= local < edges[-1]:
                j += A * phases.jerks[phase_index(edges, local)]
        durations.append(right - left)
        jerks.append(j)
    return Phases(phases.p[0], phases.v[0], phases.a[0], durations, jerks)


# ---------------------------------------------------------------------------------------------
# The planner's own: cancel S at the design frequencies by solving the phase durations


def _with_doublets(phases, count, limits, tau):
    """The phases with ``count`` jerk doublets (-s J, +s J) of ramps ``tau`` inserted in the
    longest holds (a hold at positive acceleration, or a positive cruise, dips down: s = +1). A
    cruise on a velocity limit is the last choice: a dip there loses distance it cannot make up."""
    j_max = limits.j_max
    durations, jerks = list(phases.durations), list(phases.jerks)
    accelerations, velocities = list(phases.a), list(phases.v)
    v_tol = 1e-9 * max(limits.v_max, -limits.v_min)
    for _ in range(count):
        holds = [k for k, j in enumerate(jerks) if j == 0.0
                 and not (abs(accelerations[k]) <= 1e-9 * limits.a_max
                          and min(abs(velocities[k] - limits.v_max), abs(velocities[k] - limits.v_min)) <= v_tol)]
        holds = holds or [k for k, j in enumerate(jerks) if j == 0.0]
        if holds:
            k = max(holds, key=lambda i: durations[i])
        else:  # no hold: insert one of zero length where the longest phase ends
            k = max(range(len(durations)), key=lambda i: durations[i]) + 1
            durations.insert(k, 0.0)
            jerks.insert(k, 0.0)
            accelerations.insert(k, accelerations[k])
            velocities.insert(k, velocities[k])
        a, v = accelerations[k], velocities[k]
        sign = 1.0 if (a > 0.0 or (a == 0.0 and v >= 0.0)) else -1.0
        half = 0.5 * durations[k]
        durations[k:k + 1] = [half, tau, tau, half]
        jerks[k:k + 1] = [0.0, -sign * j_max, sign * j_max, 0.0]
        accelerations[k:k + 1] = [a, a, a - sign * j_max * tau, a]
        velocities[k:k + 1] = [v, v, v, v]
    return durations, jerks


def _held_limits(durations, jerks, start, limits):
    """[(phase index, 'a' or 'v', level)] of the holds of the phases that sit on a limit: the
    solve keeps them there, so that no limit is crossed where the rigid move touched it."""
    phases = Phases(start[0], start[1], start[2], durations, jerks)
    tol_a = 1e-9 * max(limits.a_max, -limits.a_min)
    tol_v = 1e-9 * max(limits.v_max, -limits.v_min)
    held = []
    for k, j in enumerate(jerks):
        if j != 0.0:
            continue
        for level in (limits.a_max, limits.a_min):
            if abs(phases.a[k] - level) <= tol_a:
                held.append((k, "a", level))
        for level in (limits.v_max, limits.v_min):
            if abs(phases.a[k]) <= tol_a and abs(phases.v[k] - level) <= tol_v:
                held.append((k, "v", level))
    return held


def _equations(durations, jerks, start, target, T, frequencies, scales, held, ringing):
    """(F, Jacobian columns): the scaled equations of ``cancel`` and their exact derivatives with
    respect to every duration. Lengthening phase k by dt inserts dt of its jerk where it ends:
    the end state moves by Phi(R_k) (v_k, a_k, j_k) dt (R_k the time left after it, Phi the
    triple integrator's flow), and every jerk step after it comes dt later, d e^{s (T - t)} =
    -s e^{s (T - t)} dt."""
    phases = Phases(start[0], start[1], start[2], durations, jerks)
    n = len(durations)
    ends = phases.ends
    total = ends[-1]
    F = [(phases.a[-1] - target[2]) / scales[0], (phases.v[-1] - target[1]) / scales[1],
         (phases.p[-1] - target[0]) / scales[2], (total - T) / scales[3]]
    columns = [[0.0] * 4 for _ in range(n)]
    for k in range(n):
        R = total - ends[k + 1]
        dv, da, dj = phases.v[k + 1], phases.a[k + 1], jerks[k]
        columns[k][0] = dj / scales[0]
        columns[k][1] = (da + dj * R) / scales[1]
        columns[k][2] = (dv + da * R + dj * R * R / 2.0) / scales[2]
        columns[k][3] = 1.0 / scales[3]
    for m, kind, level in held:
        # "a", "v": the acceleration or velocity where phase m starts; "turn": the velocity where
        # the acceleration passes zero inside phase m, v_m - a_m^2 / (2 j_m).
        if kind == "a":
            F.append((phases.a[m] - level) / scales[0])
        elif kind == "v":
            F.append((phases.v[m] - level) / scales[1])
        else:
            F.append((phases.v[m] - phases.a[m] ** 2 / (2.0 * jerks[m]) - level) / scales[1])
        for k in range(n):
            if k >= m:
                columns[k].append(0.0)
            elif kind == "a":
                columns[k].append(jerks[k] / scales[0])
            else:
                dv = phases.a[k + 1] + jerks[k] * (ends[m] - ends[k + 1])
                if kind == "turn":
                    dv -= phases.a[m] / jerks[m] * jerks[k]
                columns[k].append(dv / scales[1])
    for omega, zeta in frequencies:
        s = complex(-zeta * omega, omega * math.sqrt(1.0 - zeta * zeta))
        # Steps dj_i at the starts of the phases and at the end; moving an instant t_i by dt
        # changes its term dj_i e^{s (T - t_i)} by -s times it.
        steps, previous = [], 0.0
        for k in range(n + 1):
            level = jerks[k] if k < n else 0.0
            steps.append((level - previous) * _exp(s * (T - ends[k])))
            previous = level
        value = sum(steps)
        if ringing is not None:
            value += ringing(omega, zeta) * _exp(s * T)
        F += [value.real / scales[4], value.imag / scales[4]]
        tail = 0j
        tails = [0j] * n
        for k in range(n - 1, -1, -1):
            tail += -s * steps[k + 1]
            tails[k] = tail / scales[4]
        for k in range(n):
            columns[k] += [tails[k].real, tails[k].imag]
    return F, columns


def cancel(start, target, limits, T, modes, rigid, ringing=None, frequencies=None, doublets=True, pins=(),
           iterations=40):
    """Durations and jerks of ``rigid``'s phases plus doublets that end in ``target`` at T with
    S = 0 at every design frequency of ``modes`` (module docstring), or None if Gauss-Newton
    fails. ``frequencies`` [(omega, zeta)] replaces the modes' design frequencies; without
    ``doublets`` the phases of ``rigid`` (a shaped move) are re-timed as they are. ``pins``
    [(phase, kind, level)] hold more points on a limit (``violation``)."""
    if frequencies is None:
        frequencies = [(omega, mode.zeta) for mode in modes for omega in mode.design_frequencies()]
    j_max = limits.j_max
    S_rigid = max(abs(jerk_sum(rigid.durations, rigid.jerks, rigid.duration, w, z, ringing)) for w, z in frequencies)
    omega_low = min(w for w, _ in frequencies)
    tau = math.sqrt(S_rigid / (j_max * omega_low * omega_low) / len(frequencies)) if S_rigid > 0.0 else 0.0
    if doublets:
        # One doublet per frequency cancels a single one; zeros spread over a band need more
        # freedom than they have equations (two doublets each), or Gauss-Newton finds no root.
        count = len(frequencies) * (1 if all(mode.delta == 0.0 for mode in modes) else 2)
        durations, jerks = _with_doublets(padded(rigid, T), count, limits, tau)
    else:
        durations, jerks = list(rigid.durations), list(rigid.jerks)
    held = _held_limits(durations, jerks, start, limits) + list(pins)
    v_scale = max(limits.v_max, -limits.v_min)
    a_scale = max(limits.a_max, -limits.a_min)
    scales = (a_scale, v_scale, v_scale * T, T, max(S_rigid, j_max * 1e-12))
    x = list(durations)
    F, columns = _equations(x, jerks, start, target, T, frequencies, scales, held, ringing)
    norm = math.sqrt(sum(f * f for f in F))
    for _ in range(iterations):
        if norm < 1e-14:
            break
        # Durations at zero that the step would make negative stay at zero (an active set).
        frozen = set()
        while True:
            step = _least_norm_step([[0.0] * len(F) if k in frozen else c for k, c in enumerate(columns)], F)
            if step is None:
                return None
            blocked = {k for k, (xk, dk) in enumerate(zip(x, step)) if xk <= 0.0 and dk < 0.0} - frozen
            if not blocked:
                break
            frozen |= blocked
        # Halve the step until the residual falls; no duration may turn negative.
        factor = 1.0
        for _ in range(30):
            trial = [max(xi + factor * dx, 0.0) for xi, dx in zip(x, step)]
            if sum(trial) > 2.0 * T:  # a step far off the duration: shorten it
                factor *= 0.5
                continue
            F_trial, columns_trial = _equations(trial, jerks, start, target, T, frequencies, scales, held, ringing)
            norm_trial = math.sqrt(sum(f * f for f in F_trial))
            if norm_trial < norm:
                x, F, columns, norm = trial, F_trial, columns_trial, norm_trial
                break
            factor *= 0.5
        else:
            break
    return (x, jerks) if norm < 1e-11 else None


def violation(phases, limits):
    """(phase, kind, level) of the point of ``phases`` furthest past a limit (relative to the
    limit), as a pin for ``cancel``; None if every limit holds to 1e-9."""
    worst, found = 1e-9, None
    for k in range(1, len(phases.durations)):
        for value, high, low, kind in ((phases.a[k], limits.a_max, limits.a_min, "a"),
                                       (phases.v[k], limits.v_max, limits.v_min, "v")):
            for level in (high, low):
                excess = (value - level) / level
                if excess > worst:
                    worst, found = excess, (k, kind, level)
    for k, j in enumerate(phases.jerks):
        a0, a1 = phases.a[k], phases.a[k + 1]
        if j != 0.0 and a0 * a1 < 0.0:
            turn = phases.v[k] - a0 * a0 / (2.0 * j)
            for level in (limits.v_max, limits.v_min):
                excess = (turn - level) / level
                if excess > worst:
                    worst, found = excess, (k, "turn", level)
    return found


def _least_norm_step(columns, F):
    """dx of least norm with J dx = -F (J given by its columns, one per duration; m <= n):
    dx = J^T y with (J J^T + mu I) y = -F, mu = 1e-13 trace (a Levenberg term that keeps the
    system positive definite), solved by Cholesky."""
    n, m = len(columns), len(F)
    rows = list(zip(*columns))
    M = [[sum(a * b for a, b in zip(rows[i], rows[j])) for j in range(i + 1)] for i in range(m)]
    mu = 1e-13 * max(sum(M[i][i] for i in range(m)), 1e-300)
    L = [[0.0] * m for _ in range(m)]
    for i in range(m):
        for j in range(i + 1):
            value = M[i][j] + (mu if i == j else 0.0) - sum(L[i][k] * L[j][k] for k in range(j))
            if i == j:
                if value <= 0.0:
                    return None
                L[i][i] = math.sqrt(value)
            else:
                L[i][j] = value / L[j][j]
    y = [0.0] * m
    for i in range(m):
        y[i] = (-F[i] - sum(L[i][k] * y[k] for k in range(i))) / L[i][i]
    for i in range(m - 1, -1, -1):
        y[i] = (y[i] - sum(L[k][i] * y[k] for k in range(i + 1, m))) / L[i][i]
    return [sum(c * yi for c, yi in zip(column, y)) for column in columns]
