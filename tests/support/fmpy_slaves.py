"""One FMI 2.0 Co-Simulation FMU as an fmpy FMU2Slave, through its life cycle and over any steps.

    variable_references(fmu) -> {name: value reference}
    instantiated(fmu, instance_name) -> slave          (the caller sets it up and frees it)
    configured(fmu, parameters) -> (slave, vr)         in initialisation mode, parameters set
    initialised(fmu, parameters) -> (slave, vr)        after fmi2ExitInitializationMode
    set_start_values(slave, vr, values)                each with the setter of its Python type
    refused_initialisation(fmu, parameters) -> the FMICallException of a refused exit of initialisation
    refused_start_values(fmu, parameters) -> the FMICallException of a refused set (or exit of initialisation)
    run_points(fmu, times, inputs, outputs, ...) -> rows over the communication points ``times``
    y_after_each_set(fmu, commands, steps) -> y of a u -> y FMU read right after each u is set
    replayed_run(fmu, times, inputs, outputs, save_at, replay_inputs, ...) -> (rows, replayed rows)
    assert_state_restores_exactly, assert_nan_input_fails_that_step_only: a u -> y FMU's state contract
"""

from __future__ import annotations

from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave


def variable_references(fmu) -> dict:
    return {v.name: v.valueReference for v in read_model_description(str(fmu)).modelVariables}


def instantiated(fmu, instance_name: str = "instance") -> FMU2Slave:
    """An instantiated fmpy FMU2Slave (the caller initialises and frees it)."""
    md = read_model_description(str(fmu))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)), modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName=instance_name)
    slave.instantiate()
    return slave


def set_start_values(slave, vr: dict, values: dict) -> None:
    """Set variables of any type, each with the setter of its value's Python type."""
    for name, value in values.items():
        if isinstance(value, bool):
            slave.setBoolean([vr[name]], [value])
        elif isinstance(value, int):
            slave.setInteger([vr[name]], [value])
        elif isinstance(value, str):
            slave.setString([vr[name]], [value])
        else:
            slave.setReal([vr[name]], [value])


def configured(fmu, parameters=None, instance_name: str = "instance"):
    """(slave, vr): an fmpy slave in initialisation mode with ``parameters`` set (the caller exits it)."""
    vr = variable_references(fmu)
    slave = instantiated(fmu, instance_name)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    set_start_values(slave, vr, parameters or {})
    return slave, vr


def initialised(fmu, parameters=None):
    """(slave, vr): an fmpy slave after fmi2ExitInitializationMode, with ``parameters`` set."""
    slave, vr = configured(fmu, parameters)
    slave.exitInitializationMode()
    return slave, vr


def refused_initialisation(fmu, parameters) -> FMICallException:
    """The exception with which an instance "bad" refuses ``parameters`` at the exit of
    initialisation (the test fails if it accepts them); the instance is freed."""
    import pytest

    slave, _ = configured(fmu, parameters, "bad")
    with pytest.raises(FMICallException) as failure:
        slave.exitInitializationMode()
    slave.freeInstance()
    return failure.value


def refused_start_values(fmu, parameters, when_set: bool = False) -> FMICallException:
    """The exception with which an instance "bad" refuses ``parameters``: when one is set, if the
    value alone is out of range, else at the exit of initialisation (``when_set``: only the former
    counts); the instance is freed."""
    import pytest

    slave = instantiated(fmu, "bad")
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    with pytest.raises(FMICallException) as failure:
        set_start_values(slave, variable_references(fmu), parameters)
        if not when_set:
            slave.exitInitializationMode()
    slave.freeInstance()
    return failure.value


