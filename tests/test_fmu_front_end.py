"""The pythonfmu FMUs' C front end (fmi/python/shim/): any exit order, no Python, in a C host.

OMSimulator crashed at exit (SIGSEGV in PyGILState_Ensure from fmi2Terminate): it terminates its
instances from an exit handler registered before it loaded the FMU, which runs after the handler
the FMU registers, and pythonfmu finalised the interpreter from that one. The front end now starts
the interpreter itself and never finalises it (python_runtime.c). These tests run our C host
(hosts_c/fmi2_host.c) in every exit order we know of and check that the process exits 0 with
every call fmi2OK and the outputs unchanged; a call after a Python host finalised the interpreter
is refused with fmi2Error and a message, not a crash; and an FMU without a usable libpython says
what it looked for and what to install, and returns NULL.
"""

from __future__ import annotations

import ctypes.util
import os
import subprocess
import sys
import sysconfig
from pathlib import Path

import numpy as np
import pytest
from support.c_hosts import fmu_arguments, host_rows, run_host
from support.fixtures_fmi import SHAPER_STARTS

RUN = ["--stop", 0.2, "--step", 1e-3]


@pytest.fixture(scope="module")
def three_kinds(shaper_fmu, ekf_fmu, plant_fmus, tmp_path_factory):
    """``--fmu`` arguments of two pythonfmu FMUs and a native plant, extracted once."""
    folder = tmp_path_factory.mktemp("front_end")
    return [fmu_arguments(fmu, folder / name)
            for name, fmu in (("Shaper", shaper_fmu), ("EKFTuner", ekf_fmu), ("plant", plant_fmus["disk_drive"]))]


def _run(c_host, fmus, tmp_path, *options, env=None):
    csv = tmp_path / "run.csv"
    result = run_host(c_host, fmus, *RUN, "--csv", csv, *options, env=env)
    assert result.returncode == 0, result.stderr[-3000:]
    assert "done" in result.stdout.splitlines()
    return result, host_rows(csv)


@pytest.fixture(scope="module")
def reference_rows(c_host, three_kinds, tmp_path_factory):
    """Outputs of one instance of each FMU, torn down normally: what every other order must give."""
    _, rows = _run(c_host, three_kinds, tmp_path_factory.mktemp("reference"))
    return rows


@pytest.mark.parametrize("teardown", ["atexit", "atexit-terminate", "never"])
def test_two_fmus_a_plant_and_two_instances_each_alive_at_exit_end_cleanly(
    c_host, three_kinds, reference_rows, tmp_path, teardown
):
    result, rows = _run(c_host, three_kinds, tmp_path, "--instances", 2, "--teardown", teardown)
    if teardown != "never":
        # The handler registered before the FMUs were loaded ran last, and all six fmi2Terminate were OK.
        assert f"exit handler: {teardown} done" in result.stderr
    for (_, fmu, instance), values in rows.items():
        np.testing.assert_array_equal(values, reference_rows[(0, fmu, 0)])  # no cross-talk between instances
    assert len(rows) == 6


def test_dlclose_and_a_second_load_in_the_same_process_run_the_same(c_host, three_kinds, reference_rows, tmp_path):
    _, rows = _run(c_host, three_kinds, tmp_path, "--passes", 2, "--teardown", "atexit")
    for fmu in range(len(three_kinds)):
        np.testing.assert_array_equal(rows[(0, fmu, 0)], reference_rows[(0, fmu, 0)])
        np.testing.assert_array_equal(rows[(1, fmu, 0)], reference_rows[(0, fmu, 0)])


def _libpython():
    return str(Path(sysconfig.get_config_var("LIBDIR")) / sysconfig.get_config_var("INSTSONAME"))


def test_calls_after_a_python_host_finalised_the_interpreter_are_refused_not_crashed(c_host, three_kinds, tmp_path):
    # A Python program's interpreter is finalised before the C exit handlers run; a C++ host object
    # destroyed then (libcosim's, say) may still terminate its instances.
    env = {**os.environ, "PYTHONHOME": sys.base_prefix}
    result, _ = _run(c_host, three_kinds[:2], tmp_path, "--embed-python", _libpython(), "--teardown", "atexit", env=env)
    assert [line for line in result.stdout.splitlines() if line.startswith("teardown")] == ["teardown 3"] * 2
    for name in ("Shaper_0", "EKFTuner_0"):
        assert f"{name}: fmi2Terminate: the Python interpreter of this process has been finalised" in result.stderr
        assert f"{name}: fmi2FreeInstance: the Python interpreter" in result.stderr
    assert "exit handler: atexit done" in result.stderr


