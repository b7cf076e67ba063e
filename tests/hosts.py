"""Run one Co-Simulation FMU in three FMI hosts with the same start values, inputs and steps.

    run_fmpy(fmu, step=..., stop_time=..., start_values=None, inputs=None, outputs=None) -> HostRun
    run_libcosim(...), run_ecos(...): the same in libcosimpy and ecospy
    HOSTS: {"fmpy": run_fmpy, "libcosim": run_libcosim, "ecos": run_ecos}
    run_ecos_program(fmu, step=..., stop_time=..., workdir=...) -> {column: values}: the ecos
        command-line program (C++, no Python of its own) with an emptied environment

Generic, for any FMI 2.0 Co-Simulation FMU (the native plants and the pythonfmu FMUs alike):
``start_values`` maps variable names to values set before initialisation (parameters, inputs,
states with initial="exact"); ``inputs`` maps input names to one value per step, held over
that step; ``outputs`` lists the variables to record (default: every output). Each host takes
``round(stop_time / step)`` fixed steps from time 0 and records after every step, so
``HostRun.time[k] = (k + 1) * step``.
"""

from __future__ import annotations

import os
import stat
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from shapefmu.cosim.peer_hosts import tbb_library


@dataclass(frozen=True)
class HostRun:
    """Recorded outputs: ``values[name][k]`` at ``time[k]``."""

    time: np.ndarray
    values: dict


def _plan(fmu, step, stop_time, inputs, outputs):
    model = read_model_description(str(fmu))
    variables = {v.name: v for v in model.modelVariables}
    if outputs is None:
        outputs = [v.name for v in model.modelVariables if v.causality == "output"]
    steps = int(round(stop_time / step))
    if steps < 1 or abs(steps * step - stop_time) > 1e-9 * stop_time:
        raise ValueError(f"stop_time must be a whole number of steps, got stop_time={stop_time}, step={step}")
    inputs = {name: np.asarray(values, dtype=float) for name, values in (inputs or {}).items()}
    for name, values in inputs.items():
        if values.shape != (steps,):
            raise ValueError(f"inputs[{name!r}] must hold one value per step ({steps}), got shape {values.shape}")
    time = step * np.arange(1, steps + 1)
    return model, variables, list(outputs), steps, inputs, time


def run_fmpy(fmu, *, step: float, stop_time: float, start_values=None, inputs=None, outputs=None) -> HostRun:
    """fmpy's FMU2Slave driven step by step (fmpy's simulate_fmu would interpolate the inputs)."""
    model, variables, outputs, steps, inputs, time = _plan(fmu, step, stop_time, inputs, outputs)
    unzipped = extract(str(fmu))
    slave = FMU2Slave(guid=model.guid, unzipDirectory=unzipped, modelIdentifier=model.coSimulation.modelIdentifier,
                      instanceName="plant")
    slave.instantiate()
    try:
        slave.setupExperiment(startTime=0.0)
        for name, value in (start_values or {}).items():
            slave.setReal([variables[name].valueReference], [float(value)])
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        output_refs = [variables[name].valueReference for name in outputs]
        input_refs = [variables[name].valueReference for name in inputs]
        record = np.empty((steps, len(outputs)))
        for k in range(steps):
            if inputs:
                slave.setReal(input_refs, [float(values[k]) for values in inputs.values()])
            slave.doStep(currentCommunicationPoint=k * step, communicationStepSize=step)
            record[k] = slave.getReal(output_refs)
        slave.terminate()
    finally:
        slave.freeInstance()
    return HostRun(time, {name: record[:, i] for i, name in enumerate(outputs)})


