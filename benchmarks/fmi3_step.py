"""Nanoseconds per step of every kind of native FMU as FMI 3.0 beside its FMI 2.0 twin: the same model
part behind the generic FMI 3.0 layer (c/fmi3_layer*.c) and behind the FMI 2.0 one, each stepped by a
hand-written C loop (set the input, doStep, get the output: benchmarks/fmu_loop3.c for FMI 3.0,
benchmarks/fmu_loop.c for FMI 2.0, the same inputs), in the same run. Goal: the FMI 3.0 layer adds at
most 10 % to a step (its value references name variables, which it maps onto the model's values;
a request of scalars, the usual one, takes a fast path). tests/test_native_fmi3.py shows the numbers
are the same.
"""

import subprocess
import tempfile
import zipfile
from pathlib import Path

from fmpy import read_model_description

from native_loop import HEADERS, HERE, c_loop_seconds

from shapefmu.fmi.native import build_plant_fmu
from shapefmu.fmi.native.twins import build_native

STEPS = 1_000_000
REPEATS = 7
# kind -> (builder(path, fmi_version), input, output, step h)
KINDS = {
    "Shaper (zvd, 2 modes)": (lambda path, v: build_native("Shaper", path, fmi_version=v, kind="zvd", n_modes=2,
                                                           Ts=1e-4, **{"f[1]": 13.0, "f[2]": 31.0}), "u", "y", 1e-4),
    "EKFTuner": (lambda path, v: build_native("EKFTuner", path, fmi_version=v), "vibration", "y", 1e-3),
    "STOSController": (lambda path, v: build_native("STOSController", path, fmi_version=v), "x_r", "u", 1e-5),
    "DiskDrive plant": (lambda path, v: build_plant_fmu("disk_drive", path, fmi_version=v), "voltage", "position", 1e-5),
}


def _loop3() -> Path:
    program = Path(tempfile.mkdtemp(prefix="shapefmu-loop3-")) / "fmu_loop3"
    subprocess.run(["gcc", "-O2", "-std=c99", "-I", str(HEADERS), str(HERE / "fmu_loop3.c"), "-o", str(program),
                    "-ldl"], check=True)
    return program


def fmi3_seconds(program: Path, fmu: Path, input_name: str, output_name: str, h: float) -> tuple[float, float]:
    md = read_model_description(str(fmu))
    folder = Path(tempfile.mkdtemp(prefix="shapefmu-loop3-fmu-"))
    zipfile.ZipFile(fmu).extractall(folder)
    library = folder / "binaries" / "x86_64-linux" / f"{md.coSimulation.modelIdentifier}.so"
    vr = {v.name: v.valueReference for v in md.modelVariables}
    completed = subprocess.run([str(program), str(STEPS), repr(h), str(library), md.instantiationToken,
                                str(vr[input_name]), str(vr[output_name])], capture_output=True, text=True, check=True)
    seconds, last = completed.stdout.split()
    return float(seconds), float(last)


def main() -> None:
    program = _loop3()
    folder = Path(tempfile.mkdtemp(prefix="shapefmu-fmi3-bench-"))
    print(f"ns per step (set input, doStep, get output), best of {REPEATS} runs of {STEPS} steps")
    print(f"{'FMU':<24} {'FMI 2.0':>9} {'FMI 3.0':>9} {'3.0 / 2.0':>10}")
    worst = 0.0
    for name, (build, input_name, output_name, h) in KINDS.items():
        two = build(folder / f"{len(name)}_2.fmu", "2.0")
        three = build(folder / f"{len(name)}_3.fmu", "3.0")
        times2, times3 = [], []
        for _ in range(REPEATS):  # alternated, so that both see the machine in the same state
            times2.append(c_loop_seconds(STEPS, h, [(two, input_name, output_name)]))
            seconds, _ = fmi3_seconds(program, three, input_name, output_name, h)
            times3.append(seconds)
        ratio = min(times3) / min(times2)
        worst = max(worst, ratio)
        print(f"{name:<24} {1e9 * min(times2) / STEPS:9.1f} {1e9 * min(times3) / STEPS:9.1f} {ratio:10.3f}")
    print(f"worst ratio {worst:.3f} (goal <= 1.10): {'met' if worst <= 1.10 else 'NOT met'}")


if __name__ == "__main__":
    main()
