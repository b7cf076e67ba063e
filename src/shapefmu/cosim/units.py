"""One FMU instance inside the master: raw FMI 2.0 calls on preallocated ctypes arrays.

fmpy's high-level ``getReal``/``setReal`` build new ctypes arrays on every call; the master calls the
FMU's C functions directly (the ctypes function objects fmpy prepared, with their argtypes) on
arrays allocated once per run, with one batched call per component and macro step for its inputs
and one for the values it must read (connected outputs plus recorded variables).

A Co-Simulation FMU steps itself (``fmi2DoStep``). A Model Exchange FMU is integrated by the master
over each macro step with fmpy's SUNDIALS CVode (BDF, dense Newton), holding its inputs constant
over the step (zero-order hold, as a Co-Simulation FMU sees them), locating state events by root
finding on the event indicators, and handling time events and step events with the FMI 2.0 event
iteration (``fmi2NewDiscreteStates`` until no new discrete states are needed).
"""

from __future__ import annotations

import collections
import math
from ctypes import byref, c_double, c_int, c_size_t, c_uint, c_void_p
from pathlib import Path

from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi2 import (
    FMU2Model,
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2FMUstate,
)
from fmpy.fmi1 import printLogMessage

STATUS_NAMES = {0: "fmi2OK", 1: "fmi2Warning", 2: "fmi2Discard", 3: "fmi2Error", 4: "fmi2Fatal", 5: "fmi2Pending"}

# fmpy's logger proxy (fmpy.logging.addLoggerProxy) formats an FMU's C varargs message and then calls
# ONE process-wide Python callback: the last one registered, whichever instance logs. A callback
# registered per unit dies with its unit, and the next FMU in the process that logs through the
# proxy (fmpy's own default callbacks included) calls freed memory: a segfault. The master registers
# one callback that lives as long as the process and finds the unit's queue by componentEnvironment;
# a message from an instance that is not the master's is printed, as fmpy's default logger does.
_MESSAGE_QUEUES: dict[int, collections.deque] = {}


def _log_to_queue(environment, instance, status, category, message):
    queue = _MESSAGE_QUEUES.get(environment or 0)
    if queue is None:
        printLogMessage(environment, instance, status, category, message)
    else:
        queue.append(f"[{STATUS_NAMES.get(status, status)}] {(message or b'').decode(errors='replace')}")


_LOGGER = fmi2CallbackLoggerTYPE(_log_to_queue)


class FMUFailure(Exception):
    """An FMI call returned a status worse than fmi2Warning; the master adds time and results."""

    def __init__(self, unit: Unit, call: str, status: int | str, time: float | None = None):
        self.unit = unit
        self.call = call
        self.status = STATUS_NAMES.get(status, status)
        self.time = time
        super().__init__(f"{call} returned {self.status}")


