"""The master algorithm: fixed macro steps over an SSP system of FMI 2.0 and FMI 3.0 FMUs.

Communication semantics (``t_k = t0 + k*h``; the last step is shortened to end exactly at stop):

* Initialisation: every FMU gets ``fmi2SetupExperiment``, then its SSP parameter bindings and the
  run's parameters (one set of values, the run's winning), then ``fmi2EnterInitializationMode``
  (FMI 3.0: the values, then ``fmi3EnterInitializationMode``), as fmpy and libcosim do: an FMU may
  reset its variables to their start values in ``fmi2SetupExperiment`` (a 20-sim export does), so a
  value set before it would be lost. The same after :meth:`Master.reset`. Inputs are propagated in initialisation
  mode (Jacobi: as many sweeps of "read every output, set every input" as there are components,
  as libcosim does; Gauss-Seidel: once in stepping order, iterating loop groups), then
  ``fmi2ExitInitializationMode``, and the outputs are read: that is the record at ``t0``.
* ``algorithm="jacobi"`` -- the scheme of libcosim's fixed-step algorithm and of ecos: every
  component's inputs for the step ``[t_k, t_k+h]`` are the transformed outputs read at ``t_k``;
  all components then set inputs, ``fmi2DoStep`` and read outputs. A recorded output that
  feeds through (``y = k*u`` computed when read) is read right after the step, before the new
  inputs are set, as libcosim reads it; ecos transfers connection by connection after the step and
  so reports such an output with the new input. Outputs computed in ``fmi2DoStep`` are identical in
  all three.
* ``algorithm="gauss-seidel"`` (default): components step one after another in the order of
  :func:`shapefmu.cosim.graph.schedule`; each takes its inputs from the latest outputs, so a
  consumer stepping after its producer sees the producer's value at ``t_k+h``. An output that
  feeds through (ModelStructure lists an input among its dependencies) is passed on as read at
  the communication point, right after its FMU's inputs are set and before ``fmi2DoStep``: it is
  a function of those inputs at that instant (FMI 2.0, sec. 4.2.1), and a sampled FMU (a shaper
  filter, a controller) holds it over the coming step. Read after the step it would pair the new
  sample's history with the old input: a shaper's delayed impulses would arrive one sample early,
  a controller's internal state (an integrator) one sample ahead. Recorded values are read after
  the step (for such an FMU only on recording steps, when nothing else needs that read).
  Algebraic loops are iterated on the torn inputs with FMU state rollback
  (``fmi2GetFMUstate``/``fmi2SetFMUstate``):
  by Newton's method with a finite-difference Jacobian (default) or plain fixed-point iteration,
  until the torn inputs agree with the outputs that feed them to ``loop_tolerance``.
* ``step_multiples={"plant": 10}``: that component steps every 10th macro step by ``10*h`` (the
  last one cut at the stop time), and its outputs are passed on when it has reached the others'
  time, as libcosim's decimation factor does.
* Model Exchange components are integrated by the master (see :mod:`shapefmu.cosim.units`).
* Values of every type travel (Real/Float64, Integer and the FMI 3.0 integer types, Boolean,
  String, Enumeration; see :mod:`.types`); parameters are typed by the model description, so the
  text of a command line (``"zvd"``, ``"true"``, an Enumeration item) sets them. Results have a
  typed column per recorded variable.
* FMI 3.0 arrays (1-D) travel element by element: a connection of two arrays of one size joins
  element i to element i, and ``name[i]`` (1-based) names one element, which connects to a scalar or
  another element (:mod:`shapefmu.fmi.ssp.connectors`). A parameter sets a whole array from a
  sequence or the text ``"[1, 2, 3]"`` of the array's size, or one element as ``"comp.k[2]"``; the
  other elements keep their start values (or the SSP bindings' values). A recorded array has a
  column per element, ``comp.y[1]`` ... ``comp.y[n]``.
* An FMU may ask to end the simulation (FMI 2.0 Co-Simulation: fmi2Discard and fmi2Terminated;
  FMI 3.0: terminateSimulation; Model Exchange: terminateSimulation at an event). That is a normal
  end: the other components finish the macro step, the row at the requested time is recorded and
  ``Master.termination`` says who asked and when. Any other failed call raises CosimError.

Speed: the per-step work is generated once for the system (no per-step dispatch on component
kinds), as a C loop where the system allows, else as a Python function calling the FMUs' C
functions on preallocated ctypes arrays (:mod:`.step_program`, :mod:`.units`).
"""

