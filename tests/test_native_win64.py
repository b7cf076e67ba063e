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

import pytest
from cross_hosts import HEADERS, HOST, assert_same_outputs, cases, write_plan

from shapefmu.fmi.native.compile import MINGW


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
    """The Windows host under Wine, headless, in a prefix of its own (created on first use); ``plan``
    is its one argument or a list of them."""
    wine = wine_program()
    arguments = [plan] if isinstance(plan, str) else list(plan)
    environment = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": str(folder),
                   "WINEPREFIX": str(folder / "wine-prefix"), "WINEDEBUG": "-all",
                   "WINEDLLOVERRIDES": "mscoree,mshtml=", "WINEARCH": "win64"}
    try:
        return subprocess.run([wine, str(program), *arguments], capture_output=True, text=True, timeout=300,
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
        plan = write_plan(folder / f"plan_{platform}.txt", every, folder, platform, wine_path=platform == "win64")
        if platform == "win64":
            completed = run_wine(program, plan, folder)
        else:
            completed = subprocess.run([str(program), plan], capture_output=True, text=True, timeout=120)
        assert completed.returncode == 0, completed.stderr[-3000:]
        outputs[platform] = completed.stdout.splitlines()
    assert_same_outputs(every, outputs["linux64"], outputs["win64"], "win64 under Wine")
