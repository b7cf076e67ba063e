"""Drive one FMU through fmpy, libcosimpy and ecospy with named inputs and outputs.

The FMUs of the profile, EKF, reference and STOS tests have other variables than the shaper's
``u``/``y`` (``fmu_drivers``). Each ``run_*`` takes ``inputs``, one ``{name: value}`` per
communication point, sets them, takes one step of ``h`` and reads ``outputs``: a list of rows, one
per step, of the outputs at the end of the step.
"""

from pathlib import Path

from fmu_drivers import configured


def run_fmpy(path, inputs, h, outputs, start_values=None):
    slave, vr = configured(path, start_values)
    slave.exitInitializationMode()
    rows = []
    for k, values in enumerate(inputs):
        for name, value in values.items():
            slave.setReal([vr[name]], [value])
        slave.doStep(k * h, h)
        rows.append(slave.getReal([vr[name] for name in outputs]))
    slave.terminate()
    slave.freeInstance()
    return rows


def run_libcosim(path, inputs, h, outputs):
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    execution = CosimExecution.from_step_size(step_size=round(h * 1e9))  # libcosim counts nanoseconds
    index = execution.add_local_slave(CosimLocalSlave(fmu_path=str(Path(path)), instance_name="instance"))
    vr = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
    override = CosimManipulator.create_override()
    execution.add_manipulator(override)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    rows = []
    for values in inputs:
        if values:
            override.slave_real_values(index, [vr[name] for name in values], list(values.values()))
        execution.step()
        rows.append(observer.last_real_values(index, [vr[name] for name in outputs]))
    return rows


def run_ecos(path, inputs, h, outputs):
    from ecospy.EcosSimulation import EcosSimulation
    from ecospy.EcosSimulationStructure import EcosSimulationStructure

    rows = []
    with EcosSimulationStructure() as structure:
        structure.add_model("instance", str(Path(path)))
        with EcosSimulation(structure=structure, step_size=h) as simulation:
            simulation.init()
            for values in inputs:
                for name, value in values.items():
                    simulation.set_real(f"instance::{name}", value)
                simulation.step(1)
                rows.append([simulation.get_real(f"instance::{name}") for name in outputs])
            simulation.terminate()
    return rows
