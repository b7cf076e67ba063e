"""``plan``: jerk-limited multi-axis moves that leave every mode ringing less than a bound.

The kernel is ``shapefmu.runtime.jerk_planner`` (standard library only, what an FMU runs); this
module checks the user's input, converts modes from Hz, and returns a ``Trajectory``: its
duration, the phases of every axis, samples at a period, and the residual of every mode.

Definitions (``runtime.jerk_vibration`` derives them):

- the residual of a mode is the amplitude the mode rings with after the move, A = |S| /
  (omega^2 omega_d), S the sum of the jerk steps each turned and damped to the end of the move;
- "percent of the unshaped one" is max over the band of A(move) / max over the band of A(rigid),
  the rigid move being the time-optimal one (equal to Ruckig's) from the same state to the same
  target: the worst case over the band of each, never a ratio per frequency (the rigid move can
  leave no vibration at some frequency of the band, and a ratio there would be 0 / 0);
- "Ruckig followed by a shaper" (the ceiling) convolves the rigid move's jerk with the shortest
  catalog shaper (its own residual within vtol over the band) with which the shaped move meets the
  limits and the bound; from a moving start the shaper filters the jerk, so the shaped move starts
  in the same state, and the rigid target is moved (a fixed point) so that the shaped move ends in
  the target. From a moving start it can fail the limits (the shaper keeps part of the initial
  acceleration on for its length) or the bound (its rigid move is not the reference one): the
  ceiling is then infinite, and the planner's move is checked against the bound all the same.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

from shapefmu.runtime import jerk_planner, jerk_vibration
from shapefmu.runtime.checks import check_finite, check_positive, check_size, check_vtol, check_zeta
from shapefmu.runtime.jerk_profiles import Limits, Phases

MAX_AXES = 16
MAX_MODES_PER_AXIS = 4


@dataclass(frozen=True)
class AxisLimits:
    """Velocity, acceleration, jerk limits of an axis; v_min, a_min (negative) default to -v_max, -a_max."""

    v_max: float
    a_max: float
    j_max: float
    v_min: float | None = None
    a_min: float | None = None


@dataclass(frozen=True)
class Mode:
    """A mode of an axis: frequency ``hz``, damping ratio ``zeta``."""

    hz: float
    zeta: float


@dataclass(frozen=True)
class ModeResidual:
    """The residual of one mode after a move: amplitudes (worst over the band) of the move and of
    the rigid move, and their ratio (the bound is ``ratio <= vtol``)."""

    axis: str
    hz: float
    zeta: float
    amplitude: float
    rigid_amplitude: float

    @property
    def ratio(self) -> float:
        return self.amplitude / self.rigid_amplitude if self.rigid_amplitude > 0.0 else 0.0


@dataclass(frozen=True)
class Trajectory:
    """A planned move of named axes: ``duration`` s, per axis the constant-jerk phases from its
    start state, how it was found (``method``: rigid, cancel or shaped), the rigid (Ruckig-equal)
    duration, the ceiling (rigid move followed by the shortest catalog shaper per axis, with the
    shapers' names), the residual of every mode, the computation time, and what a re-plan needs."""

    axes: tuple[str, ...]
    duration: float
    phases: tuple[tuple[tuple[float, float, float], tuple[float, ...], tuple[float, ...]], ...]
    method: str
    rigid_duration: float
    ceiling_duration: float
    ceiling_shapers: tuple[str | None, ...]
    residuals: tuple[ModeResidual, ...]
    compute_seconds: float
    request: tuple = field(default=(), compare=False, repr=False)

    def _phases(self) -> list[Phases]:
        return [Phases(*start, durations, jerks) for start, durations, jerks in self.phases]

    def state(self, t: float) -> dict[str, tuple[float, float, float, float]]:
        """{axis: (position, velocity, acceleration, jerk)} at time t from the start."""
        return {name: phases.state(t) for name, phases in zip(self.axes, self._phases())}

    def sample(self, ts: float) -> dict[str, list[float]]:
        """Columns ``time``, ``<axis>.position``, ``.velocity``, ``.acceleration``, ``.jerk`` at t = k ts
        from 0 through the end (the last sample at or after the end)."""
        ts = check_positive(ts, "ts")
        count = check_size(math.ceil(self.duration / ts - 1e-9) + 1, "MAX_SAMPLED_LENGTH",
                           f"a move of {self.duration:.6g} s sampled at ts = {ts!r} s has", "samples",
                           "use a longer ts")
        times = [k * ts for k in range(count)]
        columns = {"time": times}
        for name, phases in zip(self.axes, self._phases()):
            states = [phases.state(t) for t in times]
            for index, quantity in enumerate(("position", "velocity", "acceleration", "jerk")):
                columns[f"{name}.{quantity}"] = [s[index] for s in states]
        return columns

    def to_csv(self, ts: float) -> str:
        columns = self.sample(ts)
        names = list(columns)
        lines = [",".join(names)]
        for row in zip(*columns.values()):
            lines.append(",".join(f"{value:.17g}" for value in row))
        return "\n".join(lines) + "\n"

    def replan(self, t: float, target) -> Trajectory:
        """The move re-planned at time t (a sample instant) from this move's state there to a new
        ``target``, with the same limits and modes; the ringing this move has left in the modes by
        then is part of what the new move cancels."""
        t = check_finite(t, "t")
        if not 0.0 <= t <= self.duration:
            raise ValueError(f"t must be in [0, {self.duration!r}], got {t!r}")
        limits, modes, options, ringing = self.request
        state = [(p, v, a) for p, v, a, _ in self.state(t).values()]
        history = []
        for phases, before in zip(self._phases(), ringing):
            cut = _truncated(phases, t)
            history.append(_history(cut, t, before))
        return _plan(self.axes, state, target, limits, modes, options, history)


def _truncated(phases: Phases, t: float) -> Phases:
    durations, jerks, elapsed = [], [], 0.0
    for d, j in zip(phases.durations, phases.jerks):
        if elapsed >= t:
            break
        durations.append(min(d, t - elapsed))
        jerks.append(j)
        elapsed += d
    if elapsed < t:
        durations.append(t - elapsed)
        jerks.append(0.0)
    return Phases(phases.p[0], phases.v[0], phases.a[0], durations, jerks)


def _history(cut: Phases, t: float, before):
    return lambda omega, zeta: jerk_vibration.jerk_sum(cut.durations, cut.jerks, t, omega, zeta, before)


def _axis_state(value, name, what):
    if isinstance(value, (int, float)):
        return (check_finite(value, f"{what} of axis {name}"), 0.0, 0.0)
    values = tuple(value)
    if not 1 <= len(values) <= 3:
        raise ValueError(f"{what} of axis {name} must be a position or (position, velocity[, acceleration]), "
                         f"got {value!r}")
    values = values + (0.0,) * (3 - len(values))
    return tuple(check_finite(x, f"{what} of axis {name}") for x in values)


def _axis_limits(value, name) -> Limits:
    if not isinstance(value, AxisLimits):
        value = AxisLimits(*value)
    v_max = check_positive(value.v_max, f"v_max of axis {name}")
    a_max = check_positive(value.a_max, f"a_max of axis {name}")
    j_max = check_positive(value.j_max, f"j_max of axis {name}")
    v_min = -v_max if value.v_min is None else check_finite(value.v_min, f"v_min of axis {name}")
    a_min = -a_max if value.a_min is None else check_finite(value.a_min, f"a_min of axis {name}")
    if v_min >= 0.0:
        raise ValueError(f"v_min of axis {name} must be < 0, got {value.v_min!r}")
    if a_min >= 0.0:
        raise ValueError(f"a_min of axis {name} must be < 0, got {value.a_min!r}")
    return Limits(v_max, a_max, j_max, v_min, a_min)


def _check_target(target, lim: Limits, name):
    _, v, a = target
    if not lim.a_min <= a <= lim.a_max:
        raise ValueError(f"target acceleration of axis {name} must be in [{lim.a_min!r}, {lim.a_max!r}], got {a!r}")
    arrival = v - a * abs(a) / (2.0 * lim.j_max)
    if not lim.v_min <= v <= lim.v_max or not lim.v_min <= arrival <= lim.v_max:
        raise ValueError(f"unreachable target: axis {name} cannot arrive at velocity {v!r} with acceleration {a!r} "
                         f"within [{lim.v_min!r}, {lim.v_max!r}] (the velocity before the last jerk ramp would be "
                         f"{arrival!r})")


def _modes(modes, names, band, vtol):
    """Per axis the runtime modes: ``modes`` maps an axis name to (hz, zeta) pairs, or is one
    sequence shared by every axis."""
    band = check_finite(band, "band")
    if not 0.0 <= band < 0.5:
        raise ValueError(f"band must be in [0, 0.5), got {band!r}")
    vtol = check_vtol(vtol)
    if isinstance(modes, dict):
        unknown = set(modes) - set(names)
        if unknown:
            raise ValueError(f"modes name unknown axes {sorted(unknown)}; the axes are {list(names)}")
        per_axis = [list(modes.get(name, ())) for name in names]
    else:
        per_axis = [list(modes) for _ in names]
    out = []
    for name, axis_modes in zip(names, per_axis):
        if len(axis_modes) > MAX_MODES_PER_AXIS:
            raise ValueError(f"axis {name} has {len(axis_modes)} modes, more than the limit of {MAX_MODES_PER_AXIS}")
        converted = []
        for mode in axis_modes:
            hz, zeta = (mode.hz, mode.zeta) if isinstance(mode, Mode) else mode
            hz = check_positive(hz, f"mode frequency of axis {name}")
            zeta = check_zeta(zeta, f"mode damping ratio of axis {name}")
            converted.append(jerk_vibration.Mode(2.0 * math.pi * hz, zeta, band, vtol))
        out.append(converted)
    return out


def plan(state, target, limits, modes=(), *, names=None, band: float = 0.0, vtol: float = 0.01,
         straight: bool = False, ts: float | None = None) -> Trajectory:
    """The move of every axis from ``state`` to ``target`` within ``limits``, ending together,
    leaving each mode's residual within ``vtol`` of the rigid move's over its band (+- ``band``).

    ``state`` and ``target``: per axis a position or (position, velocity, acceleration).
    ``limits``: per axis ``AxisLimits`` or (v_max, a_max, j_max[, v_min, a_min]). ``modes``: a
    sequence of (hz, zeta) shared by every axis, or a dict axis name -> such a sequence.
    ``straight``: along the straight line between the positions. ``ts``: a duration that is a
    whole number of sampling periods.
    """
    count = len(state)
    if not 1 <= count <= MAX_AXES:
        raise ValueError(f"the number of axes must be in [1, {MAX_AXES}], got {count}")
    names = tuple(names) if names is not None else tuple(f"axis{i}" for i in range(count))
    if len(names) != count or len(target) != count or len(limits) != count:
        raise ValueError(f"state, target, limits and names must have one entry per axis, got {count}, {len(target)}, "
                         f"{len(limits)}, {len(names)}")
    runtime_limits = [_axis_limits(value, name) for value, name in zip(limits, names)]
    runtime_modes = _modes(modes, names, band, vtol)
    if ts is not None:
        ts = check_positive(ts, "ts")
    options = {"straight": bool(straight), "ts": ts}
    return _plan(names, state, target, runtime_limits, runtime_modes, options, [None] * count)


def _plan(names, state, target, limits, modes, options, ringing) -> Trajectory:
    states = [_axis_state(value, name, "state") for value, name in zip(state, names)]
    targets = [_axis_state(value, name, "target") for value, name in zip(target, names)]
    for value, lim, name in zip(targets, limits, names):
        _check_target(value, lim, name)
    started = time.perf_counter()
    move = jerk_planner.plan_move(states, targets, limits, modes, options["straight"], options["ts"], ringing)
    elapsed = time.perf_counter() - started
    residuals = tuple(
        ModeResidual(name, m.omega / (2.0 * math.pi), m.zeta, amplitude, reference)
        for name, axis_modes, amps, refs in zip(names, modes, move.residuals, move.references)
        for m, amplitude, reference in zip(axis_modes, amps, refs))
    phases = tuple(((p.p[0], p.v[0], p.a[0]), tuple(p.durations), tuple(p.jerks)) for p in move.phases)
    shapers = tuple(None if s is None else s[0] for s in move.ceiling)
    return Trajectory(tuple(names), move.duration, phases, move.method, move.rigid_duration, move.ceiling_duration,
                      shapers, residuals, elapsed, (limits, modes, options, ringing))


