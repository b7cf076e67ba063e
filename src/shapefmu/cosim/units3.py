"""FMI 3.0 components of the master: the FMI 2.0 units of :mod:`.units` over fmpy's FMI 3 API.

The master treats both versions alike (batched value arrays per family, the same step loop); what
differs is said here: instantiation (``fmi3InstantiateCoSimulation`` without event mode, early
return or intermediate updates; ``fmi3InstantiateModelExchange``), initialisation
(``fmi3EnterInitializationMode`` takes the start time), the step (``fmi3DoStep`` reports a request
to end the simulation in ``terminateSimulation``, and the time reached in ``lastSuccessfulTime``),
``fmi3UpdateDiscreteStates`` in Model Exchange event iterations, and FMU states.

Clocks: a Co-Simulation FMU with periodic input clocks of constant interval (``intervalDecimal``,
``shiftDecimal``; shapefmu's FMUs built with ``--clock``) is instantiated with Event Mode and its
clocks are ticked at communication points: after initialisation (the FMU is then in Event Mode) and
before every step from a tick, Event Mode, ``fmi3SetClock`` of the clocks ticking then,
``fmi3UpdateDiscreteStates`` until no update is needed, ``fmi3EnterStepMode``. The master checks
that every tick falls on a communication point of the component (``clock_ticks_on_steps``). Other
clocks (output clocks, clocks of other interval variabilities) are refused when the FMU is loaded.
Without clocks a Co-Simulation FMU runs without Event Mode: the master does not handle
``eventHandlingNeeded``, and refuses an FMU that reports it with an error naming the capability.
"""

from __future__ import annotations

import collections
import math
from ctypes import byref, c_bool, c_double, c_uint, c_void_p
from pathlib import Path

from fmpy.fmi3 import FMU3Model, FMU3Slave, fmi3IntermediateUpdateCallback, fmi3LogMessageCallback

from shapefmu.cosim.types import FAMILIES_3
from shapefmu.cosim.units import STATUS_NAMES, FMUFailure, ModelExchangeUnit, Unit, _raw

# As for FMI 2.0 (see units.py): one process-wide logger, finding the unit's queue by its
# instance environment, so no callback dies before an FMU that may still log through it.
_QUEUES: dict[int, collections.deque] = {}


def _log_to_queue(environment, status, category, message):
    queue = _QUEUES.get(environment or 0)
    text = f"[{STATUS_NAMES.get(status, status).replace('fmi2', 'fmi3')}] {(message or b'').decode(errors='replace')}"
    if queue is None:
        print(text)
    else:
        queue.append(text)


_LOGGER = fmi3LogMessageCallback(_log_to_queue)
_NO_INTERMEDIATE_UPDATE = fmi3IntermediateUpdateCallback()