def replayed_run(fmu, times, inputs, outputs, save_at=None, replay_inputs=None, *, parameters=None,
                 read_before: bool = False):
    """(rows, replayed rows) of a run over the communication points ``times`` (step k from
    times[k] to times[k + 1]) with ``inputs[k]`` ({name: value}) set before step k and ``outputs``
    read after it (``read_before``: also right after the inputs are set, before the step).
    ``parameters`` are set in initialisation. With ``save_at``, the FMU state taken before step
    ``save_at`` (serialised and read back) is restored after the run, and the steps from ``save_at``
    on run again with ``replay_inputs``: the replayed rows (else None)."""
    slave, vr = initialised(fmu, parameters)
    read = [vr[name] for name in outputs]
    state = None

    def run(first, values_at):
        nonlocal state
        rows = []
        for k in range(first, len(times) - 1):
            if k == save_at and state is None:
                taken = slave.getFMUstate()
                state = slave.deSerializeFMUstate(slave.serializeFMUstate(taken))
                slave.freeFMUstate(taken)
            if values_at[k]:
                slave.setReal([vr[name] for name in values_at[k]], list(values_at[k].values()))
            if read_before:
                rows.append(slave.getReal(read))
            slave.doStep(times[k], times[k + 1] - times[k])
            rows.append(slave.getReal(read))
        return rows

    rows, replayed = run(0, inputs), None
    if save_at is not None:
        slave.setFMUstate(state)
        replayed = run(save_at, replay_inputs)
        slave.freeFMUstate(state)
    slave.terminate()
    slave.freeInstance()
    return rows, replayed


def run_points(fmu, times, inputs, outputs, *, parameters=None, read_before: bool = False) -> list[list[float]]:
    """The rows of ``replayed_run`` without a replay."""
    return replayed_run(fmu, times, inputs, outputs, parameters=parameters, read_before=read_before)[0]


def y_after_each_set(fmu, commands, steps, parameters=None) -> list[float]:
    """y of a u -> y FMU read right after u = ``commands[k]`` is set at the start of step k (what
    feeds through), ``steps[k]`` = (communication point, step size)."""
    slave, vr = initialised(fmu, parameters)
    out = []
    for u, (t, h) in zip(commands, steps):
        slave.setReal([vr["u"]], [u])
        out.append(slave.getReal([vr["y"]])[0])
        slave.doStep(t, h)
    slave.terminate()
    slave.freeInstance()
    return out


def _step_u(slave, vr, commands, start, h):
    """Steps ``start``, ``start + 1``, ... of ``h`` with ``u`` = each command; ``y`` after each."""
    out = []
    for k, u in enumerate(commands, start=start):
        slave.setReal([vr["u"]], [u])
        slave.doStep(k * h, h)
        out.append(slave.getReal([vr["y"]])[0])
    return out


def assert_state_restores_exactly(fmu, commands, h, at):
    """fmi2GetFMUstate after ``at`` steps, run on, fmi2SetFMUstate, run on again: bit for bit the
    same outputs, and those of an uninterrupted run; then the same through a serialised state
    restored in a fresh instance."""
    slave, vr = initialised(fmu)
    _step_u(slave, vr, commands[:at], 0, h)
    state = slave.getFMUState()
    first = _step_u(slave, vr, commands[at:], at, h)
    slave.setFMUState(state)
    again = _step_u(slave, vr, commands[at:], at, h)
    raw = slave.serializeFMUState(state)
    slave.freeFMUState(state)
    slave.freeInstance()
    assert again == first
    fresh, vr = initialised(fmu)
    assert first == _step_u(fresh, vr, commands, 0, h)[at:]
    fresh.freeInstance()
    fresh, vr = initialised(fmu)
    fresh.setFMUState(fresh.deserializeFMUState(raw))
    assert _step_u(fresh, vr, commands[at:], at, h) == first
    fresh.freeInstance()


def assert_nan_input_fails_that_step_only(fmu, commands, h, at):
    """A NaN ``u`` at step ``at``: that fmi2DoStep returns fmi2Error and leaves the state as it was,
    so the run goes on as if the step had not been asked for."""
    import pytest

    slave, vr = initialised(fmu)
    out = _step_u(slave, vr, commands[:at], 0, h)
    slave.setReal([vr["u"]], [float("nan")])
    with pytest.raises(FMICallException) as failure:
        slave.doStep(at * h, h)
    assert failure.value.status == 3
    out += _step_u(slave, vr, commands[at:], at, h)
    slave.freeInstance()
    fresh, vr = initialised(fmu)
    assert out == _step_u(fresh, vr, commands, 0, h)
    fresh.freeInstance()
