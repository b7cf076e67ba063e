"""The second step of a jerk-limited axis (standard library only): a profile lasting exactly T, to end
together with a slower axis (Berscheid & Kroeger, RSS 2021, Sec. IV-C), for any T at or above the
axis's t_min and outside its blocked intervals (``jerk_profiles.block``).

The profiles searched hold an acceleration level between two time-optimal velocity changes
(``jerk_profiles.velocity_change``): a cruise at a = 0, a hold at the start's or the target's
acceleration or where the fastest profile turns, then levels across the range; and, last, two
changes that meet without a hold (the turning profiles, UDUD in the paper).
"""

from .jerk_profiles import Phases, velocity_change


def _hold_profile(problem, T, level, va):
    """(position error, phases) of: velocity change to (va, level), a hold of the acceleration
    ``level``, velocity change to the target, lasting T; None if the changes alone outlast T.

    The hold's length h and the velocity vb = va + level h it ends with depend on each other
    through the time of the second change; h = T - t_A - t_B(va + level h) is a contraction for
    |level| < the acceleration limits (t_B changes by at most 1/a_limit per unit of velocity), so
    the fixed-point iteration converges to the last bit.
    """
    lim = problem.limits
    first = velocity_change(problem.v0, problem.a0, va, level, lim.a_max, lim.a_min, lim.j_max)
    t_first = sum(t for t, _ in first)
    hold = 0.0
    for _ in range(100):
        second = velocity_change(va + level * hold, level, problem.vf, problem.af, lim.a_max, lim.a_min, lim.j_max)
        updated = T - t_first - sum(t for t, _ in second)
        if updated < 0.0:
            if updated < -problem.tol_t:
                return None
            updated = 0.0
        if updated == hold or level == 0.0:
            hold = updated
            break
        hold = updated
    phases = Phases(problem.p0, problem.v0, problem.a0,
                    [t for t, _ in first] + [hold] + [t for t, _ in second],
                    [j for _, j in first] + [0.0] + [j for _, j in second])
    return phases.p[-1] - problem.pf, phases


def profile_of_duration(problem, T, near=None, samples=24):
    """A profile of the axis lasting exactly T (>= its t_min, outside its blocked intervals).

    It holds an acceleration level between two time-optimal velocity changes: a cruise (level 0)
    first, else the level of the target's or the start's acceleration, one of the levels the
    fastest profile ``near`` turns at (an axis whose acceleration never crosses zero near its
    fastest move lengthens it by holding where it turns), then levels across the range, and a
    finer grid of them last. For each level, the velocity va at which the hold
    starts is searched in [v_min, v_max] on a grid and at the velocities where the profile ``near``
    (the axis's fastest) passes the level: just above t_min the answer is a small perturbation of
    that profile, in a window of va narrower than any grid. Where the two changes leave time to
    spare for the hold, the position error is compared between neighbours (the edges of that region
    found by bisection), a sign change refined by bisection to the last bit, and the profile checked
    like every other (``Problem.accept``).
    """
    lim = problem.limits
    levels = [0.0, problem.af, problem.a0, 0.5 * (problem.a0 + problem.af)]
    if near is not None:
        levels += [a for a in near.a[1:-1] if a not in levels]
    # Then levels across the range: the hold of an axis that ends turning hard can be anywhere.
    levels += [lim.a_min + (lim.a_max - lim.a_min) * k / (2 * samples) for k in range(1, 2 * samples)]
    for level in levels:
        found = _with_hold(problem, T, level, near, samples)
        if found is not None:
            return found
    found = _meeting_profile(problem, T, samples)
    # Last, a grid four times finer: just above t_min the levels that work can be a narrow window.
    for k in range(1, 8 * samples):
        if found is not None or k % 4 == 0:
            continue
        found = _with_hold(problem, T, lim.a_min + (lim.a_max - lim.a_min) * k / (8 * samples), near, samples)
    return found


def _with_hold(problem, T, level, near, samples):
    """The profile lasting T that holds ``level`` (``profile_of_duration``), or None."""
    lim = problem.limits
    if not lim.a_min < level < lim.a_max and level != 0.0:
        return None
    seeds = _passing_velocities(near, level) if near is not None else []
    _, points = _hold_points(problem, T, level, seeds, samples)
    errors = [(va, _hold_profile(problem, T, level, va)) for va in points]
    for (va, first), (vb, second) in zip(errors, errors[1:]):
        if first is None or second is None or first[0] * second[0] > 0.0:
            continue
        phases = _refine_hold(problem, T, level, va, vb, first)
        accepted = phases and problem.accept(phases.durations, phases.jerks)
        if accepted:
            return accepted
    return None