class Unit3(Unit):
    """An FMI 3.0 Co-Simulation FMU instance."""

    fmu_class = FMU3Slave
    fmi3 = True
    prefix = "fmi3"
    real = "Float64"
    family_table = FAMILIES_3
    state_calls = ("fmi3GetFMUState", "fmi3SetFMUState", "fmi3FreeFMUState")
    queues = _QUEUES

    def __init__(self, name: str, fmu_path: Path, unzip_directory: str, description):
        self._name_it(name, fmu_path, description)
        _QUEUES[id(self.messages)] = self.messages
        self.clocks = input_clocks(self.name, self.fmu_path, Path(unzip_directory))
        self.fmu = self._make_fmu(unzip_directory)
        self.fmu.component = self._instantiate()
        if not self.fmu.component:
            _QUEUES.pop(id(self.messages), None)
            raise ValueError(f"component {name!r}: {self.fmu_path.name} could not be instantiated"
                             + (f"; FMU log: {' | '.join(self.messages)}" if self.messages else ""))
        self.c = c_void_p(self.fmu.component)
        self.do_step = _raw(self.fmu.dll, "fmi3DoStep")
        self.time_arg, self.step_arg = c_double(), c_double()
        self._flags = (c_bool(), c_bool(), c_bool(), c_double())  # eventHandlingNeeded, terminate, earlyReturn, last
        # fmpy reads FMI 3.0's canGetAndSetFMUState into the FMI 2.0 spelling of the attribute
        self.can_roll_back = bool(self._capabilities().canGetAndSetFMUstate)
        self._state = c_void_p()
        self._start_time = 0.0
        self.configure([], [])

    def _instantiate(self):
        resources = str(Path(self.fmu.unzipDirectory) / "resources") + "/"  # FMI 3.0: a path, not a URI
        return self.fmu.fmi3InstantiateCoSimulation(
            self.name.encode(), self.description.guid.encode(), resources.encode(), False, False,
            bool(self.clocks), False, (c_uint * 0)(), 0, id(self.messages), _LOGGER, _NO_INTERMEDIATE_UPDATE)

    def setup(self, start_time: float) -> None:
        self._start_time = start_time  # FMI 3.0 passes it to fmi3EnterInitializationMode

    def enter_initialization(self) -> None:
        self._call("fmi3EnterInitializationMode", self.fmu.enterInitializationMode, startTime=self._start_time)

    def exit_initialization(self, start_time: float, tolerance: float) -> None:
        super().exit_initialization(start_time, tolerance)
        if self.clocks:  # in Event Mode now (eventModeUsed): the ticks at the start time
            self._tick(start_time, in_event_mode=True)

    def _tick(self, t: float, in_event_mode: bool = False) -> None:
        """Tick the clocks due at ``t`` (an Event Mode of their own, see the module docstring)."""
        # The time since the start as the whole steps it is (the master's t = t0 + k h): t - t0 itself
        # is off by ulps of t0, 2.4e-7 s at a Unix-epoch 1.7e9, far more than a tick's tolerance.
        elapsed = round((t - self._start_time) / self.clock_step) * self.clock_step
        due = [vr for vr, interval, shift in self.clocks if on_tick(elapsed, interval, shift)]
        if not due and not in_event_mode:
            return
        if not in_event_mode:
            self._call("fmi3EnterEventMode", self.fmu.enterEventMode)
        if due:
            self._call("fmi3SetClock", self.fmu.setClock, due, [True] * len(due))
        for _ in range(MAX_EVENT_ITERATIONS):
            more, terminate, *_ = self._call("fmi3UpdateDiscreteStates", self.fmu.updateDiscreteStates)
            if terminate:
                raise FMUFailure(self, "fmi3UpdateDiscreteStates", "terminateSimulation at a clock tick", time=t)
            if not more:
                break
        else:
            raise FMUFailure(self, "fmi3UpdateDiscreteStates", f"discrete states still changing after "
                             f"{MAX_EVENT_ITERATIONS} iterations at a clock tick", time=t)
        self._call("fmi3EnterStepMode", self.fmu.enterStepMode)

    def step(self, t: float, h: float, final: bool = True) -> bool:
        """One fmi3DoStep (after the clock ticks due at ``t``); True when the FMU asked to end the
        simulation (``terminated_at``); ``final``: noSetFMUStatePriorToCurrentPoint (see :meth:`Unit.step`)."""
        if self.clocks and t != self._start_time:
            self._tick(t)
        event, terminate, early, last = self._flags
        status = self.do_step(self.c, c_double(t), c_double(h), c_bool(final), byref(event), byref(terminate),
                              byref(early), byref(last))
        if status > 1 and not (status == 2 and terminate.value):
            raise FMUFailure(self, "fmi3DoStep", status, time=t)
        if event.value and not terminate.value:
            raise FMUFailure(self, "fmi3DoStep", "eventHandlingNeeded (the master runs FMI 3.0 Co-Simulation FMUs "
                             "without event mode)", time=t)
        if terminate.value:
            self.terminated_at = last.value if t <= last.value <= t + h else t + h
            self.termination_call = "fmi3DoStep set terminateSimulation"
            return True
        return False

    def stop_or_fail(self, t: float, h: float, status: int) -> bool:
        raise FMUFailure(self, "fmi3DoStep", status, time=t)


