"""What the tests share: FMU builds and fixtures, the drivers that run an FMU in fmpy, libcosim and
ecos, our C hosts, and the references the tests compare with.

    builds            every FMU the tests build, once per session (the ``builds`` fixture)
    fixtures_fmi, fixtures_native, fixtures_plants   the FMU fixtures and their start values
    hosts             one FMU run in fmpy, libcosimpy or ecospy with one signature
    ssp_hosts         an .ssp system run in libcosimpy and ecospy
    fmpy_slaves       one FMU as an fmpy slave: its life cycle, runs over any steps, its state
    c_hosts           tests/hosts_c/fmi2_host.c and fmi3_host.c, compiled once per session
    cross_platform    tests/hosts_c/plan_host.c on linux64, win64 (Wine) and aarch64 (qemu)
    valgrind          memcheck on the C hosts and on drivers compiled with an FMU's sources
    twins             the native twins as the twin contract runs them
    scenarios         the EKF tuner's and the STOS controller's inputs and closed loop
    c_fmus, cosim_fmus   small FMUs with known behaviour (C, pythonfmu) for the master's tests
    sampled_reference, ei_definition   references computed without the code under test

Paths: HOSTS_C (the C hosts and drivers), FMI_HEADERS (fmpy's copy of the FMI 2.0 and 3.0 headers,
with which the tests compile, as another tool compiles with its own), MODELS (the shipped plants),
CTYPES_HOST (fmi2_ctypes_host.py, an FMI 2.0 host of the standard library alone, run as a script).
"""

from pathlib import Path

import fmpy

TESTS = Path(__file__).resolve().parent.parent
HOSTS_C = TESTS / "hosts_c"
FMI_HEADERS = Path(fmpy.__file__).parent / "c-code"
MODELS = TESTS.parent / "models"
CTYPES_HOST = TESTS / "support" / "fmi2_ctypes_host.py"
