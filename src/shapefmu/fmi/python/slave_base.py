"""The one pythonfmu slave class: any FMU kind of ``shapefmu.fmi.kinds`` run inside its FMU, with the
call order, errors, state and logging of FMI 2.0.

Bundled into every FMU (standard library only), where pythonfmu's export library drives it: the
library finds the slave class by the name ``Fmi2Slave`` in its bases (the FMU's entry module derives
one per kind, setting ``model_class``) and calls the methods below (``set_real``, ``do_step``,
``_get_fmu_state``, ...). pythonfmu's own Python package is not needed at run time.

The kind's interface (``model_class.interface``) gives the variables, value reference = position;
its model (``model_class``) computes. What the slave guarantees for every kind:

- a bad call never raises into the host: wrong value reference or type, a parameter set after
  initialisation, a NaN input, a step at the wrong time, an invalid design... are logged through the
  FMI logger with status fmi2Error and the call returns normally; the FMU's C front end
  (``shim/fmi2_shim.c``) turns the call into fmi2Error, and the instance stays usable. Every method
  the export library calls catches what the model's hooks raise: pythonfmu 0.7.0 answers an
  escaping exception with fmi2Fatal and releases the instance's Python objects twice (the front
  end then stops forwarding to it, at the cost of a small leak);
- parameters are validated at the exit of initialisation (``Model.initialize``), where the design runs;
- an output got in initialization mode is what the exit would make it from the values set so far
  (``_initial_values``); parameters the exit would refuse leave it at its start value;
- NaN / inf inputs make the next ``fmi2DoStep`` fail with fmi2Error, leaving the state untouched;
- ``fmi2GetFMUstate`` / ``fmi2SetFMUstate`` and serialisation restore exactly: all variables, the
  time, the phase, and the kernel objects named in the model's ``state_attributes`` (ring buffers,
  covariances) through ``state_codec``.

Adding an FMU kind is a module of ``shapefmu.fmi.kinds`` (see there); the builder bundles it.
"""

import math
from pathlib import Path

from . import state_codec

OK, WARNING, DISCARD, ERROR, FATAL = range(5)

# pythonfmu 0.7.0's export library re-runs the FMU's entry module at every fmi2Instantiate (to find
# the slave class) and then releases the module's globals dict once more than it took (a
# Py_DECREF of PyModule_GetDict's borrowed reference): the second instance of an FMU in a process
# found a freed dict. Every run of the entry module appends its globals here, one reference per
# release (see builder.ENTRY_MODULE).
ENTRY_MODULE_REFERENCES = []

_TYPES = {"Real": float, "Integer": int, "Boolean": bool, "String": str}


class LogMessage:
    """One entry of the log queue that pythonfmu's export library drains after every call."""

    __slots__ = ("status", "category", "msg", "debug")

    def __init__(self, status, category, msg):
        self.status = status
        self.category = category
        # Hosts may pass the message to printf as a format string: never hand them a '%'.
        self.msg = msg.replace("%", " percent")
        self.debug = False