# Event iterations at one tick before the master gives up (the FMU's discrete states keep changing).
MAX_EVENT_ITERATIONS = 100
# A tick falls on a communication point t when |t - tick| <= TICK_TOLERANCE * interval (the rule of
# shapefmu's sample grid, which the master's times t0 + k h meet to rounding).
TICK_TOLERANCE = 1e-6


def on_tick(elapsed: float, interval: float, shift: float) -> bool:
    """Whether a clock of ``interval`` and ``shift`` ticks ``elapsed`` s after the start."""
    k = round((elapsed - shift) / interval)
    return k >= 0 and abs(elapsed - shift - k * interval) <= TICK_TOLERANCE * interval


def input_clocks(name: str, fmu_path: Path, unzip_directory: Path) -> list[tuple[int, float, float]]:
    """(value reference, interval, shift) of each input clock of the FMU; a clock the master cannot
    tick (an output clock, an interval other than a constant decimal one) is refused with a message."""
    import xml.etree.ElementTree as ET

    root = ET.parse(unzip_directory / "modelDescription.xml").getroot()
    clocks = []
    for clock in root.iter("Clock"):
        label = f"component {name!r} ({fmu_path.name}): clock {clock.get('name')!r}"
        if clock.get("causality") != "input" or clock.get("intervalVariability") != "constant":
            raise ValueError(f"{label} is a {clock.get('causality')} clock of interval variability "
                             f"{clock.get('intervalVariability')}; the master ticks input clocks of constant interval only")
        try:
            interval, shift = float(clock.get("intervalDecimal", "")), float(clock.get("shiftDecimal", "0"))
        except ValueError:
            raise ValueError(f"{label} declares no decimal interval (intervalDecimal); the master ticks those only") from None
        if not (interval > 0 and shift >= 0 and math.isfinite(interval + shift)):
            raise ValueError(f"{label}: intervalDecimal must be > 0 and shiftDecimal >= 0, got {interval!r}, {shift!r}")
        clocks.append((int(clock.get("valueReference")), interval, shift))
    return clocks


def clock_ticks_on_steps(unit, step: float) -> None:
    """Every tick of ``unit``'s clocks falls on one of its communication points (multiples of
    ``step``, its macro step times its step multiple), else a ValueError says which and why; the unit
    then counts its ticks by that step (``clock_step``)."""
    for vr, interval, shift in getattr(unit, "clocks", ()):
        for what, value in (("interval", interval), ("shift", shift)):
            ratio = value / step
            if abs(ratio - round(ratio)) > TICK_TOLERANCE * max(1.0, ratio):
                raise ValueError(f"component {unit.name!r}: its clock (value reference {vr}) has {what} {value!r} s, not a "
                                 f"whole number of its communication step {step!r} s; the master ticks clocks at "
                                 f"communication points: choose a step that divides it")
    unit.clock_step = step


class ModelExchangeUnit3(ModelExchangeUnit, Unit3):
    """An FMI 3.0 Model Exchange FMU, integrated by the master as an FMI 2.0 one is."""

    interface = "ModelExchange"
    fmu_class = FMU3Model

    def _instantiate(self):
        resources = str(Path(self.fmu.unzipDirectory) / "resources") + "/"  # FMI 3.0: a path, not a URI
        return self.fmu.fmi3InstantiateModelExchange(self.name.encode(), self.description.guid.encode(),
                                                     resources.encode(), False, False, id(self.messages), _LOGGER)

    def _derivatives_function(self):
        return self.fmu.getContinuousStateDerivatives

    def _discrete_states(self):
        return "fmi3UpdateDiscreteStates", self.fmu.updateDiscreteStates
