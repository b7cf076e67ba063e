"""Drive one FMU through fmpy, libcosimpy and ecospy with the same inputs and steps.

Each ``run_*`` sets ``u`` to ``commands[k]`` at the k-th communication point, takes one step of
``h`` and reads ``y``: the sequence of outputs at the end of each step.
"""


def variable_references(path):
    from fmpy import read_model_description

    return {v.name: v.valueReference for v in read_model_description(str(path)).modelVariables}


def fmpy_slave(path, instance_name="instance"):
    """An instantiated fmpy FMU2Slave (caller initialises, frees)."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(path))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path)), modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName=instance_name)
    slave.instantiate()
    return slave


def set_start_values(slave, vr, values):
    """Set parameters of any type in initialisation mode."""
    for name, value in values.items():
        if isinstance(value, bool):
            slave.setBoolean([vr[name]], [value])
        elif isinstance(value, int):
            slave.setInteger([vr[name]], [value])
        elif isinstance(value, str):
            slave.setString([vr[name]], [value])
        else:
            slave.setReal([vr[name]], [value])


def configured(path, parameters=None, instance_name="instance"):
    """An fmpy slave in initialisation mode with ``parameters`` {name: value} set (caller exits it)."""
    vr = variable_references(path)
    slave = fmpy_slave(path, instance_name)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    set_start_values(slave, vr, parameters or {})
    return slave, vr


def initialised(path, parameters=None):
    """An fmpy slave after fmi2ExitInitializationMode, with ``parameters`` {name: value} set."""
    slave, vr = configured(path, parameters)
    slave.exitInitializationMode()
    return slave, vr


def refused_initialisation(path, parameters):
    """The FMICallException with which an instance "bad" refuses ``parameters`` at the exit of
    initialisation (the test fails if it accepts them); the instance is freed."""
    import pytest
    from fmpy.fmi1 import FMICallException

    slave, _ = configured(path, parameters, "bad")
    with pytest.raises(FMICallException) as failure:
        slave.exitInitializationMode()
    slave.freeInstance()
    return failure.value


def _u_to_y(run, path, commands, h):
    """``run`` (a ``fmu_signal_drivers.run_*``) with input ``u`` = ``commands[k]``, reading ``y``."""
    return [row[0] for row in run(path, [{"u": u} for u in commands], h, ["y"])]


def run_fmpy(path, commands, h):
    import fmu_signal_drivers

    return _u_to_y(fmu_signal_drivers.run_fmpy, path, commands, h)


def run_libcosim(path, commands, h):
    import fmu_signal_drivers

    return _u_to_y(fmu_signal_drivers.run_libcosim, path, commands, h)


def run_ecos(path, commands, h):
    import fmu_signal_drivers

    return _u_to_y(fmu_signal_drivers.run_ecos, path, commands, h)


def step_u(slave, vr, commands, start, h):
    """Steps ``start``, ``start + 1``, ... of ``h`` with ``u`` = each command; ``y`` after each."""
    out = []
    for k, u in enumerate(commands, start=start):
        slave.setReal([vr["u"]], [u])
        slave.doStep(k * h, h)
        out.append(slave.getReal([vr["y"]])[0])
    return out


def assert_state_restores_exactly(path, commands, h, at):
    """fmi2GetFMUstate after ``at`` steps, run on, fmi2SetFMUstate, run on again: bit for bit the
    same outputs, and those of an uninterrupted run; then the same through a serialised state
    restored in a fresh instance."""
    slave, vr = initialised(path)
    step_u(slave, vr, commands[:at], 0, h)
    state = slave.getFMUState()
    first = step_u(slave, vr, commands[at:], at, h)
    slave.setFMUState(state)
    again = step_u(slave, vr, commands[at:], at, h)
    raw = slave.serializeFMUState(state)
    slave.freeFMUState(state)
    slave.freeInstance()
    assert again == first
    assert first == run_fmpy(path, commands, h)[at:]
    fresh, vr = initialised(path)
    fresh.setFMUState(fresh.deserializeFMUState(raw))
    assert step_u(fresh, vr, commands[at:], at, h) == first
    fresh.freeInstance()


def assert_nan_input_fails_that_step_only(path, commands, h, at):
    """A NaN ``u`` at step ``at``: that fmi2DoStep returns fmi2Error and leaves the state as it was,
    so the run goes on as if the step had not been asked for."""
    import pytest
    from fmpy.fmi1 import FMICallException

    slave, vr = initialised(path)
    out = step_u(slave, vr, commands[:at], 0, h)
    slave.setReal([vr["u"]], [float("nan")])
    with pytest.raises(FMICallException) as failure:
        slave.doStep(at * h, h)
    assert failure.value.status == 3
    out += step_u(slave, vr, commands[at:], at, h)
    slave.freeInstance()
    assert out == run_fmpy(path, commands, h)