class Unit:
    """A Co-Simulation FMU instance (Model Exchange: see :class:`ModelExchangeUnit`)."""

    interface = "CoSimulation"

    def __init__(self, name: str, fmu_path: Path, unzip_directory: str, description):
        self.name = name
        self.fmu_path = Path(fmu_path)
        self.description = description
        self.variables = {v.name: v for v in description.modelVariables}
        self.messages: collections.deque[str] = collections.deque(maxlen=20)
        self._callbacks = self._make_callbacks()
        self.fmu = self._make_fmu(unzip_directory)
        self.fmu.instantiate(callbacks=self._callbacks, loggingOn=False)
        dll = self.fmu.dll
        # The per-step calls go through argument-less function pointers on prebuilt ctypes objects:
        # fmpy's argtypes make ctypes convert every argument on every call, which costs about as
        # much as a native FMU's whole step (~0.5 us of ~1 us per call, measured).
        self.c = c_void_p(self.fmu.component)
        self.set_real = _raw(dll, "fmi2SetReal")
        self.get_real = _raw(dll, "fmi2GetReal")
        self.do_step = _raw(dll, "fmi2DoStep")
        self.time_arg, self.step_arg = c_double(), c_double()
        self.can_roll_back = bool(self._capabilities().canGetAndSetFMUstate)
        self._state = fmi2FMUstate()
        self.configure([], [])

    # ----------------------------------------------------------------------------- set-up
    def _make_fmu(self, unzip_directory):
        return FMU2Slave(guid=self.description.guid, unzipDirectory=unzip_directory,
                         modelIdentifier=self.description.coSimulation.modelIdentifier, instanceName=self.name)

    def _capabilities(self):
        return self.description.coSimulation

    def _make_callbacks(self):
        callbacks = fmi2CallbackFunctions()
        callbacks.logger = _LOGGER
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        callbacks.componentEnvironment = id(self.messages)  # registered until free()
        _MESSAGE_QUEUES[id(self.messages)] = self.messages
        try:  # formats the C varargs message before it reaches Python
            from fmpy.logging import addLoggerProxy

            addLoggerProxy(byref(callbacks))
        except Exception:  # noqa: BLE001 - without the proxy messages arrive unformatted, still useful
            pass
        return callbacks

    def variable(self, name: str):
        variable = self.variables.get(name)
        if variable is None:
            raise ValueError(f"component {self.name!r} ({self.fmu_path.name}) has no variable {name!r}")
        return variable

    def configure(self, inputs: list[str], reads: list[str]) -> None:
        """Allocate the batched arrays: ``inputs`` set before each step, ``reads`` read after it."""
        for name in (*inputs, *reads):
            if self.variable(name).type != "Real":
                raise ValueError(f"{self.name}.{name} is {self.variable(name).type}; the master connects and records Real variables only")
        self.inputs, self.reads = list(inputs), list(reads)
        self.n_in, self.n_out = len(inputs), len(reads)
        self.n_in_arg, self.n_out_arg = c_size_t(self.n_in), c_size_t(self.n_out)
        self.in_vr = (c_uint * max(1, self.n_in))(*[self.variables[n].valueReference for n in inputs])
        self.in_val = (c_double * max(1, self.n_in))()
        self.out_vr = (c_uint * max(1, self.n_out))(*[self.variables[n].valueReference for n in reads])
        self.out_val = (c_double * max(1, self.n_out))()

    # ----------------------------------------------------------------------------- calls
    def check(self, status: int, call: str) -> None:
        if status > 1:
            raise FMUFailure(self, call, status)

    def set_inputs(self) -> None:
        if self.n_in:
            self.check(self.set_real(self.c, self.in_vr, self.n_in_arg, self.in_val), "fmi2SetReal")

    def read(self) -> None:
        if self.n_out:
            self.check(self.get_real(self.c, self.out_vr, self.n_out_arg, self.out_val), "fmi2GetReal")

    def apply_values(self, values: dict) -> None:
        """Set start values/parameters by name, each with the setter of its type."""
        for name, value in values.items():
            variable = self.variable(name)
            vr = [variable.valueReference]
            try:
                if variable.type == "Real":
                    self.fmu.setReal(vr, [float(value)])
                elif variable.type in ("Integer", "Enumeration"):
                    self.fmu.setInteger(vr, [int(value)])
                elif variable.type == "Boolean":
                    self.fmu.setBoolean(vr, [bool(value)])
                else:
                    self.fmu.setString(vr, [str(value)])
            except Exception as error:  # fmpy raises FMICallException on a bad status
                raise FMUFailure(self, f"fmi2Set{variable.type}({name}={value!r})", str(error)) from None

    def setup(self, start_time: float) -> None:
        self._call("fmi2SetupExperiment", self.fmu.setupExperiment, startTime=start_time)

    def enter_initialization(self) -> None:
        self._call("fmi2EnterInitializationMode", self.fmu.enterInitializationMode)

    def exit_initialization(self, start_time: float, tolerance: float) -> None:
        self._call("fmi2ExitInitializationMode", self.fmu.exitInitializationMode)

    def reset(self) -> None:
        self._call("fmi2Reset", self.fmu.reset)

    def step(self, t: float, h: float) -> None:
        self.time_arg.value, self.step_arg.value = t, h
        status = self.do_step(self.c, self.time_arg, self.step_arg, 0)
        if status > 1:
            raise FMUFailure(self, "fmi2DoStep", status, time=t)

    def save_state(self) -> None:
        self.check(self.fmu.dll.fmi2GetFMUstate(self.c, byref(self._state)), "fmi2GetFMUstate")

    def restore_state(self) -> None:
        self.check(self.fmu.dll.fmi2SetFMUstate(self.c, self._state), "fmi2SetFMUstate")

    def _call(self, call: str, function, *args, **kwargs):
        try:
            return function(*args, **kwargs)
        except FMUFailure:
            raise
        except Exception as error:  # fmpy's FMICallException, CVode's RuntimeError
            raise FMUFailure(self, call, str(error)) from None

    def free(self) -> None:
        if self.fmu is None:
            return
        if self._state:
            self.fmu.dll.fmi2FreeFMUstate(self.c, byref(self._state))
        try:
            self.fmu.terminate()
        except Exception:  # noqa: BLE001 - terminating after an error may itself fail; free anyway
            pass
        self.fmu.freeInstance()
        self.fmu = None
        _MESSAGE_QUEUES.pop(id(self.messages), None)


def _raw(dll, name: str):
    """The exported C function ``name`` (None if absent) returning int, without argtypes: callers
    pass ctypes objects (c_void_p, c_size_t, c_double, arrays) that need no conversion."""
    try:
        getattr(dll, name)
    except AttributeError:
        return None
    function = dll._FuncPtr((name, dll))
    function.restype = c_int
    return function


class _HeldInputs:
    """fmpy's CVode calls ``input.apply(t)`` at root evaluations; inputs are held over the step."""

    def apply(self, time, continuous=True, discrete=True, after_event=False):
        return None


