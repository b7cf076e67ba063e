"""The online jerk-limited multi-axis planner with vibration bounds (standard library only).

``plan_move(states, targets, limits, modes)`` returns a ``PlannedMove``:

1. the rigid move: time-optimal, axes synchronised (``jerk_sync``), the same duration as Ruckig's;
2. the reference: for every mode of every axis, the worst residual amplitude of the rigid move over
   the band (``jerk_vibration``); the bound is vtol times it;
3. the ceiling ("Ruckig followed by the shortest shaper meeting the band and bound"): the rigid move
   followed, per axis, by the shortest catalog shaper (``shaper_designs``; its own residual within
   vtol over the band) with which the shaped move holds the limits and every mode's bound
   (``shaped_move``);
4. the planner's move: from the rigid duration upwards, the first duration T at which every axis
   with modes has phases that cancel its modes (``jerk_vibration.cancel``), each checked exactly
   (end state, limits analytically between phase ends, the bound over the band); then the gap to the
   last failed T is halved a few times. The axes without modes take a rigid profile of T.
   Nothing shorter than the ceiling found: the ceiling itself.

Every move returned has passed the checks; when neither the planner's move nor the ceiling passes,
ValueError says why.
"""

import cmath
import math

from . import jerk_vibration as vib
from .jerk_profiles import Limits, Phases
from .jerk_sync import check_start_within, profiles_lasting, rigid_blocks, straight_line, synchronise
from .shaper_designs import design_impulses

# Increases of the rigid duration tried, relative, before the halving between the last two.
_STRETCHES = (0.0, 0.0005, 0.001, 0.002, 0.004, 0.007, 0.01, 0.015, 0.02, 0.03, 0.045, 0.06, 0.08, 0.1, 0.13, 0.16,
              0.2, 0.25, 0.3, 0.4, 0.5, 0.7, 1.0)
_HALVINGS = 6
# The shaped move of the ceiling is re-timed (its phases kept, their durations solved) only for
# durations above this fraction of its own: far below it the re-timing does not converge.
_RETIMED = 0.85
# Single-mode shapers of the catalog with non-negative impulses (a convolution keeps the jerk and
# acceleration within the rigid move's), tried shortest first for each axis.
CEILING_KINDS = ("zv", "mzv", "ei", "zvd", "ei2", "zvdd", "ei3")
MAX_CEILING_SHAPERS = 8


class PlannedMove:
    """A planned move: ``duration``, the ``phases`` of every axis (all lasting ``duration``), how
    it was found (``method``: "rigid", "cancel" or "shaped"), the rigid duration, the shapers of
    the ceiling [(kind, times, amplitudes) per axis] and its duration, and per axis per mode the
    reference amplitude and the amplitude left."""

    __slots__ = ("duration", "phases", "method", "rigid_duration", "references", "residuals", "ceiling",
                 "ceiling_duration")

    def __init__(self, duration, phases, method, rigid_duration, references, residuals, ceiling, ceiling_duration):
        self.duration = duration
        self.phases = phases
        self.method = method
        self.rigid_duration = rigid_duration
        self.references = references
        self.residuals = residuals
        self.ceiling = ceiling
        self.ceiling_duration = ceiling_duration

    def state(self, t):
        """[(p, v, a, j)] of every axis at time t from the start."""
        return [phases.state(t) for phases in self.phases]


def _rigid(states, targets, limits, straight):
    return (straight_line if straight else synchronise)(states, targets, limits)


def _shaper_residual(times, amplitudes, omega, zeta):
    """The shaper's own residual V(omega): |sum A_i e^{s (t_N - t_i)}| / sum A_i."""
    s = complex(-zeta * omega, omega * math.sqrt(1.0 - zeta * zeta))
    end = times[-1]
    return abs(sum(A * cmath.exp(s * (end - t)) for t, A in zip(times, amplitudes))) / sum(amplitudes)