def run_libcosim(fmu, *, step: float, stop_time: float, start_values=None, inputs=None, outputs=None) -> HostRun:
    """libcosimpy: one local slave, initial values, an override manipulator for the inputs, and a
    last-value observer read after every step. libcosim counts time in integer nanoseconds."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    model, variables, outputs, steps, inputs, time = _plan(fmu, step, stop_time, inputs, outputs)
    step_ns = int(round(step * 1e9))
    if abs(step_ns * 1e-9 - step) > 1e-15 * step_ns:
        raise ValueError(f"libcosim needs a step that is a whole number of nanoseconds, got {step}")
    execution = CosimExecution.from_step_size(step_size=step_ns)
    index = execution.add_local_slave(CosimLocalSlave(fmu_path=str(Path(fmu).resolve()), instance_name="plant"))
    for name, value in (start_values or {}).items():
        execution.real_initial_value(index, variables[name].valueReference, float(value))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    manipulator = CosimManipulator.create_override()
    execution.add_manipulator(manipulator)
    output_refs = [variables[name].valueReference for name in outputs]
    record = np.empty((steps, len(outputs)))
    for k in range(steps):
        for name, values in inputs.items():
            manipulator.slave_real_values(index, [variables[name].valueReference], [float(values[k])])
        if not execution.step():
            raise RuntimeError(f"libcosim failed at step {k} of {fmu}")
        record[k] = observer.last_real_values(index, output_refs)
    execution.stop()
    return HostRun(time, {name: record[:, i] for i, name in enumerate(outputs)})


def run_ecos(fmu, *, step: float, stop_time: float, start_values=None, inputs=None, outputs=None) -> HostRun:
    """ecospy: a simulation structure with one model, a parameter set for the start values, and
    set_real / get_real around every step (identifiers are ``instance::variable``)."""
    from ecospy import EcosSimulation, EcosSimulationStructure

    model, variables, outputs, steps, inputs, time = _plan(fmu, step, stop_time, inputs, outputs)
    structure = EcosSimulationStructure()
    structure.add_model("plant", str(Path(fmu).resolve()))
    if start_values:
        structure.add_parameter_set("start", {f"plant::{name}": float(value) for name, value in start_values.items()})
    simulation = EcosSimulation(structure=structure, step_size=step)
    record = np.empty((steps, len(outputs)))
    try:
        if not simulation.init(parameter_set="start" if start_values else None):
            raise RuntimeError(f"ecos could not initialise {fmu}")
        for k in range(steps):
            for name, values in inputs.items():
                simulation.set_real(f"plant::{name}", float(values[k]))
            simulation.step(1)
            record[k] = [simulation.get_real(f"plant::{name}") for name in outputs]
        simulation.terminate()
    finally:
        simulation.free()
        structure.free()
    return HostRun(time, {name: record[:, i] for i, name in enumerate(outputs)})


HOSTS = {"fmpy": run_fmpy, "libcosim": run_libcosim, "ecos": run_ecos}


def _tbb_only_folder(workdir) -> dict:
    """``{"LD_LIBRARY_PATH": folder}`` holding nothing but a link to the wheel's libtbb.so.12 (so
    the ecos program finds oneTBB and nothing else, libpython least of all), or {} without the wheel."""
    library = tbb_library()
    if library is None:
        return {}
    folder = Path(workdir) / "tbb_only"
    folder.mkdir(exist_ok=True)
    link = folder / "libtbb.so.12"
    if not link.exists():
        link.symlink_to(library)
    return {"LD_LIBRARY_PATH": str(folder)}


def run_ecos_program(fmu, *, step: float, stop_time: float, workdir) -> dict:
    """The ecos command-line program shipped in the ecospy wheel, run on one FMU.

    The environment is emptied, so nothing (LD_PRELOAD, PYTHONHOME, the venv) helps the FMU find
    libpython but its own front end; LD_LIBRARY_PATH names only a folder holding oneTBB, which the
    program itself needs (``tbb_library``). Returns the CSV ecos writes as
    ``{column header: values}`` for its real columns (headers such as ``instance::y[REAL]``; ecos
    writes 6 decimals).
    """
    import ecospy

    program = Path(ecospy.__file__).parent / "binaries" / "ecos"
    # pip does not keep the wheel's execute bit on this data file.
    if not os.access(program, os.X_OK):
        program.chmod(program.stat().st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)
    result = subprocess.run(
        [str(program), "simulate", "--path", str(fmu), "--stepSize", repr(step), "--stopTime", repr(stop_time),
         "--noParallel"],
        cwd=workdir, env={"PATH": "/usr/bin:/bin", "HOME": str(workdir), **_tbb_only_folder(workdir)},
        capture_output=True, text=True, timeout=120,
    )
    if result.returncode != 0:
        raise RuntimeError(f"ecos failed on {fmu} (exit {result.returncode}):\n{result.stdout}{result.stderr}")
    (table,) = Path(workdir).glob("*.csv")
    rows = [[cell.strip() for cell in line.split(",")] for line in table.read_text().splitlines() if line.strip()]
    return {
        name: np.array([float(row[i]) for row in rows[1:]]) for i, name in enumerate(rows[0]) if name.endswith("[REAL]")
    }