class ModelExchangeUnit(Unit):
    """A Model Exchange FMU integrated by the master with CVode (see the module docstring)."""

    interface = "ModelExchange"

    def _make_fmu(self, unzip_directory):
        return FMU2Model(guid=self.description.guid, unzipDirectory=unzip_directory,
                         modelIdentifier=self.description.modelExchange.modelIdentifier, instanceName=self.name)

    def _capabilities(self):
        return self.description.modelExchange

    def configure(self, inputs, reads):
        super().configure(inputs, reads)
        self._held = [math.nan] * self.n_in

    def exit_initialization(self, start_time: float, tolerance: float) -> None:
        from fmpy.sundials import CVodeSolver

        super().exit_initialization(start_time, tolerance)
        self.time = start_time
        self._event_iteration()
        self._call("fmi2EnterContinuousTimeMode", self.fmu.enterContinuousTimeMode)
        fmu, description = self.fmu, self.description
        self.solver = CVodeSolver(
            nx=description.numberOfContinuousStates, nz=description.numberOfEventIndicators,
            get_x=fmu.getContinuousStates, set_x=fmu.setContinuousStates, get_dx=fmu.getDerivatives,
            get_z=fmu.getEventIndicators, get_nominals=fmu.getNominalsOfContinuousStates,
            set_time=fmu.setTime, input=_HeldInputs(), startTime=start_time,
            relativeTolerance=tolerance, maxNumSteps=100000,
        )
        self._held = [math.nan] * self.n_in

    def _event_iteration(self) -> None:
        """fmi2NewDiscreteStates until the FMU needs no more; remember its next time event."""
        needed, terminate = True, False
        while needed and not terminate:
            needed, terminate, _, _, defined, next_time = self._call("fmi2NewDiscreteStates", self.fmu.newDiscreteStates)
        if terminate:
            raise FMUFailure(self, "fmi2NewDiscreteStates", "terminateSimulation")
        self.next_event_time = next_time if defined else math.inf

    def step(self, t: float, h: float) -> None:
        try:
            self._integrate(t, h)
        except FMUFailure as failure:
            failure.time = t if failure.time is None else failure.time
            raise

    def _integrate(self, t: float, h: float) -> None:
        held = list(self.in_val[: self.n_in])
        if held != self._held:
            # A changed input is a discontinuity of the right-hand side: restart the integrator
            # there rather than let it interpolate across the jump.
            self._held = held
            self.solver.reset(t)
        time, t_end = t, t + h
        tiny = 1e-13 * max(1.0, abs(t_end))
        while t_end - time > tiny:
            t_next = min(t_end, self.next_event_time)
            state_event, _, time = self._call("CVode", self.solver.step, time, t_next)
            self._call("fmi2SetTime", self.fmu.setTime, time)
            step_event, terminate = self._call("fmi2CompletedIntegratorStep", self.fmu.completedIntegratorStep)
            if terminate:
                raise FMUFailure(self, "fmi2CompletedIntegratorStep", "terminateSimulation")
            time_event = abs(time - self.next_event_time) <= tiny
            if state_event or step_event or time_event:
                self._call("fmi2EnterEventMode", self.fmu.enterEventMode)
                self._event_iteration()
                self._call("fmi2EnterContinuousTimeMode", self.fmu.enterContinuousTimeMode)
                self.solver.reset(time)
        self.time = t_end

    def save_state(self) -> None:
        super().save_state()
        self._saved_time = self.time

    def restore_state(self) -> None:
        super().restore_state()
        self.time = self._saved_time
        self._held = [math.nan] * self.n_in  # re-initialise the integrator at the restored point


def load_units(components: list[tuple[str, Path]], model_exchange: set[str]) -> tuple[list[Unit], list[str]]:
    """Instantiate every (name, fmu) pair; each FMU file is extracted once and shared by its instances."""
    extracted: dict[Path, tuple[str, object]] = {}
    units, folders = [], []
    try:
        for name, fmu in components:
            fmu = Path(fmu).resolve()
            if fmu not in extracted:
                description = read_model_description(str(fmu), validate=False)
                folder = extract(str(fmu))
                folders.append(folder)
                extracted[fmu] = (folder, description)
            folder, description = extracted[fmu]
            if description.fmiVersion != "2.0":
                raise ValueError(f"component {name!r}: {fmu.name} is FMI {description.fmiVersion}; the master runs FMI 2.0")
            if name in model_exchange:
                if description.modelExchange is None:
                    raise ValueError(f"component {name!r}: {fmu.name} has no Model Exchange interface")
                units.append(ModelExchangeUnit(name, fmu, folder, description))
            elif description.coSimulation is not None:
                units.append(Unit(name, fmu, folder, description))
            elif description.modelExchange is not None:
                units.append(ModelExchangeUnit(name, fmu, folder, description))
            else:
                raise ValueError(f"component {name!r}: {fmu.name} has neither a Co-Simulation nor a Model Exchange interface")
    except BaseException:
        for unit in units:
            unit.free()
        raise
    return units, folders