def catalog_shapers(modes, duration_hint=1.0):
    """[(kind, times, amplitudes)] of the catalog shapers (``CEILING_KINDS``, and the extra-
    insensitive ones for vtol / 2, / 4, / 8, each convolved over the modes) whose own residual is
    within every mode's vtol over its band, shortest first, at most ``MAX_CEILING_SHAPERS``."""
    vtol = min(m.vtol for m in modes)
    designs = [(kind, kind, vtol) for kind in CEILING_KINDS]
    designs += [(f"{kind}(vtol/{k})", kind, vtol / k) for k in (2, 4, 8) for kind in ("ei", "ei2", "ei3")]
    found = []
    for name, kind, tolerance in designs:
        times, amplitudes = design_impulses(kind, [(m.omega, m.zeta) for m in modes], vtol=tolerance)
        if all(_shaper_residual(times, amplitudes, omega, m.zeta) <= m.vtol
               for m in modes for omega in m.band(duration_hint + times[-1])):
            found.append((name, times, amplitudes))
    found.sort(key=lambda shaper: shaper[1][-1])
    return found[:MAX_CEILING_SHAPERS]


def shaped_move(states, targets, limits, modes, bounds, ringing, straight=False, iterations=40):
    """(duration, [Phases], [(kind, times, amplitudes) or None]) of the ceiling: the rigid move
    followed, per axis, by the shortest catalog shaper (``catalog_shapers``) with which the shaped
    move holds the limits and every mode's bound (the k-th shaper of every axis tried together, k
    increasing), the rigid targets corrected by a fixed point so that the shaped axes end in
    ``targets``; None if no shaper does."""
    T0, rigid = _rigid(states, targets, limits, straight)
    lists = [catalog_shapers(axis_modes, T0) if axis_modes else [None] for axis_modes in modes]
    if not all(lists):
        return None
    for k in range(max(len(options) for options in lists)):
        shapers = [options[min(k, len(options) - 1)] for options in lists]
        shaped = _within_limits(states, targets, limits, shapers, straight, iterations)
        if shaped is not None and _meets(shaped[1], shaped[0], modes, bounds, ringing):
            return (*shaped, shapers)
    return None


def _within_limits(states, targets, limits, shapers, straight, iterations):
    """(duration, [Phases]) of the rigid move shaped with ``shapers``, within the limits, or None."""
    # From a moving start the shaper keeps part of the initial acceleration on for its length, and
    # the shaped velocity can pass a limit the rigid move only touched: the rigid move is planned
    # again within velocity limits narrowed by what the shaped one passed them by (three times).
    planned = list(limits)
    for _ in range(4):
        shaped = _shaped_fixed_point(states, targets, planned, limits, shapers, straight, iterations)
        if shaped is None:
            return None
        duration = max(p.duration for p in shaped)
        shaped = [vib.padded(p, duration) for p in shaped]
        if all(_within(phases, lim, target) for phases, lim, target in zip(shaped, limits, targets)):
            return duration, shaped
        narrowed = []
        for phases, lim, plan in zip(shaped, limits, planned):
            v_low, v_high, _, _ = phases.extrema()
            high = plan.v_max - max(v_high - lim.v_max, 0.0) * 1.001
            low = plan.v_min + max(lim.v_min - v_low, 0.0) * 1.001
            if high <= 0.0 or low >= 0.0:
                return None
            narrowed.append(Limits(high, plan.a_max, plan.j_max, low, plan.a_min))
        planned = narrowed
    return None


