"""One FMU instance inside the master: raw FMI 2.0 calls on preallocated ctypes arrays.

fmpy's high-level ``getReal``/``setReal`` build new ctypes arrays on every call; the master calls the
FMU's C functions directly (the ctypes function objects fmpy prepared, with their argtypes) on
arrays allocated once per run, with one batched call per component and macro step for its inputs
and one for the values it must read (connected outputs plus recorded variables).

A Co-Simulation FMU steps itself (``fmi2DoStep``). A Model Exchange FMU is integrated by the master
over each macro step with fmpy's SUNDIALS CVode (BDF, dense Newton), holding its inputs constant
over the step (zero-order hold, as a Co-Simulation FMU sees them), locating state events by root
finding on the event indicators, and handling time events and step events with the FMI 2.0 event
iteration (``fmi2NewDiscreteStates`` until no new discrete states are needed). Its discrete inputs
(variability discrete: every Integer, Boolean, String and Enumeration, and discrete Reals) change
only at events (FMI 2.0 sec. 3.2.3, FMI 3.0 sec. 3.2.2): at a communication point where one of them
changed, the master enters event mode, sets the inputs there and iterates the event, as fmpy does at
the discontinuities of an input table; continuous inputs are set in continuous-time mode.

FMI 3.0 arrays (1-D): a variable's value reference appears once in a batched call and its ``size``
values lie consecutively in the value array, so ``nValues`` is the number of elements over all the
value references, not their number (FMI 3.0's ``nValues`` argument). ``input_slot``/``read_slot`` give a
variable's first value; :meth:`Unit.slots` the values a name (``y``, ``y[2]``) stands for. An array
is set whole: values given for some of its elements set the others to their start values.
"""

from __future__ import annotations

import collections
import math
from ctypes import byref, c_double, c_int, c_size_t, c_uint, c_void_p
from pathlib import Path

from fmpy.fmi2 import FMU2Model, FMU2Slave, fmi2FMUstate

from shapefmu.cosim import fmpy_log
from shapefmu.cosim.types import (FAMILIES_2, Family, array_size, array_values, enumeration_items, family_of, kind_of,
                                  split_element, typed_value)

STATUS_NAMES = {0: "fmi2OK", 1: "fmi2Warning", 2: "fmi2Discard", 3: "fmi2Error", 4: "fmi2Fatal", 5: "fmi2Pending"}


class FMUFailure(Exception):
    """An FMI call returned a status worse than fmi2Warning; the master adds time and results."""

    def __init__(self, unit: Unit, call: str, status: int | str, time: float | None = None):
        self.unit = unit
        self.call = call
        self.status = STATUS_NAMES.get(status, status)
        if isinstance(status, int) and getattr(unit, "fmi3", False):
            self.status = self.status.replace("fmi2", "fmi3")  # the same numbers name fmi3Status values
        self.time = time
        super().__init__(f"{call} returned {self.status}")


class Channel:
    """The batched value arrays of one family (see :mod:`.types`) in one unit: the inputs set before
    each step and the variables read after it, with the raw FMI functions that move them.

    ``nvr_in``/``nvr_out`` count value references (one per variable), ``n_in``/``n_out`` values
    (an array's elements each): the lengths of ``in_val``/``out_val``."""

    def __init__(self, family: Family):
        self.family = family
        self.in_names: list[str] = []
        self.out_names: list[str] = []

    def allocate(self, variables: dict, raw_function, fmi3: bool = False) -> None:
        element = self.family.ctype
        self.nvr_in, self.nvr_out = len(self.in_names), len(self.out_names)
        self.n_in = sum(array_size(variables[n]) or 1 for n in self.in_names)
        self.n_out = sum(array_size(variables[n]) or 1 for n in self.out_names)
        self.nvr_in_arg, self.nvr_out_arg = c_size_t(self.nvr_in), c_size_t(self.nvr_out)
        self.n_in_arg, self.n_out_arg = c_size_t(self.n_in), c_size_t(self.n_out)
        self.in_vr = (c_uint * max(1, self.nvr_in))(*[variables[n].valueReference for n in self.in_names])
        self.in_val = (element * max(1, self.n_in))()
        self.out_vr = (c_uint * max(1, self.nvr_out))(*[variables[n].valueReference for n in self.out_names])
        self.out_val = (element * max(1, self.n_out))()
        self.setter = raw_function(f"Set{self.family.name}")
        self.getter = raw_function(f"Get{self.family.name}")
        self.fmi3 = fmi3

    def set(self, c) -> int:
        # FMI 3.0 setters and getters take the number of values after the array (nValues).
        extra = (self.n_in_arg,) if self.fmi3 else ()
        return self.setter(c, self.in_vr, self.nvr_in_arg, self.in_val, *extra)

    def get(self, c) -> int:
        extra = (self.n_out_arg,) if self.fmi3 else ()
        return self.getter(c, self.out_vr, self.nvr_out_arg, self.out_val, *extra)


