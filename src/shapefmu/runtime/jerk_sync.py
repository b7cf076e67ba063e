"""Axes that end together: the synchronised duration of a jerk-limited multi-axis move (standard
library only).

Each axis has its time-optimal duration and up to two blocked intervals (``jerk_profiles.block``).
The move lasts the shortest T that every axis can take: the candidates are the axes' t_min and the
right ends of their blocked intervals, tried in increasing order from the largest t_min on
(Berscheid & Kroeger, RSS 2021, Sec. IV-C). The axis whose candidate it is keeps its extremal
profile; every other axis gets a profile of exactly T (``jerk_duration.profile_of_duration``).

The straight-line option moves the axes along the line of their displacement: when the initial and
target velocities and accelerations are multiples of the displacement too, one path coordinate s
with limits min over the axes of limit_i / |d_i| moves from 0 to 1 and every axis follows d_i s.
"""

from .jerk_duration import profile_of_duration
from .jerk_profiles import Limits, Phases, Problem, block


def _state_problem(state, target, limits):
    (p0, v0, a0), (pf, vf, af) = state, target
    return Problem(p0, v0, a0, pf, vf, af, limits)


def check_start_within(state, limits, name):
    """The state with an acceleration or velocity within rounding (1e-9) of a limit put on it; refused
    if the limits will be broken whatever the jerk (the velocity keeps changing by a |a| / 2J
    while the acceleration is brought to zero)."""
    p, v, a = state
    a_tol = 1e-9 * max(limits.a_max, -limits.a_min)
    v_tol = 1e-9 * max(limits.v_max, -limits.v_min)
    if not limits.a_min - a_tol <= a <= limits.a_max + a_tol:
        raise ValueError(f"{name} acceleration must be in [{limits.a_min!r}, {limits.a_max!r}], got {a!r}")
    a = min(max(a, limits.a_min), limits.a_max)
    reach = v + a * abs(a) / (2.0 * limits.j_max)
    if not limits.v_min - v_tol <= reach <= limits.v_max + v_tol:
        raise ValueError(f"{name} velocity {v!r} with acceleration {a!r} reaches {reach!r} before the acceleration "
                         f"can be brought to zero; it must stay in [{limits.v_min!r}, {limits.v_max!r}]")
    # A state sampled on a move that cruises at a velocity limit may pass it by rounding.
    return p, min(max(v, limits.v_min), limits.v_max), a


def rigid_blocks(states, targets, limits):
    """([Problem], [Block]) of every axis (``jerk_profiles.block``)."""
    problems = [_state_problem(s, t, lim) for s, t, lim in zip(states, targets, limits)]
    return problems, [block(problem) for problem in problems]


def profiles_lasting(problems, blocks, T, owner=None):
    """[Phases] of every axis lasting exactly T (the ``owner`` axis keeps the extremal profile of
    that length), or None if T is blocked for an axis or an axis has no such profile."""
    if any(b.blocked(T) for b in blocks):
        return None
    out = []
    for axis, (problem, b) in enumerate(zip(problems, blocks)):
        if axis == owner:
            phases = b.profile_at(T)
        elif T - b.t_min <= problem.tol_t:
            phases = b.fastest
        else:
            phases = profile_of_duration(problem, T, b.fastest)
        if phases is None:
            return None
        out.append(phases)
    return out


def candidate_durations(blocks):
    """[(T, owner axis)] in increasing order: the durations the synchronised move may take, each
    the t_min or a blocked interval's right end of its owner and blocked for no axis (the paper,
    Sec. IV-C). The first is the synchronised duration."""
    floor = max(b.t_min for b in blocks)
    candidates = sorted((t, axis) for axis, b in enumerate(blocks)
                        for t in [b.t_min] + [right for _, right, _ in b.intervals])
    return [(T, owner) for T, owner in candidates if T >= floor and not any(b.blocked(T) for b in blocks)]


def synchronise(states, targets, limits):
    """(T, [Phases]) of the time-synchronised move of every axis from ``states`` (p, v, a) to
    ``targets`` (p, v, a) within ``limits`` (``Limits`` per axis)."""
    problems, blocks = rigid_blocks(states, targets, limits)
    for T, owner in candidate_durations(blocks):
        phases = profiles_lasting(problems, blocks, T, owner)
        if phases is not None:
            return T, phases
    raise ValueError("unreachable target: no common duration found in which every axis reaches its target "
                     "within its limits")


def straight_line(states, targets, limits):
    """(T, [Phases]) of the move along the straight line between the positions (see the module
    docstring); ValueError if the velocities and accelerations are not along that line."""
    d = [t[0] - s[0] for s, t in zip(states, targets)]
    length = max(abs(x) for x in d)
    if length == 0.0:
        return synchronise(states, targets, limits)
    direction = [x / length for x in d]
    # The path coordinate s runs from 0 to length (the largest displacement), axis i at s * direction_i.
    path_state, path_target = [], []
    for kind in (1, 2):
        for source, out in ((states, path_state), (targets, path_target)):
            values = [row[kind] for row in source]
            scale = _along(values, direction)
            if scale is None:
                raise ValueError("a straight-line move needs every initial and target velocity and acceleration "
                                 "along the line between the positions")
            out.append(scale)
    bounds = []
    for lim, x in zip(limits, direction):
        if x == 0.0:
            continue
        m = abs(x)
        # Positive x: the path's limits are the axis limits over x; negative: mirrored.
        up = (lim.v_max / m, lim.a_max / m, -lim.v_min / m, -lim.a_min / m) if x > 0 else \
             (-lim.v_min / m, -lim.a_min / m, lim.v_max / m, lim.a_max / m)
        bounds.append((up, lim.j_max / m))
    v_max = min(b[0][0] for b in bounds)
    a_max = min(b[0][1] for b in bounds)
    v_min = -min(b[0][2] for b in bounds)
    a_min = -min(b[0][3] for b in bounds)
    j_max = min(b[1] for b in bounds)
    path_limits = Limits(v_max, a_max, j_max, v_min, a_min)
    start = (0.0, path_state[0], path_state[1])
    end = (length, path_target[0], path_target[1])
    start = check_start_within(start, path_limits, "path")
    T, (path,) = synchronise([start], [end], [path_limits])
    return T, [Phases(s[0], s[1], s[2], path.durations, [j * x for j in path.jerks]) for s, x in zip(states, direction)]


def _along(values, direction):
    """c with values == c * direction (to rounding), or None."""
    k = max(range(len(direction)), key=lambda i: abs(direction[i]))
    c = values[k] / direction[k]
    scale = max(max(abs(v) for v in values), 1e-300)
    if all(abs(v - c * x) <= 1e-12 * scale for v, x in zip(values, direction)):
        return c
    return None
