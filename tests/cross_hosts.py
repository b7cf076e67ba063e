"""What the cross-platform tests share (tests/test_native_win64.py under Wine,
tests/test_native_aarch64.py under qemu): the C host tests/fmu_host.c, and one plan over every kind
of native FMU (every plant of models/, closed-form and build-time shapers, window, twin-pulse and
time-frequency filters) that each platform's host runs on that platform's binaries."""

import zipfile
from pathlib import Path

from fixtures_native import H
from fmpy import read_model_description

HOST = Path(__file__).parent / "fmu_host.c"
HEADERS = Path(__file__).parent.parent / "src" / "shapefmu" / "fmi" / "native" / "c"
# Per plant: (step, steps, input scale), as tests/test_plantgen_hosts.py drives them.
PLANTS = {"disk_drive": (1e-5, 200, 11.0), "disk_drive_back_emf": (1e-5, 200, 11.0),
          "linear_synchronous_motor": (1e-3, 200, 1.0), "ten_pendula": (1e-2, 300, 0.7),
          "mass_spring_chain": (5e-3, 200, 10.0), "pendulum": (1e-2, 200, 3.0)}


def plan_of(fmu, folder, platform, start_values, steps, h, scale):
    """Plan lines for one FMU (tests/fmu_host.c): its library, start values, input, outputs, run."""
    md = read_model_description(str(fmu))
    identifier = md.coSimulation.modelIdentifier
    unzipped = folder / fmu.stem
    if not unzipped.is_dir():
        zipfile.ZipFile(fmu).extractall(unzipped)
    library = unzipped / "binaries" / platform / f"{identifier}{'.dll' if platform == 'win64' else '.so'}"
    if platform == "win64":
        library = "Z:" + str(library).replace("/", "\\")  # Wine's drive Z: is the Unix root
    variables = {v.name: v for v in md.modelVariables}
    lines = [f"fmu {library} {md.guid}"]
    for name, value in start_values.items():
        kind = variables[name].type.lower()
        lines.append(f"{kind} {variables[name].valueReference} {value!r}" if kind != "string"
                     else f"string {variables[name].valueReference} {value}")
    (input_name,) = [v.name for v in md.modelVariables if v.causality == "input"]
    lines.append(f"input {variables[input_name].valueReference} {scale!r}")
    lines += [f"output {v.valueReference}" for v in md.modelVariables if v.causality == "output"]
    lines.append(f"run {steps} {h!r}")
    return "\n".join(lines)


def cases(plant_fmus, native_shapers, native_filters):
    """(name, FMU, start values, steps, h, input scale) of every native FMU kind."""
    out = [(name, plant_fmus[name], {}, steps, h, scale) for name, (h, steps, scale) in PLANTS.items()]
    redesigned = {"kind": "mzv", "f[1]": 9.0, "zeta[1]": 0.1}  # re-designed in C with the platform's own libm
    out.append(("shaper zv_dn -> mzv", native_shapers[("zv_dn", 2)][0], redesigned, 300, H, 1.0))
    for key in (("ei2", 2), ("simultaneous", 2), ("um_zv", 1)):
        out.append((f"shaper {key[0]}", native_shapers[key][0], {}, 300, H, 1.0))
    for name in ("hanning2", "TP:BC", "time-frequency"):
        out.append((f"filter {name}", native_filters[name][0], {}, 500, H, 1.0))
    return out


def write_plan(path, every, folder, platform, wine_path=False):
    """The plan of ``every`` case for ``platform``'s binaries, written to ``path``; returns the
    argument its host takes (Wine's Z: path for the Windows host)."""
    path.write_text("\n".join(plan_of(fmu, folder, platform, starts, steps, h, scale)
                              for _, fmu, starts, steps, h, scale in every) + "\n")
    return "Z:" + str(path).replace("/", "\\") if wine_path else str(path)


def assert_same_outputs(every, reference_lines, lines, what):
    """Each case's outputs on another platform equal the linux64 ones to 1e-12 of their scale."""
    import numpy as np

    assert len(lines) == len(reference_lines) == len(every), what
    for (name, *_), reference_line, line in zip(every, reference_lines, lines):
        reference, actual = (np.array(text.split(), dtype=float) for text in (reference_line, line))
        assert reference.size > 100 and np.all(np.isfinite(reference)), name
        scale = max(1.0, float(np.max(np.abs(reference))))
        np.testing.assert_allclose(actual, reference, rtol=0, atol=1e-12 * scale, err_msg=f"{what}: {name}")


def run_on_every_platform(fmu, plan_body: str, folder) -> dict:
    """tests/fmu_host.c on linux64, on aarch64-linux under qemu and on win64 under Wine, each
    loading that platform's binary of ``fmu`` and running ``plan_body`` (the plan's lines after its
    ``fmu`` line): {platform: the printed numbers}. Skips, saying why, without the cross tools."""
    import subprocess

    import numpy as np
    import pytest
    from test_native_aarch64 import AARCH64, ARM_ROOT, QEMU
    from test_native_aarch64 import missing_tools as arm_missing
    from test_native_win64 import MINGW, run_wine
    from test_native_win64 import missing_tools as wine_missing

    reason = " ".join(filter(None, (arm_missing(), wine_missing())))
    if reason:
        pytest.skip(reason)
    md = read_model_description(str(fmu))
    identifier = md.coSimulation.modelIdentifier
    hosts = {"linux64": ("gcc", "fmu_host", ["-ldl"], []), "aarch64-linux": (AARCH64, "fmu_host_arm", ["-ldl"], [QEMU, "-L", ARM_ROOT]),
             "win64": (MINGW, "fmu_host.exe", ["-static-libgcc"], None)}
    outputs = {}
    for platform, (compiler, program, flags, runner) in hosts.items():
        host = folder / program
        subprocess.run([compiler, "-O2", "-std=c99", "-I", str(HEADERS), str(HOST), "-o", str(host), *flags], check=True)
        unzipped = folder / f"{fmu.stem}_{platform}"
        zipfile.ZipFile(fmu).extractall(unzipped)
        library = unzipped / "binaries" / platform / f"{identifier}{'.dll' if platform == 'win64' else '.so'}"
        windows = (lambda path: "Z:" + str(path).replace("/", "\\")) if platform == "win64" else str  # Wine's Z:
        plan = folder / f"plan_{fmu.stem}_{platform}.txt"
        plan.write_text(f"fmu {windows(library)} {md.guid}\n{plan_body}")
        if runner is None:
            completed = run_wine(host, windows(plan), folder)
        else:
            completed = subprocess.run([*runner, str(host), str(plan)], capture_output=True, text=True, timeout=300)
        assert completed.returncode == 0, (platform, completed.stderr[-2000:])
        outputs[platform] = np.array(completed.stdout.split(), dtype=float)
    return outputs