class Unit:
    """A Co-Simulation FMU instance (Model Exchange: see :class:`ModelExchangeUnit`)."""

    interface = "CoSimulation"
    fmu_class = FMU2Slave  # fmpy's class of the instance
    fmi3 = False
    prefix = "fmi2"
    real = "Real"  # the family of floating-point variables, which the fast paths move
    family_table = FAMILIES_2
    terminated_at: float | None = None  # set when the FMU asks to end the simulation
    state_calls = ("fmi2GetFMUstate", "fmi2SetFMUstate", "fmi2FreeFMUstate")  # FMI 3.0 spells them FMUState
    queues = fmpy_log.SINKS  # where the process-wide logger finds this unit's messages

    def __init__(self, name: str, fmu_path: Path, unzip_directory: str, description):
        self._name_it(name, fmu_path, description)
        self._callbacks = self._make_callbacks()
        self.fmu = self._make_fmu(unzip_directory)
        self.fmu.instantiate(callbacks=self._callbacks, loggingOn=False)
        dll = self.fmu.dll
        # The per-step calls go through argument-less function pointers on prebuilt ctypes objects:
        # fmpy's argtypes make ctypes convert every argument on every call, which costs about as
        # much as a native FMU's whole step (~0.5 us of ~1 us per call, measured).
        self.c = c_void_p(self.fmu.component)
        self.do_step = _raw(dll, "fmi2DoStep")
        self.time_arg, self.step_arg = c_double(), c_double()
        self.can_roll_back = bool(self._capabilities().canGetAndSetFMUstate)
        self._state = fmi2FMUstate()
        self.configure([], [])

    # ----------------------------------------------------------------------------- set-up
    def _name_it(self, name: str, fmu_path: Path, description) -> None:
        """The unit's name, FMU file, description, variables by name and the queue of its messages."""
        self.name = name
        self.fmu_path = Path(fmu_path)
        self.description = description
        self.variables = {v.name: v for v in description.modelVariables}
        self.messages: collections.deque[str] = collections.deque(maxlen=20)

    def _make_fmu(self, unzip_directory):
        return self.fmu_class(guid=self.description.guid, unzipDirectory=unzip_directory,
                              modelIdentifier=self._capabilities().modelIdentifier, instanceName=self.name)

    def _capabilities(self):
        """The description of the interface this unit runs (fmpy's coSimulation or modelExchange)."""
        return getattr(self.description, "modelExchange" if self.interface == "ModelExchange" else "coSimulation")

    def _make_callbacks(self):
        """Callbacks routing this instance's messages into its queue (``fmpy_log``: fmpy's proxy is one
        slot per process), registered until free()."""
        messages = self.messages
        return fmpy_log.listening(
            lambda status, category, text: messages.append(f"[{STATUS_NAMES.get(status, status)}] {text}"),
            id(messages))

    def variable(self, name: str):
        variable = self.variables.get(name)
        if variable is None:
            raise ValueError(f"component {self.name!r} ({self.fmu_path.name}) has no variable {name!r}")
        return variable

    def family(self, name: str) -> Family:
        """The family (see :mod:`.types`) that gets and sets variable ``name``."""
        variable = self.variable(name)
        if len(getattr(variable, "shape", None) or ()) > 1:
            raise ValueError(f"{self.name}.{name} is an array variable of shape {variable.shape}; the master moves "
                             f"scalars and 1-D arrays only")
        try:
            return family_of(variable, self.fmi3)
        except ValueError as error:
            raise ValueError(f"{self.name}.{error}") from None

    def elements(self, reference: str) -> tuple[str, list[int]]:
        """The variable ``reference`` names and the 0-based indices of the values it stands for:
        every element of a whole array, ``[i - 1]`` for ``name[i]``, ``[0]`` for a scalar."""
        if reference not in self.variables:
            element = split_element(reference)
            size = array_size(self.variables[element[0]]) if element and element[0] in self.variables else None
            if size is None:
                self.variable(reference)  # raises: no such variable
            name, index = element
            if index > size:
                raise ValueError(f"{self.name}.{reference}: index {index} is beyond the {size} elements of "
                                 f"{self.name}.{name}")
            return name, [index - 1]
        return reference, list(range(array_size(self.variables[reference]) or 1))

    def slots(self, reference: str, inputs: bool) -> tuple[str, list[int]]:
        """(family name, indices in its input or read values) of what ``reference`` names (configured)."""
        name, indices = self.elements(reference)
        family, first = (self.input_slot if inputs else self.read_slot)[name]
        return family, [first + i for i in indices]

    def configure(self, inputs: list[str], reads: list[str]) -> None:
        """Allocate the batched arrays: variables ``inputs`` set before each step, ``reads`` read
        after it, one pair of arrays per family; ``slot[name]`` is (family name, index of its first
        value) in them."""
        self.inputs, self.reads = list(inputs), list(reads)
        self.channels: dict[str, Channel] = {}
        self.input_slot, self.read_slot = {}, {}
        filled: dict[tuple[str, str], int] = {}  # values allocated so far, by (family, direction)
        for names, slots, direction in ((inputs, self.input_slot, "in"), (reads, self.read_slot, "out")):
            for name in names:
                family = self.family(name)
                channel = self.channels.get(family.name) or self.channels.setdefault(family.name, Channel(family))
                (channel.in_names if direction == "in" else channel.out_names).append(name)
                first = filled.get((family.name, direction), 0)
                slots[name] = (family.name, first)
                filled[family.name, direction] = first + (array_size(self.variables[name]) or 1)
        self.channels.setdefault(self.real, Channel(self.family_table[self.real]))
        for channel in self.channels.values():
            channel.allocate(self.variables, self._raw_function, self.fmi3)
        real = self.channels[self.real]
        self.n_in, self.n_out = real.n_in, real.n_out
        self.n_in_arg, self.n_out_arg = real.n_in_arg, real.n_out_arg
        self.in_vr, self.in_val, self.out_vr, self.out_val = real.in_vr, real.in_val, real.out_vr, real.out_val
        self.set_real, self.get_real = real.setter, real.getter
        self._setters = [c for c in self.channels.values() if c.n_in]
        self._getters = [c for c in self.channels.values() if c.n_out]

    def _raw_function(self, name: str):
        return _raw(self.fmu.dll, f"{self.prefix}{name}")

    # ----------------------------------------------------------------------------- calls
    def check(self, status: int, call: str) -> None:
        if status > 1:
            raise FMUFailure(self, call, status)

    def set_inputs(self) -> None:
        for channel in self._setters:
            self.check(channel.set(self.c), f"{self.prefix}Set{channel.family.name}")

    def read(self) -> None:
        for channel in self._getters:
            self.check(channel.get(self.c), f"{self.prefix}Get{channel.family.name}")

    def apply_values(self, values: dict) -> None:
        """Set start values/parameters by name, each with the setter of its type (Enumeration values
        may be item names). An array's elements (``k[2]``) are set with the whole array, whose other
        elements keep their start values; the input arrays' unconnected elements start from the
        same values (their input slots are filled, as the step sets the whole array)."""
        arrays: dict[str, dict[int, object]] = {}
        for key, value in values.items():
            name, indices = self.elements(key)
            if array_size(self.variables[name]) is None:
                self._set(name, [value], f"{name}={value!r}")
                continue
            given = array_values(value, len(indices), f"{self.name}.{key}") if key == name else [value]
            arrays.setdefault(name, {}).update(zip(indices, given))
        for name in dict.fromkeys([*arrays, *self.input_slot]):
            if array_size(self.variables[name]) is None:
                continue
            whole = self._start_elements(name, arrays.get(name, {}))
            if name in arrays:
                self._set(name, whole, f"{name}={whole!r}")
            if name in self.input_slot:
                family, first = self.input_slot[name]
                typed = self._typed(name, whole, f"{self.prefix}Set{family}({name})")
                self.channels[family].in_val[first:first + len(typed)] = typed

    def _start_elements(self, name: str, given: dict[int, object]) -> list:
        """Every element of array ``name``: ``given[i]``, else the start value from the model description."""
        variable = self.variables[name]
        size = array_size(variable)
        call = f"{self.prefix}Set{self.family(name).name}({name})"
        starts = (variable.start or "").split()
        if len(given) < size and len(starts) != size:
            raise FMUFailure(self, call, f"{self.name}.{name} has no start value for each of its {size} elements: set them all")
        if self.family(name).name != "String":  # the model description's text, as the values it stands for
            starts = self._typed(name, starts, call)
        return [given[i] if i in given else starts[i] for i in range(size)]

    def _typed(self, name: str, items: list, call: str) -> list:
        """``items`` as values of variable ``name`` in its family's C element type (strings encoded)."""
        variable, family = self.variables[name], self.family(name)
        try:
            typed = [typed_value(item, kind_of(variable), enumeration_items(self.description, variable),
                                 f"{self.name}.{name}", variable.type) for item in items]
        except ValueError as error:
            raise FMUFailure(self, call, str(error)) from None
        return [item.encode() for item in typed] if family.name == "String" else typed

    def _set(self, name: str, items: list, shown: str) -> None:
        """Set variable ``name`` (all its elements: ``items``) with one call of its family's setter."""
        family = self.family(name)
        call = f"{self.prefix}Set{family.name}({shown})"
        array = (family.ctype * len(items))(*self._typed(name, items, call))
        extra = (c_size_t(len(items)),) if self.fmi3 else ()
        status = self._raw_function(f"Set{family.name}")(self.c, (c_uint * 1)(self.variables[name].valueReference),
                                                         c_size_t(1), array, *extra)
        if status > 1:
            raise FMUFailure(self, call, status)

    def setup(self, start_time: float) -> None:
        self._call("fmi2SetupExperiment", self.fmu.setupExperiment, startTime=start_time)

    def enter_initialization(self) -> None:
        self._call("fmi2EnterInitializationMode", self.fmu.enterInitializationMode)

    def exit_initialization(self, start_time: float, tolerance: float) -> None:
        self._call(f"{self.prefix}ExitInitializationMode", self.fmu.exitInitializationMode)

    def reset(self) -> None:
        self._call(f"{self.prefix}Reset", self.fmu.reset)
        self.terminated_at = None

    def step(self, t: float, h: float, final: bool = True) -> bool:
        """One step; True when the FMU asked to end the simulation (``terminated_at`` says when).

        ``final``: the master will not roll the FMU back before ``t`` (noSetFMUStatePriorToCurrentPoint,
        FMI 2.0 sec. 4.2.2). Only a step inside an algebraic loop, which may be repeated from a saved
        state, passes False: an FMU may keep such a step provisional until a later step confirms it.
        """
        self.time_arg.value, self.step_arg.value = t, h
        status = self.do_step(self.c, self.time_arg, self.step_arg, 1 if final else 0)
        return status > 1 and self.stop_or_fail(t, h, status)

    def stop_or_fail(self, t: float, h: float, status: int) -> bool:
        """After fmi2DoStep returned ``status`` > fmi2Warning: True, with ``terminated_at`` set, if
        it was fmi2Discard and the FMU asks to terminate (fmi2GetBooleanStatus(fmi2Terminated),
        FMI 2.0 sec. 4.2.3) at a time it reached; else FMUFailure. The end time is
        fmi2LastSuccessfulTime where the FMU reports it, else the end of the step. A step that made
        no progress (fmi2LastSuccessfulTime = its start: pythonfmu's answer when ``do_step`` returns
        False) failed: it is an error, as is any other status."""
        if status != 2:
            raise FMUFailure(self, "fmi2DoStep", status, time=t)
        flag, when = c_int(0), c_double(t + h)
        boolean_status, real_status = _raw(self.fmu.dll, "fmi2GetBooleanStatus"), _raw(self.fmu.dll, "fmi2GetRealStatus")
        if boolean_status is None or boolean_status(self.c, c_int(3), byref(flag)) > 1 or not flag.value:  # fmi2Terminated
            raise FMUFailure(self, "fmi2DoStep", status, time=t)
        if real_status is None or real_status(self.c, c_int(2), byref(when)) > 1 or not t <= when.value <= t + h:
            when.value = t + h  # fmi2LastSuccessfulTime not reported: the step's end
        if when.value <= t and h > 0:
            raise FMUFailure(self, "fmi2DoStep", status, time=t)
        self.terminated_at = when.value
        self.termination_call = "fmi2DoStep returned fmi2Discard and fmi2Terminated is true"
        return True

    def save_state(self) -> None:
        call = self.state_calls[0]
        self.check(getattr(self.fmu.dll, call)(self.c, byref(self._state)), call)

    def restore_state(self) -> None:
        call = self.state_calls[1]
        self.check(getattr(self.fmu.dll, call)(self.c, self._state), call)

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
            getattr(self.fmu.dll, self.state_calls[2])(self.c, byref(self._state))
        try:
            self.fmu.terminate()
        except Exception:  # noqa: BLE001 - terminating after an error may itself fail; free anyway
            pass
        self.fmu.freeInstance()
        self.fmu = None
        self.queues.pop(id(self.messages), None)


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
    fmu_class = FMU2Model

    def configure(self, inputs, reads):
        super().configure(inputs, reads)
        self._held = None
        self._continuous_time = False  # in continuous-time mode: discrete inputs wait for an event
        self._continuous_inputs = []  # (channel, its continuous inputs' channel, their indices in it)
        self._discrete_inputs = []  # (channel, indices of its discrete inputs)
        for channel in self._setters:
            continuous, discrete = [], []  # the values of each, by index in the channel's input values
            for name in channel.in_names:
                _, first = self.input_slot[name]
                values = range(first, first + (array_size(self.variables[name]) or 1))
                (continuous if self.variables[name].variability == "continuous" else discrete).extend(values)
            if continuous:
                subset = Channel(channel.family)
                subset.in_names = [n for n in channel.in_names if self.variables[n].variability == "continuous"]
                subset.allocate(self.variables, self._raw_function, self.fmi3)
                self._continuous_inputs.append((channel, subset, continuous))
            if discrete:
                self._discrete_inputs.append((channel, discrete))
        self._discrete_set = None  # the discrete input values the FMU has

    def _discrete_values(self) -> tuple:
        return tuple(channel.in_val[i] for channel, indices in self._discrete_inputs for i in indices)

    def set_inputs(self) -> None:
        """Set every input, or in continuous-time mode the continuous ones, and the discrete ones
        in event mode where they changed (see the module docstring)."""
        if not self._continuous_time:  # initialization or event mode: every input may be set
            super().set_inputs()
            self._discrete_set = self._discrete_values()
            return
        try:
            for channel, subset, indices in self._continuous_inputs:
                for j, i in enumerate(indices):
                    subset.in_val[j] = channel.in_val[i]
                self.check(subset.set(self.c), f"{self.prefix}Set{channel.family.name}")
            if self._discrete_values() != self._discrete_set:
                self._input_event()
        except FMUFailure as failure:
            failure.time = self.time if failure.time is None else failure.time
            raise

    def _input_event(self) -> None:
        """A discrete input changed at the current time: set the inputs in event mode and iterate."""
        self._call(f"{self.prefix}EnterEventMode", self.fmu.enterEventMode)
        self._continuous_time = False
        self.set_inputs()
        self._event_iteration()
        if self.terminated_at is None:
            self._call(f"{self.prefix}EnterContinuousTimeMode", self.fmu.enterContinuousTimeMode)
            self._continuous_time = True
        self._held = None  # restart the integrator at the event

    def exit_initialization(self, start_time: float, tolerance: float) -> None:
        from fmpy.sundials import CVodeSolver

        super().exit_initialization(start_time, tolerance)
        self.time = start_time
        self._event_iteration()
        if self.terminated_at is not None:
            return
        self._call(f"{self.prefix}EnterContinuousTimeMode", self.fmu.enterContinuousTimeMode)
        self._continuous_time = True
        fmu, description = self.fmu, self.description
        self.solver = CVodeSolver(
            nx=description.numberOfContinuousStates, nz=description.numberOfEventIndicators,
            get_x=fmu.getContinuousStates, set_x=fmu.setContinuousStates, get_dx=self._derivatives_function(),
            get_z=fmu.getEventIndicators, get_nominals=fmu.getNominalsOfContinuousStates,
            set_time=fmu.setTime, input=_HeldInputs(), startTime=start_time,
            relativeTolerance=tolerance, maxNumSteps=100000,
        )
        self._held = None

    def _derivatives_function(self):
        return self.fmu.getDerivatives

    def _discrete_states(self):
        """fmi2NewDiscreteStates (FMI 3.0: fmi3UpdateDiscreteStates): (needed, terminate,
        nominals changed, values changed, next event time defined, next event time)."""
        return "fmi2NewDiscreteStates", self.fmu.newDiscreteStates

    def _event_iteration(self) -> None:
        """fmi2NewDiscreteStates until the FMU needs no more; remember its next time event, or that
        it asked to end the simulation (``terminated_at``)."""
        needed, terminate = True, False
        call, function = self._discrete_states()
        while needed and not terminate:
            needed, terminate, _, _, defined, next_time = self._call(call, function)
        if terminate:
            self.terminated_at = self.time
            self.termination_call = f"{call} set terminateSimulation"
        self.next_event_time = next_time if defined else math.inf

    def step(self, t: float, h: float, final: bool = True) -> bool:
        """Integrate over [t, t + h]; True when the FMU asked to end the simulation on the way
        (``final``: as for a Co-Simulation step, passed on to fmi2CompletedIntegratorStep)."""
        if self.terminated_at is not None:  # it asked at the event of an input that changed at t
            return True
        try:
            self._integrate(t, h, final)
        except FMUFailure as failure:
            failure.time = t if failure.time is None else failure.time
            raise
        return self.terminated_at is not None

    def _integrate(self, t: float, h: float, final: bool) -> None:
        held = [list(channel.in_val[: channel.n_in]) for channel in self._setters]
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
            self._call(f"{self.prefix}SetTime", self.fmu.setTime, time)
            step_event, terminate = self._call(f"{self.prefix}CompletedIntegratorStep", self.fmu.completedIntegratorStep,
                                               noSetFMUStatePriorToCurrentPoint=final)
            self.time = time
            if terminate:
                self.terminated_at = time
                self.termination_call = f"{self.prefix}CompletedIntegratorStep set terminateSimulation"
                return
            time_event = abs(time - self.next_event_time) <= tiny
            if state_event or step_event or time_event:
                self._call(f"{self.prefix}EnterEventMode", self.fmu.enterEventMode)
                self._event_iteration()
                if self.terminated_at is not None:
                    return
                self._call(f"{self.prefix}EnterContinuousTimeMode", self.fmu.enterContinuousTimeMode)
                self.solver.reset(time)
        self.time = t_end

    def save_state(self) -> None:
        super().save_state()
        self._saved = self.time, self._discrete_set

    def restore_state(self) -> None:
        super().restore_state()
        self.time, self._discrete_set = self._saved
        self._held = None  # re-initialise the integrator at the restored point

    def reset(self) -> None:
        super().reset()
        self._continuous_time = False