from __future__ import annotations

import dataclasses
import math
import shutil
import sys
import time as wallclock
import weakref

import numpy as np

from shapefmu.cosim import step_program
from shapefmu.cosim.errors import AlgebraicLoopError, CosimError, CosimInterrupted, Termination
from shapefmu.cosim.graph import Stage, _feeds_through, output_dependencies, schedule
from shapefmu.cosim.types import array_size, array_values, enumeration_items, kind_of, typed_value
from shapefmu.cosim.loading import load_units
from shapefmu.cosim.units import FMUFailure
from shapefmu.cosim.units3 import clock_ticks_on_steps
from shapefmu.fmi.ssp import System, read_ssp
from shapefmu.runtime.checks import check_size

ALGORITHMS = ("gauss-seidel", "jacobi")
LOOP_SOLVERS = ("newton", "fixed-point")


def _split(reference: str, what: str) -> tuple[str, str]:
    component, dot, variable = reference.partition(".")
    if not dot:
        raise ValueError(f"{what} must be 'component.variable', got {reference!r}")
    return component, variable


class Master:
    """Run an SSP system (a :class:`~shapefmu.fmi.ssp.System` or a .ssp/.ssd path) by fixed steps.

    Parameters
    ----------
    system_or_path : System | str | Path
    step : float
        Macro (communication) step in s.
    algorithm : "gauss-seidel" | "jacobi"
    record : list of "component.variable", default every output of every component; an array (1-D)
        is recorded as a column per element, ``component.y[1]`` ... (``record`` then lists the columns).
    output_interval : float, default ``step``; must be a whole multiple of ``step``.
    step_multiples : {"component": m}, m >= 1: that component steps by ``m*step``.
    model_exchange : components to run through their Model Exchange interface.
    tolerance : relative tolerance of CVode for Model Exchange components.
    loop_solver : "newton" | "fixed-point"; loop_tolerance, max_loop_iterations: its stopping rule.
    progress : print a progress bar on stderr.
    native : run the per-step loop compiled in C (see :mod:`.step_program`) where the system allows
        it: no Model Exchange component, no algebraic loop, a C compiler on the machine. The
        results are bit-identical to the Python loop's; ``loop_kind`` says which one runs and
        ``loop_reason`` why the Python one does (a String connection, a Model Exchange component...).
    """

    def __init__(self, system_or_path, step: float, *, algorithm: str = "gauss-seidel", record: list[str] | None = None,
                 output_interval: float | None = None, step_multiples: dict[str, int] | None = None,
                 model_exchange: list[str] | None = None, tolerance: float = 1e-8, loop_solver: str = "newton",
                 loop_tolerance: float = 1e-13, max_loop_iterations: int = 50, progress: bool = False,
                 native: bool = True):
        if not (isinstance(step, (int, float)) and math.isfinite(step) and step > 0):
            raise ValueError(f"step must be a finite number > 0 s, got {step!r}")
        if algorithm not in ALGORITHMS:
            raise ValueError(f"algorithm must be one of {ALGORITHMS}, got {algorithm!r}")
        if loop_solver not in LOOP_SOLVERS:
            raise ValueError(f"loop_solver must be one of {LOOP_SOLVERS}, got {loop_solver!r}")
        if not (0 < tolerance < 1):
            raise ValueError(f"tolerance must be in (0, 1), got {tolerance!r}")
        self.system = system_or_path if isinstance(system_or_path, System) else read_ssp(system_or_path)
        self.system.validate()
        self.step = float(step)
        self.algorithm = algorithm
        self.loop_solver = loop_solver
        self.loop_tolerance = loop_tolerance
        self.max_loop_iterations = max_loop_iterations
        self.tolerance = tolerance
        self.progress = progress
        self.native = native
        self.output_interval = self._interval(output_interval)
        names = list(self.system.components)
        self.multiples = self._multiples(step_multiples or {}, names)
        for name in model_exchange or ():
            if name not in self.system.components:
                raise ValueError(f"model_exchange names unknown component {name!r} (components: {', '.join(names)})")
        check_size(len(names), "MAX_COMPONENTS", f"system {self.system.name!r} has", "components",
                   "split it into systems run one after the other")
        self.units, self._folders = load_units([(n, self.system.components[n].fmu) for n in names], set(model_exchange or ()))
        # Released by close(), or when the master is collected or the interpreter exits without
        # close(): weakref.finalize runs from an atexit hook while modules can still be used,
        # where a __del__ at shutdown found the import machinery (sys.meta_path) already gone.
        self._finalizer = weakref.finalize(self, _release, self.units, self._folders)
        self._unit = {u.name: u for u in self.units}
        try:
            for unit in self.units:  # a clock's ticks must be communication points (see .units3)
                clock_ticks_on_steps(unit, self.step * self.multiples[unit.name])
            self._build(record)
            # read once (.ssv files included); applied at each run's initialisation
            self._bindings = {u.name: self.system.parameter_values(u.name) for u in self.units}
        except BaseException:
            self.close()
            raise
        self._state = "instantiated"
        self.termination: Termination | None = None

    # ----------------------------------------------------------------------------- set-up
    def _interval(self, output_interval):
        if output_interval is None:
            return 1
        if not (isinstance(output_interval, (int, float)) and math.isfinite(output_interval) and output_interval > 0):
            raise ValueError(f"output_interval must be a finite whole multiple > 0 of step {self.step!r} s, "
                             f"got {output_interval!r}")
        ratio = output_interval / self.step
        every = round(ratio)
        if every < 1 or abs(every - ratio) > 1e-9 * ratio:
            raise ValueError(f"output_interval must be a whole multiple of step {self.step!r} s, got {output_interval!r}")
        return every

    @staticmethod
    def _multiples(multiples: dict, names: list[str]) -> dict[str, int]:
        result = dict.fromkeys(names, 1)
        for name, m in multiples.items():
            if name not in result:
                raise ValueError(f"step_multiples names unknown component {name!r} (components: {', '.join(names)})")
            if not (isinstance(m, int) and m >= 1):
                raise ValueError(f"step_multiples[{name!r}] must be an integer >= 1, got {m!r}")
            result[name] = m
        return result

    def _build(self, record):
        system = self.system
        if record is None:
            record = [f"{u.name}.{v.name}" for u in self.units for v in u.description.modelVariables
                      if v.causality == "output" and kind_of(v) and len(v.shape) <= 1]
        # The connections between whole variables (an array element's is its array's): what the
        # units move, and what the stepping order and loops are found on.
        links = [dataclasses.replace(c, start_connector=self._unit[c.start_component].elements(c.start_connector)[0],
                                     end_connector=self._unit[c.end_component].elements(c.end_connector)[0])
                 for c in system.connections]
        inputs = {u.name: [] for u in self.units}
        reads = {u.name: [] for u in self.units}
        for c in links:
            for names, variable in ((inputs[c.end_component], c.end_connector), (reads[c.start_component], c.start_connector)):
                if variable not in names:
                    names.append(variable)
        references = []
        for reference in record:
            component, variable = _split(reference, "record entry")
            if component not in self._unit:
                raise ValueError(f"record entry {reference!r} names unknown component {component!r}")
            name, _ = self._unit[component].elements(variable)
            if name not in reads[component]:
                reads[component].append(name)
            references.append((component, variable))
        for unit in self.units:
            unit.configure(inputs[unit.name], reads[unit.name])
        # A column per recorded scalar: (component, family, slot) in its unit's read arrays.
        self.record, self._record_sources = [], []
        for component, variable in references:
            unit = self._unit[component]
            name, indices = unit.elements(variable)
            family, slots = unit.slots(variable, inputs=False)
            whole = variable == name and array_size(unit.variables[name]) is not None
            for i, slot in zip(indices, slots):
                self.record.append(f"{component}.{name}[{i + 1}]" if whole else f"{component}.{variable}")
                self._record_sources.append((component, family, slot))
        # ops[name]: how each floating-point input value of that component is computed from an
        # output value (the fast path, also used by loops); typed_ops: every other family. A
        # connection of arrays is one op per element.
        self._ops = {u.name: [] for u in self.units}
        self._typed_ops = {u.name: [] for u in self.units}
        for c in system.connections:
            source, target = self._unit[c.start_component], self._unit[c.end_component]
            f, ds = target.slots(c.end_connector, inputs=True)
            g, ss = source.slots(c.start_connector, inputs=False)
            for d, s in zip(ds, ss):  # of one size: System.validate refused others
                if f == target.real and g == source.real:
                    self._ops[target.name].append((d, source, s, c.factor, c.offset))
                else:
                    self._typed_ops[target.name].append((f, d, source, g, s, c.factor, c.offset))
        if self.algorithm == "jacobi":
            self.stages = [Stage([u.name]) for u in self.units]
        else:
            dependencies = {u.name: output_dependencies(u.description) for u in self.units}
            self.stages = schedule(list(system.components), links, dependencies)
            for stage in self.stages:
                if stage.is_loop:
                    stuck = [n for n in stage.components if not self._unit[n].can_roll_back]
                    if stuck:
                        raise AlgebraicLoopError(
                            f"algebraic loop through {', '.join(stage.loop_variables)} needs FMU state rollback, "
                            f"but {', '.join(stuck)} cannot get/set its FMU state (canGetAndSetFMUstate is false); "
                            f"run it with algorithm='jacobi' or break the loop", stage.loop_variables)
                    if any(self.multiples[n] != 1 for n in stage.components):
                        raise ValueError(f"components of the algebraic loop through {', '.join(stage.loop_variables)} "
                                         f"must share the macro step; remove them from step_multiples")
        self._loops = [s for s in self.stages if s.is_loop]
        # Gauss-Seidel passes feed-through outputs on as read before the step (module docstring).
        self._early = {}
        if self.algorithm != "jacobi":
            for stage in self.stages:
                if stage.is_loop:
                    continue
                unit = self._unit[stage.components[0]]
                dependencies = output_dependencies(unit.description)
                early = {}
                for name in reads[unit.name]:
                    if name in dependencies and _feeds_through(dependencies, name):
                        f, slots = unit.slots(name, inputs=False)
                        early.setdefault(f, set()).update(slots)
                if early:
                    self._early[unit.name] = {f: (slots, (unit.channels[f].family.ctype * unit.channels[f].n_out)())
                                              for f, slots in early.items()}
        self._tear_slots = [self._tears(stage) for stage in self._loops]
        self._run_chunk = self._compile()

    def connection_ops(self, name: str) -> list[tuple]:
        """Every input of component ``name`` as (family, index, source unit, source family, slot,
        factor, offset): its value is the source's read value * factor + offset."""
        unit = self._unit[name]
        return ([(unit.real, d, source, source.real, s, f, o) for d, source, s, f, o in self._ops[name]]
                + self._typed_ops[name])

    def _tears(self, stage):
        """For each torn input value (every connected element of a torn array): (unit, input index,
        source unit, source slot, factor, offset)."""
        slots = []
        for component, connector in dict.fromkeys(stage.tears):  # an array fed by two connections is torn once
            unit = self._unit[component]
            family, values = unit.slots(connector, inputs=True)
            if family != unit.real:
                raise AlgebraicLoopError(f"algebraic loop through {', '.join(stage.loop_variables)}: the master iterates "
                                         f"on floating-point inputs only, and {component}.{connector} is {family}",
                                         stage.loop_variables)
            for index, source, s, f, o in self._ops[component]:
                if index in values:
                    slots.append((unit, index, source, s, f, o))
        return slots

    # ----------------------------------------------------------------------------- code generation
    def _compile(self):
        """``run_chunk(k0, k1, row, t0, h, t_stop, last, buf, every)`` for this system and scheme:
        the compiled C loop where the system allows it, else the generated Python one."""
        blocks = step_program.plan(self)
        self.loop_reason = step_program.python_only_reason(self, blocks) if self.native else "native=False"
        native = step_program.native_chunk(self, blocks) if self.loop_reason is None else None
        self.loop_kind = "C" if native else "Python"
        return native or step_program.python_chunk(self, blocks)

    def _reads_only_to_record(self, name: str) -> bool:
        """Whether every connected output of ``name`` is passed on as read before its step, so the
        read after the step serves the record only (and can wait for a recording step)."""
        if name not in self._early:
            return False
        early = self._early[name]
        return all(s in early.get(g, ((), None))[0] for other in self._unit
                   for _, _, source, g, s, _, _ in self.connection_ops(other) if source.name == name)

    def _fail(self, i, call, t, status):
        raise FMUFailure(self.units[i], call, status, time=t)

    # ----------------------------------------------------------------------------- running
    def run(self, stop_time: float, parameters: dict[str, float] | None = None) -> np.ndarray:
        """Initialise, step to ``stop_time`` and return the recorded results (structured array).

        ``parameters`` ({"component.variable": value}) apply to this run only, over the system's
        parameter bindings; values (or their text) are typed by each variable's declared type. A
        second call starts again from a reset (see :meth:`reset`). A run that an FMU ended early
        returns the rows up to that time, and ``termination`` says who ended it.
        """
        if self._state == "closed":
            raise ValueError("this Master is closed")
        t0 = self.system.start_time
        if not (math.isfinite(stop_time) and stop_time > t0):
            raise ValueError(f"stop_time must be a finite number > start time {t0!r} s, got {stop_time!r}")
        grouped = self._check_parameters(parameters or {})
        if self._state != "instantiated":
            self.reset()
        self._state = "running"
        span = (stop_time - t0) / self.step
        check_size(span, "MAX_MACRO_STEPS", f"a run from {t0!r} s to {stop_time!r} s by steps of {self.step!r} s takes",
                   "macro steps", "take a longer step or a shorter run")
        n_steps = max(1, math.ceil(span - 1e-9))
        last = n_steps - 1
        # An output interval longer than the run records its end only; the compiled loop's integers
        # then stay within the run's step count (an interval of 1e300 s is no overflow).
        every = min(self.output_interval, n_steps)
        rows = 1 + n_steps // every + (1 if n_steps % every else 0)
        dtype = step_program.buffer_dtype(self)
        _check_result_size(rows, dtype.itemsize, len(self.record), stop_time - t0, self.step * self.output_interval)
        buf = np.empty(rows, dtype=dtype)
        self._buf, self._row = buf, 0
        self.termination = None
        t = t0
        bar = None
        try:
            self._initialize(t0, grouped)
            buf[0] = self._record_row(t0)
            self._row = 1
            if any(u.terminated_at is not None for u in self.units):
                self._stop(0, buf, -1)  # asked to end during initialisation: the record at t0 is the last
                self._row = 1
            chunk = max(1, min(n_steps, 10000, n_steps // 100 or 1))
            bar = _ProgressBar(n_steps) if self.progress else None
            for k0 in range(0, n_steps if self.termination is None else 0, chunk):
                t = t0 + k0 * self.step
                k1 = min(n_steps, k0 + chunk)
                self._row = self._run_chunk(k0, k1, self._row, t0, self.step, stop_time, last, buf, every)
                if bar:
                    bar.update(k1)
                if self.termination is not None:
                    break
            if bar:
                bar.close()
        except FMUFailure as failure:
            self._state = "failed"
            if bar:
                bar.close()  # the message that follows gets a line of its own
            raise self._error(failure, failure.time if failure.time is not None else t, buf[: self._row].copy()) from None
        except KeyboardInterrupt:
            self._state = "failed"
            if bar:
                bar.close()
            raise CosimInterrupted(t, buf[: self._row].copy()) from None
        self._state = "finished"
        return buf[: self._row]

    def _record_row(self, t: float) -> tuple:
        row = [t]
        for c, f, s in self._record_sources:
            value = self._unit[c].channels[f].out_val[s]
            row.append((value or b"").decode(errors="replace") if f == "String" else value)
        return tuple(row)

    def _stop(self, row: int, buf: np.ndarray, k: int) -> int:
        """An FMU asked to end the simulation in macro step ``k``: record the row at the earliest
        requested time (every component has finished the step) and note who stopped the run."""
        unit = min((u for u in self.units if u.terminated_at is not None), key=lambda u: u.terminated_at)
        self.termination = Termination(unit.name, unit.terminated_at, unit.termination_call)
        if k >= 0:
            buf[row] = self._record_row(unit.terminated_at)
            row += 1
        return row

    def _check_parameters(self, parameters: dict) -> dict[str, dict]:
        grouped = {u.name: {} for u in self.units}
        for reference, value in parameters.items():
            component, variable = _split(reference, "parameter name")
            if component not in self._unit:
                raise ValueError(f"parameter {reference!r} names unknown component {component!r}")
            unit = self._unit[component]
            name, indices = unit.elements(variable)
            declared = unit.variables[name]
            kind = kind_of(declared)
            if kind is None:
                raise ValueError(f"parameter {reference!r} has type {declared.type}, which cannot be set by value")
            # typed by the model description: "--set shaper.kind=zvd", "--set a.flag=true"
            items = enumeration_items(unit.description, declared)
            if variable == name and array_size(declared) is not None:  # a whole array: its elements
                for i, item in zip(indices, array_values(value, len(indices), f"parameter {reference}")):
                    grouped[component][f"{name}[{i + 1}]"] = typed_value(item, kind, items, f"parameter {reference}[{i + 1}]",
                                                                         declared.type)
            else:
                grouped[component][variable] = typed_value(value, kind, items, f"parameter {reference}", declared.type)
        return grouped

    def _error(self, failure: FMUFailure, t, partial) -> CosimError:
        unit = failure.unit
        detail = f"; FMU log: {' | '.join(unit.messages)}" if unit.messages else ""
        when = f"t = {t:.9g} s" if t is not None else "set-up"
        return CosimError(f"component {unit.name!r} ({unit.fmu_path.name}): {failure.call} returned {failure.status} "
                          f"at {when}{detail}", component=unit.name, call=failure.call, time=t, partial=partial)

    def _initialize(self, t0: float, parameters: dict[str, dict]) -> None:
        for unit in self.units:
            unit.setup(t0)
            unit.apply_values({**self._bindings[unit.name], **parameters[unit.name]})
            unit.enter_initialization()
        if self.algorithm == "jacobi":
            for _ in range(len(self.units)):
                for unit in self.units:
                    unit.read()
                self._transfer_all()
                for unit in self.units:
                    unit.set_inputs()
        else:
            loop_number = 0
            for stage in self.stages:
                if stage.is_loop:
                    self._solve_loop(loop_number, t0, 0.0, initializing=True)
                    loop_number += 1
                    continue
                unit = self._unit[stage.components[0]]
                self._transfer(unit)
                unit.set_inputs()
                unit.read()
        for unit in self.units:
            unit.exit_initialization(t0, self.tolerance)
        for unit in self.units:
            unit.read()
            for f, (_, early) in self._early.get(unit.name, {}).items():
                early[:] = unit.channels[f].out_val[: unit.channels[f].n_out]

    def _transfer(self, unit) -> None:
        values = unit.in_val
        for d, source, s, f, o in self._ops[unit.name]:
            values[d] = source.out_val[s] * f + o
        for f, d, source, g, s, factor, offset in self._typed_ops[unit.name]:
            value = source.channels[g].out_val[s]
            unit.channels[f].in_val[d] = value * factor + offset if factor != 1.0 or offset != 0.0 else value

    def _transfer_all(self) -> None:
        for unit in self.units:
            self._transfer(unit)

    def _solve_loop(self, number: int, t: float, dt: float, initializing: bool = False) -> None:
        """Step a loop group so its torn inputs equal the outputs feeding them (module docstring)."""
        stage, slots = self._loops[number], self._tear_slots[number]
        units = [self._unit[n] for n in stage.components]
        if not initializing:
            for unit in units:
                unit.save_state()
        evaluations = 0

        def evaluate(x):
            nonlocal evaluations
            if evaluations and not initializing:
                for unit in units:
                    unit.restore_state()
            evaluations += 1
            for unit in units:
                self._transfer(unit)
                for (owner, d, *_), value in zip(slots, x):
                    if owner is unit:
                        unit.in_val[d] = value
                unit.set_inputs()
                if not initializing:
                    unit.step(t, dt, final=False)  # it may be repeated from the saved state
                unit.read()
            return np.array([source.out_val[s] * f + o for _, _, source, s, f, o in slots])

        x = np.array([source.out_val[s] * f + o for _, _, source, s, f, o in slots])
        gx = evaluate(x)
        for _ in range(self.max_loop_iterations):
            residual = gx - x
            if np.max(np.abs(residual)) <= self.loop_tolerance * (1.0 + np.max(np.abs(x))):
                return
            if self.loop_solver == "fixed-point":
                x = gx
            else:
                jacobian = np.empty((len(x), len(x)))
                for j in range(len(x)):
                    delta = 1e-7 * max(1.0, abs(x[j]))
                    shifted = x.copy()
                    shifted[j] += delta
                    jacobian[:, j] = (evaluate(shifted) - gx) / delta
                try:
                    x = x - np.linalg.solve(jacobian - np.eye(len(x)), residual)
                except np.linalg.LinAlgError:
                    raise FMUFailure(units[0], f"algebraic loop through {', '.join(stage.loop_variables)} (singular Newton matrix)",
                                     "no solution", time=t) from None
            gx = evaluate(x)
        raise FMUFailure(units[0], f"algebraic loop through {', '.join(stage.loop_variables)}",
                         f"no convergence in {self.max_loop_iterations} iterations (residual {np.max(np.abs(gx - x)):.3g})", time=t)

    def reset(self) -> None:
        """Back to the freshly instantiated state; the next run applies the SSP parameter bindings
        again at its initialisation.

        Uses ``fmi2Reset`` on every FMU (no re-extraction or re-loading).
        """
        if self._state == "closed":
            raise ValueError("this Master is closed")
        try:
            for unit in self.units:
                unit.reset()
        except FMUFailure as failure:
            raise self._error(failure, None, None) from None
        self._state = "instantiated"

    def close(self) -> None:
        """Free every FMU instance and remove the extracted files."""
        release = getattr(self, "_finalizer", None)  # absent if the constructor failed before loading
        if release is not None:
            release()  # a weakref.finalize runs once: closing twice is harmless
        self.units, self._folders = [], []
        self._state = "closed"

    def __enter__(self) -> Master:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _release(units, folders) -> None:
    """Free the FMU instances ``units`` and remove the extracted FMU folders ``folders``."""
    for unit in units:
        unit.free()
    for folder in folders:
        shutil.rmtree(folder, ignore_errors=True)


class _ProgressBar:
    """A one-line progress bar on stderr, updated at most ten times a second."""

    def __init__(self, total: int):
        self.total, self.start, self.shown = total, wallclock.perf_counter(), 0.0

    def update(self, done: int) -> None:
        now = wallclock.perf_counter()
        if now - self.shown < 0.1 and done < self.total:
            return
        self.shown = now
        fraction = done / self.total
        rate = done / max(now - self.start, 1e-9)
        bar = "#" * int(30 * fraction)
        sys.stderr.write(f"\r[{bar:<30}] {100 * fraction:5.1f} %  {rate:,.0f} steps/s")
        sys.stderr.flush()

    def close(self) -> None:
        sys.stderr.write("\n")


def simulate(system_or_path, stop_time: float, step: float, *, parameters: dict | None = None, **kwargs) -> np.ndarray:
    """Run ``system_or_path`` once with :class:`Master` and return the recorded results."""
    with Master(system_or_path, step, **kwargs) as master:
        return master.run(stop_time, parameters=parameters)


def _check_result_size(rows: int, row_bytes: int, variables: int, span: float, interval: float) -> None:
    """Refuse, before the first step, a run whose recorded results would not fit in memory."""
    check_size(rows * row_bytes, "MAX_RESULT_BYTES",
               f"recording {variables} variable(s) every {interval!r} s over {span!r} s ({rows:.4g} rows) needs",
               "bytes", "record fewer variables (--record) or less often (--output-interval)")