def _with_front_end(fmu, tmp_path, **lookup):
    """``--fmu`` arguments of ``fmu`` extracted, its front end recompiled to look for Python per ``lookup``."""
    from fmpy import read_model_description

    from shapefmu.fmi.python.builder import compile_shim

    arguments = fmu_arguments(fmu, tmp_path / "fmu")
    directory, identifier = Path(arguments[1]), arguments[2]
    guid = read_model_description(str(fmu)).guid
    compile_shim(directory / "binaries" / "linux64" / f"{identifier}.so", identifier, guid, **lookup)
    return arguments


def test_without_a_usable_libpython_instantiation_says_what_it_tried_and_returns_null(shaper_fmu, c_host, tmp_path):
    # The recorded libpython is gone and no soname of the fallback list exists on any system.
    missing = "/nonexistent/lib/libpython3.11.so.1.0"
    arguments = _with_front_end(shaper_fmu, tmp_path, libpython=missing, minors=(98, 99))
    result = run_host(c_host, [arguments], *RUN)
    assert result.returncode == 2, result.stderr  # the host's "instantiate returned NULL", not a signal
    (message,) = [line for line in result.stderr.splitlines() if "Python runtime" in line]
    tried = (missing, "libpython3.98.so.1.0, libpython3.99.so.1.0")
    for words in (*tried, "apt install libpython3.98", "LD_LIBRARY_PATH"):
        assert words in message
    assert "FAIL fmi2Instantiate of Shaper returned NULL" in result.stderr


def test_a_recorded_libpython_that_is_gone_falls_back_to_the_soname(shaper_fmu, c_host, tmp_path):
    minor = sys.version_info.minor
    if ctypes.util.find_library(f"python3.{minor}") is None:
        pytest.skip(f"no libpython3.{minor} on the library path to fall back to")
    arguments = _with_front_end(shaper_fmu, tmp_path, libpython="/nonexistent/libpython.so", minors=(minor,))
    csv = tmp_path / "run.csv"
    result = run_host(c_host, [arguments], *RUN, "--csv", csv)
    assert result.returncode == 0, result.stderr[-3000:]
    rows = host_rows(csv)[(0, 0, 0)]
    # ZV at 10 Hz: y = (u[k] + u[k - 50]) / 2, resting at u0 before t = 0.
    u = rows[:, 1]
    expected = 0.5 * u + 0.5 * np.concatenate([np.full(50, SHAPER_STARTS["u0"]), u[:-50]])
    np.testing.assert_allclose(rows[:, 2], expected, rtol=0, atol=1e-12)


def test_a_percent_sign_in_a_logged_path_reaches_a_printf_logger_verbatim(shaper_fmu, tmp_path):
    # fmpy's logger formats the message like printf (as FMI 2.0 says); the resource URI of a folder
    # named with %s and %n, which the front end refuses, must not be read as conversions.
    script = (
        "import sys\n"
        "from fmpy import extract, read_model_description\n"
        "from fmpy.fmi2 import FMU2Slave\n"
        "md = read_model_description(sys.argv[1])\n"
        "slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(sys.argv[1], sys.argv[2]), modelIdentifier='Shaper')\n"
        "try:\n"
        "    slave.instantiate()\n"
        "except Exception as error:\n"
        "    print('refused:', type(error).__name__)\n"
    )
    folder = tmp_path / "odd %s%s%n name"
    result = subprocess.run([sys.executable, "-c", script, str(shaper_fmu), str(folder)], capture_output=True,
                            text=True, timeout=120)
    assert result.returncode == 0, result.stderr[-3000:]
    assert "refused:" in result.stdout
    assert "odd%20%25s%25s%25n%20name/resources is not this FMU's resources directory" in result.stdout
