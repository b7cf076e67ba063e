"""The C twin of the motion planner (``c/jerk_*.c``, interface ``c/jerk_planner.h``) compiled as a shared library and called
through ctypes: what the tests compare with the Python kernel (``runtime.jerk_planner``) and what the
benchmark times beside Ruckig. The FMU that will carry it waits for the FMU kinds of issue 33.

``plan(states, targets, limits, modes, ...)`` takes the runtime kernel's arguments
(``Limits``, ``jerk_vibration.Mode``) and returns a ``runtime.jerk_planner.PlannedMove``; the ceiling's
shapers, which depend only on the modes, are designed here in Python first
(``runtime.jerk_planner.catalog_shapers``), as a native FMU designs them at build time.
"""

from __future__ import annotations

import ctypes
import functools
import math
import tempfile
import threading
from pathlib import Path

from shapefmu.fmi.compiler import run_compiler
from shapefmu.runtime.jerk_planner import MAX_CEILING_SHAPERS, PlannedMove, catalog_shapers
from shapefmu.runtime.jerk_profiles import Phases

SOURCES = [Path(__file__).parent / "c" / f"jerk_{part}.c" for part in ("axis", "sync", "vibration", "planner")]
MAX_AXES, MAX_MODES, MAX_PHASES, MAX_IMPULSES, MAX_SHAPERS = 8, 4, 256, 64, MAX_CEILING_SHAPERS
METHODS = ("rigid", "cancel", "shaped")


class _Limits(ctypes.Structure):
    _fields_ = [(name, ctypes.c_double) for name in ("v_max", "v_min", "a_max", "a_min", "j_max")]


class _Mode(ctypes.Structure):
    _fields_ = [(name, ctypes.c_double) for name in ("omega", "zeta", "delta", "vtol")]


class _Shaper(ctypes.Structure):
    _fields_ = [("count", ctypes.c_int), ("times", ctypes.c_double * MAX_IMPULSES),
                ("amplitudes", ctypes.c_double * MAX_IMPULSES)]


class _AxisPhases(ctypes.Structure):
    _fields_ = [("count", ctypes.c_int), ("start", ctypes.c_double * 3), ("durations", ctypes.c_double * MAX_PHASES),
                ("jerks", ctypes.c_double * MAX_PHASES)]


class _Request(ctypes.Structure):
    _fields_ = [("axes", ctypes.c_int), ("states", (ctypes.c_double * 3) * MAX_AXES),
                ("targets", (ctypes.c_double * 3) * MAX_AXES), ("limits", _Limits * MAX_AXES),
                ("mode_count", ctypes.c_int * MAX_AXES), ("modes", (_Mode * MAX_MODES) * MAX_AXES),
                ("ceiling_count", ctypes.c_int * MAX_AXES), ("ceiling", (_Shaper * MAX_SHAPERS) * MAX_AXES),
                ("straight", ctypes.c_int), ("ts", ctypes.c_double),
                ("history", ctypes.POINTER(_AxisPhases))]


class _Result(ctypes.Structure):
    _fields_ = [("duration", ctypes.c_double), ("rigid_duration", ctypes.c_double),
                ("ceiling_duration", ctypes.c_double), ("method", ctypes.c_int),
                ("ceiling_choice", ctypes.c_int * MAX_AXES), ("phases", _AxisPhases * MAX_AXES),
                ("references", (ctypes.c_double * MAX_MODES) * MAX_AXES),
                ("residuals", (ctypes.c_double * MAX_MODES) * MAX_AXES), ("message", ctypes.c_char * 256)]


@functools.lru_cache(maxsize=1)
def library() -> ctypes.CDLL:
    """The compiled twin (gcc -O2), built once per process in a temporary folder."""
    folder = Path(tempfile.mkdtemp(prefix="shapefmu-jerk-planner-"))
    target = folder / "libjerk_planner.so"
    done = run_compiler(["gcc", "-O2", "-std=c99", "-Wall", "-Wextra", "-Werror", "-shared", "-fPIC", "-o", str(target),
                         *map(str, SOURCES), "-lm"])
    if done.returncode != 0:
        raise RuntimeError(f"compiling the C planner failed: {done.stderr}")
    lib = ctypes.CDLL(str(target))
    lib.jp_workspace_new.argtypes = []
    lib.jp_workspace_new.restype = ctypes.c_void_p
    lib.jp_workspace_free.argtypes = [ctypes.c_void_p]
    lib.jp_workspace_free.restype = None
    lib.jp_plan.argtypes = [ctypes.POINTER(_Request), ctypes.POINTER(_Result), ctypes.c_void_p]
    lib.jp_plan.restype = ctypes.c_int
    lib.jp_rigid_duration.argtypes = [ctypes.POINTER(_Request), ctypes.POINTER(ctypes.c_double), ctypes.c_char_p,
                                      ctypes.c_int, ctypes.c_void_p]
    lib.jp_rigid_duration.restype = ctypes.c_int
    return lib


