"""One FMU's libraries for linux64, win64 (run under Wine) and aarch64-linux (run under qemu-user),
compared on the same plan: what tests/test_native_platforms.py, the twin contract and
test_native_fmi3.py share.

    PLATFORMS: {platform: (C compiler, its flags, the FMU library's suffix)}
    missing_tools(platform) -> "" or the Debian packages it needs, for pytest.skip
    cross_hosts: session fixture, a CrossHosts: each C host (tests/hosts_c/) compiled once per platform
        (``.host(source, platform)``), run natively, under qemu or under Wine (``.run(platform,
        program, arguments)``) in one Wine prefix for the session (making one takes seconds)
    windows_path(path): the Wine path (drive Z: is the Unix root) of a file
    plan_of / cases / write_plan / assert_same_outputs: hosts_c/plan_host.c's plans over every kind of
        native FMU (every plant of models/, closed-form and build-time shapers, window, twin-pulse and
        time-frequency filters)
    CrossHosts.run_on_every_platform(fmu, plan_body, folder) -> {platform: the numbers plan_host printed}
"""

from __future__ import annotations

import os
import shutil
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description

from support import FMI_HEADERS, HOSTS_C

PLAN_HOST = HOSTS_C / "plan_host.c"
MINGW = "x86_64-w64-mingw32-gcc"  # Debian gcc-mingw-w64-x86-64
AARCH64 = "aarch64-linux-gnu-gcc"  # Debian gcc-aarch64-linux-gnu
QEMU = "qemu-aarch64"  # Debian qemu-user
ARM_ROOT = "/usr/aarch64-linux-gnu"  # where Debian's cross toolchain keeps the ARM C library
PLATFORMS = {"linux64": ("gcc", ["-ldl", "-lm"], ".so"), "aarch64-linux": (AARCH64, ["-ldl", "-lm"], ".so"),
             "win64": (MINGW, ["-static-libgcc"], ".dll")}
# Per plant: (step, steps, input scale), as tests/test_plantgen_hosts.py drives them.
PLANTS = {"disk_drive": (1e-5, 200, 11.0), "disk_drive_back_emf": (1e-5, 200, 11.0),
          "linear_synchronous_motor": (1e-3, 200, 1.0), "ten_pendula": (1e-2, 300, 0.7),
          "mass_spring_chain": (5e-3, 200, 10.0), "pendulum": (1e-2, 200, 3.0)}


def wine_program() -> str | None:
    """Debian's wine64 loader: on PATH as wine64 or wine, or where the wine64 package puts it."""
    for candidate in (shutil.which("wine64"), shutil.which("wine"), "/usr/lib/wine/wine64"):
        if candidate and os.access(candidate, os.X_OK):
            return candidate
    return None


def missing_tools(platform: str) -> str:
    """Why ``platform``'s binaries cannot run here ("" if they can)."""
    if platform == "win64":
        found = ((MINGW, shutil.which(MINGW)), ("wine64", wine_program()), ("gcc", shutil.which("gcc")))
        packages = "Debian gcc-mingw-w64-x86-64, wine64"
    else:
        found = [(name, shutil.which(name)) for name in (AARCH64, QEMU, "gcc")]
        packages = "Debian gcc-aarch64-linux-gnu, qemu-user"
    missing = [name for name, where in found if not where]
    return f"needs {', '.join(missing)} ({packages}: bash .ci/system-packages)" if missing else ""


class CrossHosts:
    def __init__(self, folder: Path):
        self.folder = folder
        self._programs: dict[tuple, Path] = {}

    def host(self, source: Path, platform: str) -> Path:
        """``source`` compiled for ``platform`` (once)."""
        if (source, platform) not in self._programs:
            compiler, flags, _ = PLATFORMS[platform]
            program = self.folder / f"{source.stem}_{platform}{'.exe' if platform == 'win64' else ''}"
            subprocess.run([compiler, "-O2", "-I", str(FMI_HEADERS), str(source), "-o", str(program), *flags],
                           check=True)
            self._programs[source, platform] = program
        return self._programs[source, platform]

    def run(self, platform: str, program: Path, arguments: list) -> subprocess.CompletedProcess:
        """``program`` (compiled for ``platform``) run with ``arguments`` (Wine paths for win64): a
        Windows program under Wine, headless, in the session's prefix, the Wine server stopped after."""
        if platform != "win64":
            runner = [QEMU, "-L", ARM_ROOT] if platform == "aarch64-linux" else []
            return subprocess.run([*runner, str(program), *map(str, arguments)], capture_output=True, text=True,
                                  timeout=300)
        environment = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": str(self.folder),
                       "WINEPREFIX": str(self.folder / "wine-prefix"), "WINEDEBUG": "-all",
                       "WINEDLLOVERRIDES": "mscoree,mshtml=", "WINEARCH": "win64"}
        try:
            return subprocess.run([wine_program(), str(program), *map(str, arguments)], capture_output=True,
                                  text=True, timeout=300, env=environment, cwd=self.folder)
        finally:
            server = shutil.which("wineserver") or "/usr/lib/wine/wineserver"
            if os.access(server, os.X_OK):
                subprocess.run([server, "-k"], env=environment, capture_output=True, timeout=60)

    def run_on_every_platform(self, fmu, plan_body: str, folder: Path) -> dict:
        """plan_host on linux64, on aarch64-linux under qemu and on win64 under Wine, each loading that
        platform's library of ``fmu`` (extracted into ``folder``) and running ``plan_body`` (the plan's
        lines after its ``fmu`` line): {platform: the printed numbers}. Skips, saying why, without the
        cross tools."""
        reason = " ".join(filter(None, map(missing_tools, ("aarch64-linux", "win64"))))
        if reason:
            pytest.skip(reason)
        guid = read_model_description(str(fmu)).guid
        outputs = {}
        for platform in PLATFORMS:
            plan = folder / f"plan_{fmu.stem}_{platform}.txt"
            plan.write_text(f"fmu {_library(fmu, folder / f'{fmu.stem}_{platform}', platform)} {guid}\n{plan_body}")
            completed = self.run(platform, self.host(PLAN_HOST, platform),
                                 [windows_path(plan) if platform == "win64" else plan])
            assert completed.returncode == 0, (platform, completed.stderr[-2000:])
            outputs[platform] = np.array(completed.stdout.split(), dtype=float)
        return outputs