def _shaped_fixed_point(states, targets, planned, limits, shapers, straight, iterations):
    """The shaped phases of every axis, the rigid targets (planned within ``planned``) corrected
    until the shaped axes end in ``targets``; None if the rigid move cannot be planned."""
    corrected = [list(t) for t in targets]
    try:
        for _ in range(iterations):
            _, rigid = _rigid(states, [tuple(t) for t in corrected], planned, straight)
            shaped = [p if shaper is None else vib.convolve_jerk(p, shaper[1], shaper[2])
                      for p, shaper in zip(rigid, shapers)]
            error = 0.0
            for axis, (phases, target) in enumerate(zip(shaped, targets)):
                p, v, _ = phases.end()
                corrected[axis][0] += target[0] - p
                corrected[axis][1] += target[1] - v
                error = max(error, abs(target[0] - p) / max(abs(target[0] - states[axis][0]), 1e-300),
                            abs(target[1] - v) / max(limits[axis].v_max, -limits[axis].v_min))
            if error <= 1e-13:
                break
    except ValueError:  # the narrowed limits leave the start or the target out of reach
        return None
    return shaped


def _within(phases, limits, target, relative=1e-9):
    """The exact checks: limits over the whole move (analytically between phase ends) and the
    end state, to ``relative`` of each limit's or the move's scale."""
    v_low, v_high, a_low, a_high = phases.extrema()
    a_tol = relative * max(limits.a_max, -limits.a_min)
    v_tol = relative * max(limits.v_max, -limits.v_min)
    if any(abs(j) > limits.j_max * (1.0 + relative) for j in phases.jerks):
        return False
    if a_high > limits.a_max + a_tol or a_low < limits.a_min - a_tol:
        return False
    if v_high > limits.v_max + v_tol or v_low < limits.v_min - v_tol:
        return False
    p, v, a = phases.end()
    p_tol = relative * max(abs(target[0] - phases.p[0]), v_tol * phases.duration, 1e-300)
    return abs(p - target[0]) <= p_tol and abs(v - target[1]) <= v_tol and abs(a - target[2]) <= a_tol


def _cancelled(state, target, lim, T, axis_modes, rigid, bounds, ringing, doublets=True):
    """Phases of one axis lasting T that meet every bound of its modes, or None: ``rigid`` with
    doublets, or without (a shaped move re-timed). Starts with the modes' design equations; a
    solution past a limit has that point pinned to the limit, one that still exceeds a band's
    bound gets the worst frequency added, and the durations are solved again (eight times at most)."""
    frequencies = [(omega, m.zeta) for m in axis_modes for omega in m.design_frequencies()]
    pins = []
    for _ in range(8):
        solved = vib.cancel(state, target, lim, T, axis_modes, rigid, ringing, frequencies, doublets, pins)
        if solved is None:
            return None
        phases = Phases(state[0], state[1], state[2], *solved)
        past = vib.violation(phases, lim)
        if past is not None:
            pins.append(past)
            continue
        if not _within(phases, lim, target):
            return None
        worst = None
        for mode, bound in zip(axis_modes, bounds):
            for omega in mode.band(T):
                excess = vib.amplitude(phases.durations, phases.jerks, T, omega, mode.zeta, ringing) - bound
                if excess > 0.0 and (worst is None or excess > worst[0]):
                    worst = (excess, omega, mode.zeta)
        if worst is None:
            return phases
        frequencies.append(worst[1:])
        pins = []  # another frequency inserts another doublet: the phases the pins named move
    return None


