"""Every kind of native FMU runs on 64-bit ARM Linux (a Raspberry Pi, the boards that drive
printers): its binaries/aarch64-linux library, loaded by an ARM host under qemu-user, gives the
linux64 binary's outputs to 1e-12.

The C host tests/fmu_host.c is compiled with gcc for linux64 and with Debian's
gcc-aarch64-linux-gnu for ARM; both run the same plan (tests/cross_hosts.py) over the same FMUs,
the ARM one under qemu-aarch64 with the cross toolchain's libraries as its root. make test
installs both tools (.ci/system-packages); without them this test skips and says why.
"""

import shutil
import subprocess
import zipfile

import pytest
from cross_hosts import HEADERS, HOST, assert_same_outputs, cases, write_plan

from shapefmu.fmi.native.compile import AARCH64

QEMU = "qemu-aarch64"
ARM_ROOT = "/usr/aarch64-linux-gnu"  # where Debian's cross toolchain keeps the ARM C library


def missing_tools():
    missing = [name for name in (AARCH64, QEMU, "gcc") if not shutil.which(name)]
    return (f"needs {', '.join(missing)} (Debian gcc-aarch64-linux-gnu, qemu-user: bash .ci/system-packages)"
            if missing else "")


@pytest.fixture(scope="module")
def hosts(tmp_path_factory):
    reason = missing_tools()
    if reason:
        pytest.skip(reason)
    folder = tmp_path_factory.mktemp("fmu_host_arm")
    linux, arm = folder / "fmu_host", folder / "fmu_host_aarch64"
    subprocess.run(["gcc", "-O2", "-std=c99", "-I", str(HEADERS), str(HOST), "-o", str(linux), "-ldl"], check=True)
    subprocess.run([AARCH64, "-O2", "-std=c99", "-I", str(HEADERS), str(HOST), "-o", str(arm), "-ldl"], check=True)
    return linux, arm, folder


def test_every_native_fmu_carries_an_arm_library(plant_fmus, native_shapers, native_filters):
    if not shutil.which(AARCH64):
        pytest.skip(f"needs {AARCH64} (Debian gcc-aarch64-linux-gnu: bash .ci/system-packages)")
    for _, fmu, *_ in cases(plant_fmus, native_shapers, native_filters):
        with zipfile.ZipFile(fmu) as archive:
            library = next(n for n in archive.namelist() if n.startswith("binaries/aarch64-linux/"))
            elf = archive.read(library)[:20]
        assert elf[:4] == b"\x7fELF" and int.from_bytes(elf[18:20], "little") == 183, fmu  # e_machine EM_AARCH64


def test_aarch64_libraries_under_qemu_equal_the_linux64_binaries(hosts, plant_fmus, native_shapers, native_filters):
    linux, arm, folder = hosts
    every = cases(plant_fmus, native_shapers, native_filters)
    outputs = {}
    for platform, command in (("linux64", [str(linux)]), ("aarch64-linux", [QEMU, "-L", ARM_ROOT, str(arm)])):
        plan = write_plan(folder / f"plan_{platform}.txt", every, folder, platform)
        completed = subprocess.run([*command, plan], capture_output=True, text=True, timeout=300)
        assert completed.returncode == 0, completed.stderr[-3000:]
        outputs[platform] = completed.stdout.splitlines()
    assert_same_outputs(every, outputs["linux64"], outputs["aarch64-linux"], "aarch64 under qemu")