class _Workspace:
    """The buffers plans work in (``jp_workspace_new``), freed with the object; every thread plans in
    its own (``_workspace``), so threads plan at the same time (ctypes releases the GIL)."""

    def __init__(self):
        self.lib = library()
        self.pointer = self.lib.jp_workspace_new()
        if not self.pointer:
            raise MemoryError("the C planner's workspace could not be allocated")

    def __del__(self):
        if getattr(self, "pointer", None):
            self.lib.jp_workspace_free(self.pointer)
            self.pointer = None


_per_thread = threading.local()


def _workspace() -> _Workspace:
    """This thread's workspace."""
    if not hasattr(_per_thread, "workspace"):
        _per_thread.workspace = _Workspace()
    return _per_thread.workspace


def _request(states, targets, limits, modes=None, shapers=None, straight=False, ts=None, history=None) -> _Request:
    count = len(states)
    if not 1 <= count <= MAX_AXES:
        raise ValueError(f"the number of axes must be in [1, {MAX_AXES}], got {count}")
    request = _Request()
    request.axes = count
    for i, (state, target, lim) in enumerate(zip(states, targets, limits)):
        request.states[i][:] = list(map(float, state))
        request.targets[i][:] = list(map(float, target))
        request.limits[i] = _Limits(lim.v_max, lim.v_min, lim.a_max, lim.a_min, lim.j_max)
        axis_modes = modes[i] if modes else []
        if len(axis_modes) > MAX_MODES:
            raise ValueError(f"axis {i} has {len(axis_modes)} modes, more than the C twin's {MAX_MODES}")
        request.mode_count[i] = len(axis_modes)
        for q, mode in enumerate(axis_modes):
            request.modes[i][q] = _Mode(mode.omega, mode.zeta, mode.delta, mode.vtol)
        options = [shaper for shaper in (shapers[i] if shapers else []) if len(shaper[1]) <= MAX_IMPULSES]
        request.ceiling_count[i] = len(options[:MAX_SHAPERS])
        for k, (_, times, amplitudes) in enumerate(options[:MAX_SHAPERS]):
            request.ceiling[i][k].count = len(times)
            request.ceiling[i][k].times[: len(times)] = times
            request.ceiling[i][k].amplitudes[: len(times)] = amplitudes
    request.straight = int(bool(straight))
    request.ts = float(ts) if ts is not None else 0.0
    if history is not None:
        axes = (_AxisPhases * count)()
        for i, phases in enumerate(history):
            if len(phases.durations) > MAX_PHASES:
                raise ValueError(f"the history of axis {i} has more than {MAX_PHASES} phases")
            axes[i].count = len(phases.durations)
            axes[i].durations[: len(phases.durations)] = phases.durations
            axes[i].jerks[: len(phases.jerks)] = phases.jerks
        request.history = ctypes.cast(axes, ctypes.POINTER(_AxisPhases))
        request._history_keepalive = axes
    return request


def rigid_duration(states, targets, limits) -> float:
    """The synchronised rigid duration (Ruckig's) computed by the twin."""
    request = _request(states, targets, limits)
    duration, message = ctypes.c_double(), ctypes.create_string_buffer(256)
    if library().jp_rigid_duration(ctypes.byref(request), ctypes.byref(duration), message, 256,
                                   _workspace().pointer) != 0:
        raise ValueError(message.value.decode())
    return duration.value


def ceiling_shapers(states, targets, limits, modes):
    """Per axis the catalog shapers of its modes, shortest first (``catalog_shapers``, designed with
    the rigid duration as ``runtime.jerk_planner.shaped_move`` does); [] for an axis without modes."""
    T0 = rigid_duration(states, targets, limits)
    return [catalog_shapers(axis_modes, T0) if axis_modes else [] for axis_modes in modes]


def plan(states, targets, limits, modes, straight=False, ts=None, history=None, shapers=None) -> PlannedMove:
    """``runtime.jerk_planner.plan_move`` in C, in this thread's workspace. ``history``: per axis the
    ``Phases`` of the jerk since the first start (a re-plan); ``shapers`` the ceiling's candidates
    (``ceiling_shapers`` by default)."""
    if shapers is None and any(modes):
        shapers = ceiling_shapers(states, targets, limits, modes)
    request = _request(states, targets, limits, modes, shapers, straight, ts, history)
    result = _Result()
    if library().jp_plan(ctypes.byref(request), ctypes.byref(result), _workspace().pointer) != 0:
        raise ValueError(result.message.decode())
    phases = []
    for i in range(len(states)):
        axis = result.phases[i]
        phases.append(Phases(*axis.start, list(axis.durations[: axis.count]), list(axis.jerks[: axis.count])))
    counts = [len(m) for m in modes] if modes else [0] * len(states)
    references = [list(result.references[i][:c]) for i, c in enumerate(counts)]
    residuals = [list(result.residuals[i][:c]) for i, c in enumerate(counts)]
    ceiling_duration = result.ceiling_duration if math.isfinite(result.ceiling_duration) else math.inf
    ceiling = [None] * len(states)
    if shapers is not None and math.isfinite(ceiling_duration):
        ceiling = [options[result.ceiling_choice[i]] if options else None for i, options in enumerate(shapers)]
    return PlannedMove(result.duration, phases, METHODS[result.method], result.rigid_duration, references, residuals,
                       ceiling, ceiling_duration)