@pytest.fixture(scope="session")
def cross_hosts(tmp_path_factory) -> CrossHosts:
    return CrossHosts(tmp_path_factory.mktemp("cross_hosts"))


def windows_path(path) -> str:
    return "Z:" + str(path).replace("/", "\\")


def _library(fmu, unzipped: Path, platform: str) -> str:
    """Where ``platform``'s library of ``fmu`` lies once extracted to ``unzipped``, as that platform names it."""
    identifier = read_model_description(str(fmu)).coSimulation.modelIdentifier
    if not unzipped.is_dir():
        zipfile.ZipFile(fmu).extractall(unzipped)
    library = unzipped / "binaries" / platform / f"{identifier}{PLATFORMS[platform][2]}"
    return windows_path(library) if platform == "win64" else str(library)


def plan_of(fmu, folder, platform, start_values, steps, h, scale):
    """Plan lines for one FMU (hosts_c/plan_host.c): its library, start values, input, outputs, run."""
    md = read_model_description(str(fmu))
    variables = {v.name: v for v in md.modelVariables}
    lines = [f"fmu {_library(fmu, folder / fmu.stem, platform)} {md.guid}"]
    for name, value in start_values.items():
        kind = variables[name].type.lower()
        lines.append(f"{kind} {variables[name].valueReference} {value!r}" if kind != "string"
                     else f"string {variables[name].valueReference} {value}")
    (input_name,) = [v.name for v in md.modelVariables if v.causality == "input"]
    lines.append(f"input {variables[input_name].valueReference} {scale!r}")
    lines += [f"output {v.valueReference}" for v in md.modelVariables if v.causality == "output"]
    lines.append(f"run {steps} {h!r}")
    return "\n".join(lines)


def cases(plant_fmus, native_shapers, native_filters, h):
    """(name, FMU, start values, steps, step, input scale) of every native FMU kind; shapers and
    filters step by their sample period ``h``."""
    out = [(name, plant_fmus[name], {}, steps, step, scale) for name, (step, steps, scale) in PLANTS.items()]
    redesigned = {"kind": "mzv", "f[1]": 9.0, "zeta[1]": 0.1}  # re-designed in C with the platform's own libm
    out.append(("shaper zv_dn -> mzv", native_shapers[("zv_dn", 2)][0], redesigned, 300, h, 1.0))
    for key in (("ei2", 2), ("simultaneous", 2), ("um_zv", 1)):
        out.append((f"shaper {key[0]}", native_shapers[key][0], {}, 300, h, 1.0))
    for name in ("hanning2", "TP:BC", "time-frequency"):
        out.append((f"filter {name}", native_filters[name][0], {}, 500, h, 1.0))
    return out


def write_plan(path: Path, every, folder: Path, platform: str) -> str:
    """The plan of ``every`` case for ``platform``'s binaries, written to ``path``; returns the
    argument its host takes (a Wine path for win64)."""
    path.write_text("\n".join(plan_of(fmu, folder, platform, starts, steps, h, scale)
                              for _, fmu, starts, steps, h, scale in every) + "\n")
    return windows_path(path) if platform == "win64" else str(path)


def assert_same_outputs(every, reference_lines, lines, what):
    """Each case's outputs on another platform equal the linux64 ones to 1e-12 of their scale."""
    assert len(lines) == len(reference_lines) == len(every), what
    for (name, *_), reference_line, line in zip(every, reference_lines, lines):
        reference, actual = (np.array(text.split(), dtype=float) for text in (reference_line, line))
        assert reference.size > 100 and np.all(np.isfinite(reference)), name
        scale = max(1.0, float(np.max(np.abs(reference))))
        np.testing.assert_allclose(actual, reference, rtol=0, atol=1e-12 * scale, err_msg=f"{what}: {name}")