def _hold_points(problem, T, level, seeds, samples):
    """(edges, points): the velocities va where the two changes around a hold at ``level`` take
    exactly T (edges), and those plus the grid points where they take less (points)."""
    lim = problem.limits
    grid = [lim.v_min + (lim.v_max - lim.v_min) * k / samples for k in range(samples + 1)]
    grid = sorted(set(grid + seeds))
    spare = [_hold_time(problem, level, va) <= T for va in grid]
    points, edges = [], []
    for k, va in enumerate(grid):
        if spare[k]:
            points.append(va)
        if k + 1 < len(grid) and spare[k] != spare[k + 1]:
            inside, outside = (va, grid[k + 1]) if spare[k] else (grid[k + 1], va)
            edges.append(_edge(lambda v: _hold_time(problem, level, v), T, inside, outside))
    return edges, sorted(points + edges)


def _meeting_profile(problem, T, samples):
    """The last resort of ``profile_of_duration``: two velocity changes that meet, without a
    hold, at an acceleration level and take exactly T together (the profiles whose acceleration
    bends back, UDUD in the paper). For each level of a grid the meeting velocities are the edges
    of ``_hold_points``; they trace curves over the level, along which the position error is
    continuous: an edge is followed to the nearest edge of the next level, and a sign change of
    the error is refined by bisection on the level."""
    lim = problem.limits
    span = lim.v_max - lim.v_min
    levels = [lim.a_min + (lim.a_max - lim.a_min) * k / (2 * samples) for k in range(1, 2 * samples)]
    table = [_hold_points(problem, T, level, [], samples)[0] for level in levels]
    for k in range(len(levels) - 1):
        for va in table[k]:
            nearest = min(table[k + 1], key=lambda vb: abs(vb - va), default=None)
            if nearest is None or abs(nearest - va) > 0.1 * span:
                continue
            phases = _bisect_meeting(problem, T, samples, (levels[k], va), (levels[k + 1], nearest))
            accepted = phases and problem.accept(phases.durations, phases.jerks)
            if accepted:
                return accepted
    return None


def _bisect_meeting(problem, T, samples, low, high):
    """The meeting profile where the position error changes sign between the curve points
    ``low`` and ``high`` (level, meeting velocity), or None if it does not."""
    first, second = _hold_profile(problem, T, low[0], low[1]), _hold_profile(problem, T, high[0], high[1])
    if first is None or second is None or first[0] * second[0] > 0.0:
        return None
    error_low, phases = first
    for _ in range(100):
        level = 0.5 * (low[0] + high[0])
        if level in (low[0], high[0]):
            break
        guess = 0.5 * (low[1] + high[1])
        edges = _hold_points(problem, T, level, [], samples)[0]
        if not edges:
            return None
        va = min(edges, key=lambda v: abs(v - guess))
        result = _hold_profile(problem, T, level, va)
        if result is None:
            return None
        error, phases = result
        if (error < 0.0) == (error_low < 0.0):
            low, error_low = (level, va), error
        else:
            high = (level, va)
    return phases


def _passing_velocities(phases, level):
    """Velocities of ``phases`` where its acceleration equals ``level`` (passing or holding)."""
    found = []
    for k, (t, j) in enumerate(zip(phases.durations, phases.jerks)):
        a0, a1 = phases.a[k], phases.a[k + 1]
        if j != 0.0 and min(a0, a1) <= level <= max(a0, a1):
            s = (level - a0) / j
            found.append(phases.v[k] + s * (a0 + s * j / 2.0))
        elif j == 0.0 and t > 0.0 and a0 == level:
            found.append(phases.v[k])
    return found


def _hold_time(problem, level, va):
    """Time of the two velocity changes around a hold of zero length starting at va."""
    lim = problem.limits
    return (sum(t for t, _ in velocity_change(problem.v0, problem.a0, va, level, lim.a_max, lim.a_min, lim.j_max))
            + sum(t for t, _ in velocity_change(va, level, problem.vf, problem.af, lim.a_max, lim.a_min, lim.j_max)))


def _edge(busy, T, inside, outside):
    """The point between ``inside`` (busy <= T) and ``outside`` where busy reaches T."""
    for _ in range(100):
        middle = 0.5 * (inside + outside)
        if middle in (inside, outside):
            break
        if busy(middle) <= T:
            inside = middle
        else:
            outside = middle
    return inside


def _refine_hold(problem, T, level, low, high, result_low):
    error_low, phases = result_low
    for _ in range(200):
        middle = 0.5 * (low + high)
        if middle in (low, high) or error_low == 0.0:
            break
        result = _hold_profile(problem, T, level, middle)
        if result is None:
            return None
        error, phases = result
        if (error < 0.0) == (error_low < 0.0):
            low, error_low = middle, error
        else:
            high = middle
    return phases