class Fmi2Slave:
    """The slave of every shapefmu FMU (the class name is what pythonfmu's export library looks for);
    the FMU's entry module derives one whose ``model_class`` is its kind's ``Model``."""

    model_class = None
    # Written by the builder into resources/: start values baked into this FMU and its identity.
    build_file = "shapefmu_build.json"

    def __init__(self, instance_name="instance", resources=None, logger=None, visible=False, **_ignored):
        interface = self.model_class.interface
        self.model_name = interface.name
        self.instance_name = instance_name
        self.log_queue = []
        self.variables = list(interface.variables)  # value reference = position
        self.by_name = {v.name: v for v in self.variables}
        self._by_type = {t: {} for t in _TYPES}
        for vr, v in enumerate(self.variables):
            self._by_type[v.type][vr] = v
        self.values = {v.name: (0.0 if v.start is None else v.start) for v in self.variables}
        self.model = self.model_class(self.values, f"{self.model_name} {instance_name}", self.log)
        self._kernel_classes = {cls.__name__: cls for cls in self.model.kernels}
        self.phase = "instantiated"
        self.time = 0.0
        self._input_names = [v.name for v in self.variables if v.causality == "input"]
        self._output_names = [v.name for v in self.variables if v.causality == "output"]
        self.guid = ""
        self.declared_dependencies = None
        if resources:
            self._load_build(Path(resources) / self.build_file)

    # The model sees the FMU's time and whether it is stepping.
    @property
    def time(self):
        return self.model.time

    @time.setter
    def time(self, value):
        self.model.time = value

    @property
    def phase(self):
        return self._phase

    @phase.setter
    def phase(self, value):
        self._phase = value
        self.model.running = value == "step"

    # -- logging ---------------------------------------------------------------------------------

    def log(self, message, status=OK):
        category = {WARNING: "logStatusWarning", ERROR: "logStatusError", FATAL: "logStatusFatal"}.get(status, "logAll")
        self.log_queue.append(LogMessage(status, category, message))

    def error(self, message):
        """Log ``message`` with fmi2Error: the front end makes the current call return fmi2Error."""
        self.log(message, ERROR)

    def _get_log_queue(self):
        return self.log_queue

    # -- build metadata --------------------------------------------------------------------------

    def _load_build(self, path):
        import json

        try:
            build = json.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            return
        self.guid = build.get("guid", "")
        self.declared_dependencies = build.get("dependencies")
        for name, value in build.get("start_values", {}).items():
            self.values[name] = _TYPES[self.by_name[name].type](value)

    # -- FMI calls -------------------------------------------------------------------------------

    def setup_experiment(self, start_time=0.0, *_ignored):
        if self.phase != "instantiated":
            self.error(f"fmi2SetupExperiment is allowed only after fmi2Instantiate, not in phase {self.phase}")
            return
        if not math.isfinite(start_time):
            self.error(f"startTime must be finite, got {start_time!r}")
            return
        self.time = float(start_time)

    def enter_initialization_mode(self):
        if self.phase != "instantiated":
            self.error(f"fmi2EnterInitializationMode is allowed only after fmi2Instantiate, not in phase {self.phase}")
            return
        self.phase = "initialization"

    def exit_initialization_mode(self):
        if self.phase != "initialization":
            self.error(f"fmi2ExitInitializationMode is allowed only in initialization mode, not in phase {self.phase}")
            return
        try:
            self.model.initialize()
            self._check_declared_dependencies()
        except Exception as error:  # noqa: BLE001 - every failure is the host's fmi2Error
            self.phase = "failed"
            self.error(f"{self.model_name} {self.instance_name}: invalid parameters: {_describe(error)}")
            return
        self.phase = "step"

    def _check_declared_dependencies(self):
        if self.declared_dependencies is None:
            return
        for output, inputs in self.model.output_dependencies().items():
            missing = set(inputs) - set(self.declared_dependencies.get(output, []))
            if missing:
                raise ValueError(
                    f"with these parameters {output} feeds through from {sorted(missing)}, but this FMU was built "
                    f"declaring it independent of them; rebuild it with these parameters as start values"
                )

    def do_step(self, current_time, step_size, *_ignored):
        if self.phase != "step":
            self.error(f"fmi2DoStep is allowed only after fmi2ExitInitializationMode succeeded, not in phase {self.phase}")
            return False
        if not (math.isfinite(current_time) and math.isfinite(step_size) and step_size > 0.0):
            self.error(f"fmi2DoStep needs a finite time and a step size > 0, got t = {current_time!r}, h = {step_size!r}")
            return False
        if abs(current_time - self.time) > 1e-9 * max(1.0, abs(self.time)):
            self.error(f"fmi2DoStep at t = {current_time!r}, but the FMU is at t = {self.time!r}")
            return False
        values = self.values
        for name in self._input_names:
            if not math.isfinite(values[name]):
                self.error(f"input {name} is {values[name]!r} at t = {current_time!r}; it must be finite")
                return False
        try:
            self.model.step(current_time, step_size)
        except Exception as error:  # noqa: BLE001
            self.error(f"{self.model_name} {self.instance_name}: step at t = {current_time!r} failed: {_describe(error)}")
            return False
        self.time = current_time + step_size
        return True

    def terminate(self):
        if self.phase not in ("step", "failed", "initialization"):
            self.error(f"fmi2Terminate is not allowed in phase {self.phase}")
            return
        self.phase = "terminated"

    def _initial_values(self):
        """The values, with the outputs fmi2ExitInitializationMode would give from the parameters and
        inputs set so far, computed by a model of their own so that nothing is committed: FMI 2.0
        (section 2.2.7, initial="calculated") lets a host get them in initialization mode, and a master
        propagating values before the first step passes them on. Parameters the exit would refuse leave
        the start values (no message): the refusal stays at the exit, where a host expects it and where
        parameters set one at a time are complete."""
        preview = self.model_class(dict(self.values), self.model.owner)
        preview.time = self.time
        try:
            preview.initialize()
        except Exception:  # noqa: BLE001 - see the docstring: refused at the exit, with its message
            return self.values
        return self.values | {name: preview.values[name] for name in self._output_names}

    def _get(self, vrs, type_):
        table = self._by_type[type_]
        values = self._initial_values() if self.phase == "initialization" else self.values
        try:
            return [values[table[vr].name] for vr in vrs]
        except KeyError:
            bad = [vr for vr in vrs if vr not in table]
            self.error(f"fmi2Get{type_}: no {type_} variable with value reference {bad}")
            return [_TYPES[type_]() for _ in vrs]

    def get_real(self, vrs):
        return self._get(vrs, "Real")

    def get_integer(self, vrs):
        return self._get(vrs, "Integer")

    def get_boolean(self, vrs):
        return self._get(vrs, "Boolean")

    def get_string(self, vrs):
        return self._get(vrs, "String")

    def _set(self, vrs, values, type_):
        table = self._by_type[type_]
        for vr, value in zip(vrs, values):
            var = table.get(vr)
            if var is None:
                self.error(f"fmi2Set{type_}: no {type_} variable with value reference {vr}")
            elif var.causality == "output":
                self.error(f"{var.name} is an output and cannot be set")
            elif var.causality == "parameter" and self.phase not in ("instantiated", "initialization"):
                self.error(f"parameter {var.name} can be set only before fmi2ExitInitializationMode (phase {self.phase})")
            elif self.phase == "terminated":
                self.error(f"{var.name} cannot be set after fmi2Terminate")
            else:
                self.values[var.name] = _TYPES[type_](value)
                if var.causality == "input":
                    try:
                        self.model.input_changed(var.name)
                    except Exception as error:  # noqa: BLE001 - see "never raises" in the docstring
                        self.error(f"{self.model_name} {self.instance_name}: input {var.name} = {value!r}: {_describe(error)}")

    def set_real(self, vrs, values):
        self._set(vrs, values, "Real")

    def set_integer(self, vrs, values):
        self._set(vrs, values, "Integer")

    def set_boolean(self, vrs, values):
        self._set(vrs, values, "Boolean")

    def set_string(self, vrs, values):
        self._set(vrs, values, "String")

    # -- FMU state -------------------------------------------------------------------------------

    def _get_fmu_state(self):
        kernels = {name: getattr(self.model, name) for name in self.model.state_attributes}
        try:
            return state_codec.encode(
                {
                    "model": self.model_name,
                    "guid": self.guid,
                    "phase": self.phase,
                    "time": self.time,
                    "values": self.values,
                    "kernels": kernels,
                },
                self._kernel_classes,
            )
        except Exception as error:  # noqa: BLE001 - a kernel the codec cannot store is fmi2Error
            self.error(f"fmi2GetFMUstate: {_describe(error)}")
            return state_codec.invalid(str(error))

    def _set_fmu_state(self, tree):
        try:
            state = state_codec.decode(tree, self._kernel_classes)
            if not isinstance(state, dict) or "invalid" in state:
                raise ValueError(state.get("invalid", "not a state") if isinstance(state, dict) else "not a state")
            if state.get("model") != self.model_name or state.get("guid") != self.guid:
                raise ValueError(f"the state belongs to {state.get('model')!r} {state.get('guid')!r}, not to this FMU")
            values = state["values"]
            if set(values) != set(self.values):
                raise ValueError("the state's variables differ from this FMU's")
            for name, value in values.items():
                if not isinstance(value, _TYPES[self.by_name[name].type]):
                    raise ValueError(f"the state's {name} has the wrong type")
            phase, time, kernels = state["phase"], state["time"], state["kernels"]
            if phase not in ("instantiated", "initialization", "step", "failed", "terminated"):
                raise ValueError(f"unknown phase {phase!r}")
            if not isinstance(time, float) or set(kernels) != set(self.model.state_attributes):
                raise ValueError("the state's time or kernels are malformed")
            where = state_codec.first_non_finite({"time": time, "values": values, "kernels": kernels}, "state")
            if where is not None:
                raise ValueError(f"{where} is not a finite number (fmi2SetReal takes none)")
            for name, kernel in kernels.items():
                problem = kernel.state_problem() if hasattr(kernel, "state_problem") else None
                if problem is not None:
                    raise ValueError(f"{name}: {problem}")
        except Exception as error:  # noqa: BLE001 - whatever the state holds, it is refused, not raised
            self.error(f"fmi2SetFMUstate: {_describe(error)}")
            return
        self.values.clear()  # in place: the model holds this dict
        self.values.update(values)
        self.phase = phase
        self.time = time
        for name, kernel in kernels.items():
            setattr(self.model, name, kernel)

    @staticmethod
    def _fmu_state_to_bytes(tree):
        # Called on the class, with no instance to log through: a state that cannot be serialised
        # becomes the bytes of a state that fmi2SetFMUstate refuses with a logged error.
        try:
            return state_codec.to_bytes(tree)
        except Exception as error:  # noqa: BLE001
            return state_codec.to_bytes(state_codec.invalid(f"the state could not be serialised: {_describe(error)}"))

    @staticmethod
    def _fmu_state_from_bytes(raw):
        # Called on the class, with no instance to log through: a bad byte string becomes a state
        # that fmi2SetFMUstate refuses with a logged error.
        try:
            return state_codec.from_bytes(raw)
        except Exception as error:  # noqa: BLE001
            return state_codec.invalid(str(error))


def _describe(error):
    return str(error) if isinstance(error, ValueError) else f"{type(error).__name__}: {error}"