def plan_move(states, targets, limits, modes, straight=False, ts=None, ringing=None):
    """The ``PlannedMove`` of axes from ``states`` [(p, v, a)] to ``targets`` [(p, v, a)] within
    ``limits`` [Limits], each axis with its ``modes`` [[jerk_vibration.Mode]] (module docstring).

    ``straight``: move along the straight line between the positions. ``ts``: a duration that is
    a whole number of periods ts. ``ringing``: per axis a function (omega, zeta) -> S of the jerk
    steps before the start (a re-planned move), or None.
    """
    states = [check_start_within(state, lim, f"axis {axis}: initial") for axis, (state, lim) in
              enumerate(zip(states, limits))]
    ringing = ringing or [None] * len(states)
    T0, rigid = _rigid(states, targets, limits, straight)
    problems, blocks = rigid_blocks(states, targets, limits)
    if ts is not None:
        T0, rigid = _snapped(T0, rigid, problems, blocks, ts, straight)
    references = [[vib.worst_amplitude(p, T0, m, r) for m in axis_modes]
                  for p, axis_modes, r in zip(rigid, modes, ringing)]
    bounds = [[m.vtol * ref for m, ref in zip(axis_modes, refs)] for axis_modes, refs in zip(modes, references)]
    if not any(modes):
        return PlannedMove(T0, rigid, "rigid", T0, references, references, [None] * len(states), T0)
    ceiling = shaped_move(states, targets, limits, modes, bounds, ringing, straight)
    ceiling_T = ceiling[0] if ceiling is not None else math.inf

    def attempt(T):
        if straight:
            return None
        lasting = profiles_lasting(problems, blocks, T) if T != T0 else rigid
        if lasting is None:
            return None
        out = []
        for axis, phases in enumerate(lasting):
            if not modes[axis]:
                out.append(phases)
                continue
            solved = _cancelled(states[axis], targets[axis], limits[axis], T, modes[axis], rigid[axis],
                                bounds[axis], ringing[axis])
            if solved is None and ceiling is not None and T >= _RETIMED * ceiling_T:
                solved = _cancelled(states[axis], targets[axis], limits[axis], T, modes[axis], ceiling[1][axis],
                                    bounds[axis], ringing[axis], doublets=False)
            if solved is None:
                return None
            out.append(solved)
        return out

    best, failed = None, T0
    for stretch in _STRETCHES:
        T = _on_grid(T0 * (1.0 + stretch), ts)
        if T >= ceiling_T:
            break
        found = attempt(T)
        if found is not None:
            best = (T, found)
            break
        failed = T
    if best is not None:
        for _ in range(_HALVINGS):
            T = _on_grid(0.5 * (failed + best[0]), ts)
            if not failed < T < best[0]:
                break
            found = attempt(T)
            if found is None:
                failed = T
            else:
                best = (T, found)
    if best is None:
        if ceiling is None:
            raise ValueError("no move meets the vibration bounds within the limits from this state: neither the "
                             "planner's nor the rigid move followed by a catalog shaper (the shaped move would "
                             "leave the limits, or no shaper of the catalog meets a band); widen vtol or the limits")
        T, phases, shapers = ceiling
        method = "shaped"
    else:
        (T, phases), method = best, "cancel"
    residuals = [[vib.worst_amplitude(p, T, m, r) for m in axis_modes]
                 for p, axis_modes, r in zip(phases, modes, ringing)]
    return PlannedMove(T, [vib.padded(p, T) for p in phases], method, T0, references, residuals,
                       ceiling[2] if ceiling is not None else [None] * len(states), ceiling_T)


def _meets(phases, T, modes, bounds, ringing):
    """Every mode of every axis within its bound (1e-9 relative) after ``phases`` ending at T."""
    return all(vib.worst_amplitude(p, T, m, r) <= bound * (1.0 + 1e-9)
               for p, axis_modes, axis_bounds, r in zip(phases, modes, bounds, ringing)
               for m, bound in zip(axis_modes, axis_bounds))


def _on_grid(T, ts):
    return T if ts is None else math.ceil(T / ts - 1e-9) * ts


def _snapped(T0, rigid, problems, blocks, ts, straight):
    """The shortest multiple of ts at or after T0 that every axis can take, with its profiles."""
    if straight:
        raise ValueError("a straight-line move cannot be snapped to the sampling period")
    T = _on_grid(T0, ts)
    for _ in range(10000):
        lasting = profiles_lasting(problems, blocks, T)
        if lasting is not None:
            return T, lasting
        T += ts
    raise ValueError(f"no multiple of ts = {ts!r} s near the move's duration {T0!r} s is possible for every axis")
