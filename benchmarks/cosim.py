"""Steps per second of two systems in our master, libcosimpy, ecospy and a minimal hand-written
fmpy loop, measured side by side in one run (10^5 macro steps of 1 us each):

* shaper -> disk drive: the pythonfmu Shaper FMU feeding the native plant FMU. The Shaper's
  fmi2DoStep runs Python inside the FMU (about 2 us a step) in every host alike, which bounds every
  host's rate: ours, whose compiled loop adds little to it, cannot be 3x a host that adds less
  than twice that (ecos at its best adds about 1.4 us);
* native shaper -> disk drive: the same system with the native C Shaper (``shapefmu build shaper
  --native``): no Python in any FMU, so the hosts' own per-step overhead shows;
* disk drive -> disk drive: two native plant FMUs, the first one's position driving the second
  one's voltage. Each FMU step costs well under 0.1 us of C.

For the all-native systems, the limit no master can beat: a hand-written C loop calling the same
two FMUs' functions directly (benchmarks/fmu_loop.c: set input, doStep, get output).

Then a 10^6-step run of the plant alone with tracemalloc: memory stays flat apart from the results.

Goals (issue 9): ours >= 3x libcosimpy and ecospy, >= 0.9x the hand-written loop. Goals for the
native shaper -> disk drive system: ours >= 3x ecospy, >= 30x libcosimpy, >= 0.8 of the C loop.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from native_loop import c_loop_seconds

from shapefmu.cosim import Master
from shapefmu.cosim.peer_hosts import preload_tbb
from shapefmu.fmi import build_fmu
from shapefmu.fmi.native import build_plant_fmu
from shapefmu.fmi.native.sampled import build_native_fmu
from shapefmu.fmi.ssp import PARAMETER_SET, System

STEP = 1e-6
STEPS = 100_000
SHAPER = {"kind": "zvd", "f[1]": 2000.0, "zeta[1]": 0.01, "Ts": STEP, "u": 1.0}


def shaped_system(folder: Path) -> System:
    shaper = build_fmu("Shaper", folder / "Shaper.fmu")
    plant = build_plant_fmu("models/disk_drive.toml", folder / "DiskDrive.fmu")
    return (System("bench").add("source", shaper, SHAPER).add("plant", plant)
            .connect("source.y", "plant.voltage", factor=11.0))


def native_shaper_system(folder: Path) -> System:
    """The shaped system with the native C Shaper, built with the same design (and u = 1 baked in)."""
    shaper = build_native_fmu("Shaper", folder / "NativeShaper.fmu", **SHAPER)
    return (System("native_shaper").add("source", shaper, SHAPER).add("plant", folder / "DiskDrive.fmu")
            .connect("source.y", "plant.voltage", factor=11.0))


def native_system(folder: Path) -> System:
    """Both FMUs native: a disk drive under 1 V drives a second one with its position (rad -> V)."""
    plant = folder / "DiskDrive.fmu"
    return (System("native").add("source", plant, {"voltage": 1.0}).add("plant", plant)
            .connect("source.position", "plant.voltage", factor=11.0))


def ours(ssp: Path, algorithm: str) -> float:
    with Master(ssp, STEP, algorithm=algorithm, record=["plant.position"], output_interval=100 * STEP) as master:
        start = time.perf_counter()
        master.run(STEPS * STEP)
        return time.perf_counter() - start


def libcosim(ssp: Path) -> float:
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level

    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_ssp_file(str(ssp), step_size=round(STEP * 1e9))
    start = time.perf_counter()
    execution.step(STEPS)
    return time.perf_counter() - start


def ecos(ssp: Path) -> float:
    """ecospy at its best: its threads confined to one core. Free to use both cores of this machine,
    ecos handing each step between threads on different cores ran the shaper system 4-5x slower
    (about 55,000 against 265,000 steps per second, measured here)."""
    preload_tbb()  # ecospy's libtbb.so.12, from the tbb wheel (no Debian libtbb12 needed)
    from ecospy.EcosSimulation import EcosSimulation

    cores = os.sched_getaffinity(0)
    os.sched_setaffinity(0, {min(cores)})  # this thread, and the threads ecos starts from it
    try:
        simulation = EcosSimulation(ssp_path=str(ssp), step_size=STEP)
        simulation.init(parameter_set=PARAMETER_SET)
        start = time.perf_counter()
        simulation.step(STEPS)
        elapsed = time.perf_counter() - start
        simulation.terminate()
        simulation.free()
    finally:
        os.sched_setaffinity(0, cores)
    return elapsed


def hand_written(sys_: System) -> float:
    """What a user writes with fmpy's FMU2Slave: set, step and get each FMU in turn (Jacobi)."""
    slaves = {}
    for name, component in sys_.components.items():
        description = read_model_description(str(component.fmu))
        slave = FMU2Slave(guid=description.guid, unzipDirectory=extract(str(component.fmu)),
                          modelIdentifier=description.coSimulation.modelIdentifier, instanceName=name)
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        variables = {v.name: v for v in description.modelVariables}
        for key, value in sys_.parameter_values(name).items():
            vr = [variables[key].valueReference]
            if variables[key].type == "String":
                slave.setString(vr, [value])
            elif variables[key].type == "Integer":
                slave.setInteger(vr, [int(value)])
            else:
                slave.setReal(vr, [float(value)])
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        slaves[name] = (slave, variables)
    (connection,) = sys_.connections
    source, sv = slaves["source"]
    plant, pv = slaves["plant"]
    y, voltage = [sv[connection.start_connector].valueReference], [pv["voltage"].valueReference]
    position = [pv["position"].valueReference]
    factor = connection.factor
    start = time.perf_counter()
    command = source.getReal(y)[0]
    for k in range(STEPS):
        t = k * STEP
        plant.setReal(voltage, [factor * command])
        source.doStep(t, STEP)
        plant.doStep(t, STEP)
        command = source.getReal(y)[0]
        if k % 100 == 99:
            plant.getReal(position)
    elapsed = time.perf_counter() - start
    for slave, _ in slaves.values():
        slave.terminate()
        slave.freeInstance()
    return elapsed


