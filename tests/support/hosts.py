"""One FMI 2.0 Co-Simulation FMU run in fmpy, libcosimpy and ecospy, with one signature.

    run_fmpy(fmu, inputs, step, outputs=None, start_values=None) -> rows
    run_libcosim(...), run_ecos(...): the same, in libcosimpy and ecospy
    HOSTS: {"fmpy": run_fmpy, "libcosim": run_libcosim, "ecos": run_ecos}
    y_of_u(run, fmu, commands, step) -> [y after each step], a u -> y FMU fed commands[k] over step k
    run_ecos_program(fmu, step=..., stop_time=..., workdir=...) -> {column: values}: the ecos
        command-line program (C++, no Python of its own) with an emptied environment

``inputs`` holds one ``{input name: value}`` per step, set at the step's start and held over it: its
length is the number of steps, each of ``step`` from time 0. ``outputs`` lists the variables read
after every step (default: every output). ``start_values`` ({name: value}, typed by the Python type:
bool, int, str, float) are set in initialisation mode. A run returns one row per step: the outputs at
its end, row k at (k + 1) * step. fmpy is driven call by call (its ``simulate_fmu`` would
interpolate the inputs); libcosim counts time in whole nanoseconds, so ``step`` must be one.
"""

from __future__ import annotations

import os
import stat
import subprocess
from pathlib import Path

import numpy as np
from fmpy import read_model_description

from support.fmpy_slaves import configured

from shapefmu.cosim.peer_hosts import tbb_library


def _plan(fmu, outputs):
    """{name: variable} of ``fmu`` and the outputs to read (every output by default)."""
    variables = {v.name: v for v in read_model_description(str(fmu)).modelVariables}
    if outputs is None:
        outputs = [name for name, v in variables.items() if v.causality == "output"]
    return variables, list(outputs)


def run_fmpy(fmu, inputs, step: float, outputs=None, start_values=None) -> list[list[float]]:
    variables, outputs = _plan(fmu, outputs)
    slave, vr = configured(fmu, start_values)
    slave.exitInitializationMode()
    rows = []
    for k, values in enumerate(inputs):
        if values:
            slave.setReal([vr[name] for name in values], list(values.values()))
        slave.doStep(k * step, step)
        rows.append(slave.getReal([vr[name] for name in outputs]))
    slave.terminate()
    slave.freeInstance()
    return rows


_LIBCOSIM_SETTERS = {bool: "boolean_initial_value", int: "integer_initial_value", str: "string_initial_value"}


def run_libcosim(fmu, inputs, step: float, outputs=None, start_values=None) -> list[list[float]]:
    """One local slave, initial values, an override manipulator for the inputs and a last-value
    observer read after every step."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    variables, outputs = _plan(fmu, outputs)
    step_ns = round(step * 1e9)
    if abs(step_ns * 1e-9 - step) > 1e-15 * step_ns:
        raise ValueError(f"libcosim needs a step that is a whole number of nanoseconds, got {step}")
    execution = CosimExecution.from_step_size(step_size=step_ns)
    index = execution.add_local_slave(CosimLocalSlave(fmu_path=str(Path(fmu).resolve()), instance_name="instance"))
    for name, value in (start_values or {}).items():
        setter = getattr(execution, _LIBCOSIM_SETTERS.get(type(value), "real_initial_value"))
        setter(index, variables[name].valueReference, value if type(value) in _LIBCOSIM_SETTERS else float(value))
    override = CosimManipulator.create_override()
    execution.add_manipulator(override)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    output_refs = [variables[name].valueReference for name in outputs]
    rows = []
    for k, values in enumerate(inputs):
        if values:
            override.slave_real_values(index, [variables[name].valueReference for name in values], list(values.values()))
        if not execution.step():
            raise RuntimeError(f"libcosim failed at step {k} of {fmu}")
        rows.append(observer.last_real_values(index, output_refs))
    execution.stop()
    return rows


def run_ecos(fmu, inputs, step: float, outputs=None, start_values=None) -> list[list[float]]:
    """A simulation structure of one model, a parameter set for the start values, and set_real /
    get_real around every step (identifiers are ``instance::variable``)."""
    from ecospy.EcosSimulation import EcosSimulation
    from ecospy.EcosSimulationStructure import EcosSimulationStructure

    _, outputs = _plan(fmu, outputs)
    rows = []
    with EcosSimulationStructure() as structure:
        structure.add_model("instance", str(Path(fmu).resolve()))
        if start_values:
            structure.add_parameter_set("start", {f"instance::{name}": value for name, value in start_values.items()})
        with EcosSimulation(structure=structure, step_size=step) as simulation:
            if not simulation.init(parameter_set="start" if start_values else None):
                raise RuntimeError(f"ecos could not initialise {fmu}")
            for values in inputs:
                for name, value in values.items():
                    simulation.set_real(f"instance::{name}", value)
                simulation.step(1)
                rows.append([simulation.get_real(f"instance::{name}") for name in outputs])
            simulation.terminate()
    return rows


HOSTS = {"fmpy": run_fmpy, "libcosim": run_libcosim, "ecos": run_ecos}


def y_of_u(run, fmu, commands, step: float) -> list[float]:
    """``run`` (one of HOSTS) on a u -> y FMU with u = ``commands[k]`` over step k: y after each step."""
    return [y for (y,) in run(fmu, [{"u": u} for u in commands], step, ["y"])]


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
