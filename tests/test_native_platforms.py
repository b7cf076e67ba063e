"""Every kind of native FMU runs on Windows and on 64-bit ARM Linux (a Raspberry Pi, the boards that
drive printers): its binaries/win64 DLL under Wine, and its binaries/aarch64-linux library under
qemu-user, give the linux64 binary's outputs to 1e-12 of their scale.

The C host tests/hosts_c/plan_host.c is compiled for linux64 with gcc, for Windows with the
mingw-w64 cross compiler and for ARM with Debian's gcc-aarch64-linux-gnu; each runs the same plan
(start values, input sequence, steps; tests/support/cross_platform.py) over the same FMUs, the
Windows one under Wine (Debian wine64) with its own prefix in the test's temporary folder, headless,
the ARM one under qemu-aarch64 with the cross toolchain's libraries as its root. Plants: every model
of models/ (linear zero-order hold, nonlinear RK4); shapers: a closed-form Shaper re-designed in C,
the EI and simultaneous designs, window, twin-pulse and time-frequency filters. make test installs
the tools (.ci/system-packages); without them these tests skip and say why.
"""

import shutil
import zipfile

import pytest

from support.cross_platform import AARCH64, PLAN_HOST, assert_same_outputs, cases, missing_tools, write_plan
from support.fixtures_native import H


@pytest.mark.foreign
@pytest.mark.parametrize("platform", ["win64", "aarch64-linux"])
def test_the_libraries_of_another_platform_equal_the_linux64_binaries(plant_fmus, native_shapers, native_filters,
                                                                      cross_hosts, tmp_path, platform):
    reason = missing_tools(platform)
    if reason:
        pytest.skip(reason)
    every = cases(plant_fmus, native_shapers, native_filters, H)
    outputs = {}
    for name in ("linux64", platform):
        plan = write_plan(tmp_path / f"plan_{name}.txt", every, tmp_path, name)
        completed = cross_hosts.run(name, cross_hosts.host(PLAN_HOST, name), [plan])
        assert completed.returncode == 0, completed.stderr[-3000:]
        outputs[name] = completed.stdout.splitlines()
    assert_same_outputs(every, outputs["linux64"], outputs[platform], f"{platform} binaries")


def test_every_native_fmu_carries_an_arm_library(plant_fmus, native_shapers, native_filters):
    if not shutil.which(AARCH64):
        pytest.skip(f"needs {AARCH64} (Debian gcc-aarch64-linux-gnu: bash .ci/system-packages)")
    for _, fmu, *_ in cases(plant_fmus, native_shapers, native_filters, H):
        with zipfile.ZipFile(fmu) as archive:
            library = next(n for n in archive.namelist() if n.startswith("binaries/aarch64-linux/"))
            elf = archive.read(library)[:20]
        assert elf[:4] == b"\x7fELF" and int.from_bytes(elf[18:20], "little") == 183, fmu  # e_machine EM_AARCH64