def memory(folder: Path) -> tuple[int, int]:
    """tracemalloc growth (bytes) between a 10^5- and a 10^6-step run of the plant, few records."""
    plant = System("plant").add("plant", folder / "DiskDrive.fmu", {"voltage": 1.0})
    with Master(plant, STEP, record=["plant.position"], output_interval=1e5 * STEP) as master:
        master.run(1e4 * STEP)
        tracemalloc.start()
        master.run(1e5 * STEP)
        _, short = tracemalloc.get_traced_memory()
        tracemalloc.reset_peak()
        start = time.perf_counter()
        master.run(1e6 * STEP)
        elapsed = time.perf_counter() - start
        _, long = tracemalloc.get_traced_memory()
        tracemalloc.stop()
    return long - short, elapsed


def c_loop(sys_: System) -> float:
    """fmu_loop.c over the system's two FMUs (source -> plant), both native; NaN for a pythonfmu one."""
    (connection,) = sys_.connections
    source, plant = sys_.components["source"].fmu, sys_.components["plant"].fmu
    if read_model_description(str(source)).generationTool.endswith("export library)"):
        return float("nan")
    return c_loop_seconds(STEPS, STEP, [(source, "voltage" if "voltage" in _names(source) else "u",
                                         connection.start_connector), (plant, "voltage", "position")],
                          factor=connection.factor)


def _names(fmu) -> set[str]:
    return {v.name for v in read_model_description(str(fmu)).modelVariables}


HOSTS = ("shapefmu master (jacobi)", "shapefmu master (gauss-seidel)", "libcosimpy", "ecospy", "hand-written fmpy loop",
         "hand-written C loop")
GOALS = {"shaper -> disk drive": (("libcosimpy", 3.0), ("ecospy", 3.0), ("hand-written fmpy loop", 0.9)),
         "native shaper -> disk drive": (("libcosimpy", 30.0), ("ecospy", 3.0), ("hand-written C loop", 0.8)),
         "disk drive -> disk drive": (("libcosimpy", 3.0), ("ecospy", 3.0), ("hand-written fmpy loop", 0.9),
                                      ("hand-written C loop", None))}


REPEATS = 3


def rates_of(sys_: System, ssp: Path) -> dict[str, float]:
    """Each host's best of REPEATS runs, the hosts taking turns, so that a burst of load from
    other processes on a shared machine (or ecos's thread scheduling) does not decide a ratio."""
    runs = (lambda: ours(ssp, "jacobi"), lambda: ours(ssp, "gauss-seidel"), lambda: libcosim(ssp),
            lambda: ecos(ssp), lambda: hand_written(sys_), lambda: c_loop(sys_))
    best = [min(times) for times in zip(*([run() for run in runs] for _ in range(REPEATS)))]
    return {name: STEPS / seconds for name, seconds in zip(HOSTS, best)}


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        systems = {"shaper -> disk drive": shaped_system(folder),
                   "native shaper -> disk drive": native_shaper_system(folder),
                   "disk drive -> disk drive": native_system(folder)}
        rates = {name: rates_of(sys_, sys_.write_ssp(folder / f"{sys_.name}.ssp")) for name, sys_ in systems.items()}
        names = list(systems)
        print(f"steps per second, {STEPS:,} macro steps of {STEP:g} s, best of {REPEATS}, measured side by side")
        print(f"  {'host':32s}" + "".join(f"{name:>30s}" for name in names))
        for host in HOSTS:
            print(f"  {host:32s}" + "".join(f"{rates[name][host]:30,.0f}" if rates[name][host] == rates[name][host]
                                            else f"{'n/a (Python inside)':>30s}" for name in names))
        peers = dict.fromkeys(peer for goals in GOALS.values() for peer, _ in goals)
        for peer in peers:
            cells = []
            for name in names:
                goal = dict(GOALS[name]).get(peer)
                best = max(rates[name][HOSTS[0]], rates[name][HOSTS[1]])
                ratio = best / rates[name][peer]
                if peer not in dict(GOALS[name]) or ratio != ratio:
                    cell = ""
                elif goal is None:  # measured, no goal set
                    cell = f"{ratio:6.2f}x"
                else:
                    cell = f"{ratio:6.2f}x {'met' if ratio >= goal else 'NOT met':>7s} (>= {goal:g})"
                cells.append(cell)
            print(f"  ours / {peer:24s}" + "".join(f"{cell:>30s}" for cell in cells))
        growth, elapsed = memory(folder)
        print(f"plant alone, 10^6 steps in {elapsed:.2f} s: tracemalloc peak grows by {growth} bytes "
              f"over the 10^5-step run (results: 11 rows)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
