"""Every kind of native FMU runs on Windows: its win64 DLL under Wine gives the linux64 binary's
outputs to 1e-12.

A small C host (tests/fmu_host.c) is compiled twice, with gcc for Linux and with the mingw-w64
cross compiler for Windows; both run the same plan (start values, input sequence, steps) over the
same FMUs, the Windows one under Wine (Debian wine64) with its own prefix in the test's temporary
folder, headless. Plants: every model of models/ (linear zero-order hold, nonlinear RK4); shapers:
a closed-form Shaper re-designed in C, the EI and simultaneous designs, window, twin-pulse and
time-frequency filters. make test installs mingw-w64 and Wine (.ci/system-packages); without them
this test skips and says why.
"""

import os
import shutil
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fixtures_native import H
from fmpy import read_model_description

from shapefmu.fmi.native.compile import MINGW

HOST = Path(__file__).parent / "fmu_host.c"
HEADERS = Path(__file__).parent.parent / "src" / "shapefmu" / "fmi" / "native" / "c"
# Per plant: (step, steps, input scale), as tests/test_plantgen_hosts.py drives them.
PLANTS = {"disk_drive": (1e-5, 200, 11.0), "disk_drive_back_emf": (1e-5, 200, 11.0),
          "linear_synchronous_motor": (1e-3, 200, 1.0), "ten_pendula": (1e-2, 300, 0.7),
          "mass_spring_chain": (5e-3, 200, 10.0), "pendulum": (1e-2, 200, 3.0)}


def wine_program():
    """Debian's wine64 loader: on PATH as wine64 or wine, or where the wine64 package puts it."""
    for candidate in (shutil.which("wine64"), shutil.which("wine"), "/usr/lib/wine/wine64"):
        if candidate and os.access(candidate, os.X_OK):
            return candidate
    return None


def missing_tools():
    missing = [name for name, found in ((MINGW, shutil.which(MINGW)), ("wine64", wine_program()),
                                        ("gcc", shutil.which("gcc"))) if not found]
    return f"needs {', '.join(missing)} (Debian gcc-mingw-w64-x86-64, wine64: bash .ci/system-packages)" if missing else ""


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
    redesigned = {"kind": "mzv", "f[1]": 9.0, "zeta[1]": 0.1}  # re-designed in C with the DLL's own libm
    out.append(("shaper zv_dn -> mzv", native_shapers[("zv_dn", 2)][0], redesigned, 300, H, 1.0))
    for key in (("ei2", 2), ("simultaneous", 2), ("um_zv", 1)):
        out.append((f"shaper {key[0]}", native_shapers[key][0], {}, 300, H, 1.0))
    for name in ("hanning2", "TP:BC", "time-frequency"):
        out.append((f"filter {name}", native_filters[name][0], {}, 500, H, 1.0))
    return out


@pytest.fixture(scope="module")
def hosts(tmp_path_factory):
    reason = missing_tools()
    if reason:
        pytest.skip(reason)
    folder = tmp_path_factory.mktemp("fmu_host")
    linux, windows = folder / "fmu_host", folder / "fmu_host.exe"
    subprocess.run(["gcc", "-O2", "-std=c99", "-I", str(HEADERS), str(HOST), "-o", str(linux), "-ldl"], check=True)
    subprocess.run([MINGW, "-O2", "-std=c99", "-static-libgcc", "-I", str(HEADERS), str(HOST), "-o", str(windows)],
                   check=True)
    return linux, windows, folder


def run_wine(program, plan, folder):
    """The Windows host under Wine, headless, in a prefix of its own (created on first use)."""
    wine = wine_program()
    environment = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": str(folder),
                   "WINEPREFIX": str(folder / "wine-prefix"), "WINEDEBUG": "-all",
                   "WINEDLLOVERRIDES": "mscoree,mshtml=", "WINEARCH": "win64"}
    try:
        return subprocess.run([wine, str(program), plan], capture_output=True, text=True, timeout=300,
                              env=environment, cwd=folder)
    finally:
        server = shutil.which("wineserver") or "/usr/lib/wine/wineserver"
        if os.access(server, os.X_OK):
            subprocess.run([server, "-k"], env=environment, capture_output=True, timeout=60)


def test_win64_binaries_under_wine_equal_the_linux64_binaries(hosts, plant_fmus, native_shapers, native_filters):
    linux, windows, folder = hosts
    every = cases(plant_fmus, native_shapers, native_filters)
    outputs = {}
    for platform, program in (("linux64", linux), ("win64", windows)):
        plan = folder / f"plan_{platform}.txt"
        plan.write_text("\n".join(plan_of(fmu, folder, platform, starts, steps, h, scale)
                                  for _, fmu, starts, steps, h, scale in every) + "\n")
        if platform == "win64":
            completed = run_wine(program, "Z:" + str(plan).replace("/", "\\"), folder)
        else:
            completed = subprocess.run([str(program), str(plan)], capture_output=True, text=True, timeout=120)
        assert completed.returncode == 0, completed.stderr[-3000:]
        outputs[platform] = completed.stdout.splitlines()
    assert len(outputs["win64"]) == len(outputs["linux64"]) == len(every)
    for (name, *_), linux_line, windows_line in zip(every, outputs["linux64"], outputs["win64"]):
        reference, actual = (np.array(line.split(), dtype=float) for line in (linux_line, windows_line))
        assert reference.size > 100 and np.all(np.isfinite(reference)), name
        scale = max(1.0, float(np.max(np.abs(reference))))
        np.testing.assert_allclose(actual, reference, rtol=0, atol=1e-12 * scale, err_msg=name)
