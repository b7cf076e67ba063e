"""The contract every native C twin keeps with its pythonfmu FMU, one parametrised test per item.

A kind (tests/support/twins.py declares each: its cases, inputs, runs and what each run must show)
joins by one line in TWINS. For each kind: fmpy's validator passes on the native FMU, which
declares the twin's variables and carries an ARM library; its outputs equal the twin's with steps
of Ts, with random steps (an FMU state restored mid-run replays the native run), with parameters
set before initialisation, in libcosim and ecos, and with both FMUs side by side in our C host
(t += h, exit-handler teardown); the C host prints the same numbers on linux64, win64 under Wine and
aarch64 under qemu; valgrind finds no invalid access and no leak in a driver of the FMU's sources.
The second opinion everywhere is the pythonfmu twin, whose Python is the design layer's own code.
"""

import shutil
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from support.c_hosts import fmu_arguments, host_rows, run_host
from support.fmpy_slaves import replayed_run, run_points
from support.hosts import run_ecos, run_fmpy, run_libcosim
from support.declarations import declared
from support.tracked_shaper_twin import TRACKED_SHAPER
from support.twins import EKF_TUNER, IMPULSE_TRAIN, PROFILE_GENERATOR, REFERENCE_PLAYER, SCHEDULED_SHAPER, STOS_CONTROLLER
from support.valgrind import requires_valgrind, run_driver_under_valgrind

TWINS = [
    EKF_TUNER,
    STOS_CONTROLLER,
    PROFILE_GENERATOR,
    REFERENCE_PLAYER,
    IMPULSE_TRAIN,
    SCHEDULED_SHAPER,
    TRACKED_SHAPER,
]


def runs_of(*items: str):
    """pytest parameters (kind, run) of every kind's runs of the contract ``items``."""
    return [pytest.param(kind, run, id=f"{kind.model}-{item}-{run.case}-{i}")
            for kind in TWINS for item in items for i, run in enumerate(getattr(kind, item))]


@pytest.mark.parametrize("kind", TWINS, ids=repr)
def test_validation_passes_the_variables_are_the_twins_and_an_arm_library_is_inside(builds, kind):
    for case in kind.cases:
        native, twin = kind.pair(builds, case)
        assert validate_fmu(str(native)) == [], case
        assert declared(native, kind.units) == declared(twin, kind.units), case
        identifier = read_model_description(str(native)).coSimulation.modelIdentifier
        assert f"binaries/aarch64-linux/{identifier}.so" in zipfile.ZipFile(native).namelist() or not shutil.which(
            "aarch64-linux-gnu-gcc")


@pytest.mark.parametrize(("kind", "run"), runs_of("steps_of_ts", "changes"))
def test_equals_the_twin_with_steps_of_ts_as_built_and_with_parameters_set_before_initialisation(builds, kind, run):
    pair = kind.pair(builds, run.case)
    native, twin = (kind.run(fmu, run, pair) for fmu in pair)
    kind.assert_same(native, twin, kind.exact)
    run.check(twin)


@pytest.mark.parametrize(("kind", "run"), runs_of("random"))
def test_equals_the_twin_with_random_steps_and_a_restored_state_replays_the_run(builds, kind, run):
    """Steps of random sizes, slivers of 1e-12 s or less among them; the FMU state taken two fifths
    into the run (serialised and read back) is restored after it and the rest run again."""
    pair = kind.pair(builds, run.case)
    times = run.times()
    inputs = run.inputs(pair, times)
    save_at = 2 * (len(times) - 1) // 5
    rows, replayed = replayed_run(pair[0], times, inputs, kind.outputs, save_at, inputs, read_before=kind.read_before)
    twin = run_points(pair[1], times, inputs, kind.outputs, read_before=kind.read_before)
    kind.assert_same(rows, twin, kind.exact)
    assert replayed == rows[(2 if kind.read_before else 1) * save_at:]
    run.check(twin)


@pytest.mark.parametrize("kind", TWINS, ids=repr)
def test_equals_the_twin_in_fmpy_libcosim_and_ecos(builds, quiet_libcosim, kind):
    run = kind.hosts
    pair = kind.pair(builds, run.case)
    inputs = run.inputs(pair, run.times())
    twin = run_fmpy(pair[1], inputs, kind.host_step, kind.outputs)
    for host in (run_fmpy, run_libcosim, run_ecos):
        kind.assert_same(host(pair[0], inputs, kind.host_step, kind.outputs), twin, exact=False)


@pytest.mark.parametrize("kind", TWINS, ids=repr)
def test_equals_the_twin_in_the_c_host_with_drifting_time_and_exit_handler_teardown(builds, c_host, tmp_path, kind):
    """Both FMUs side by side in hosts_c/fmi2_host.c: the same times and inputs, the same outputs."""
    native, twin = kind.pair(builds, kind.c_host.case)
    csv = tmp_path / "both.csv"
    result = run_host(c_host, [fmu_arguments(twin, tmp_path / "twin"), fmu_arguments(native, tmp_path / "native")],
                      *kind.c_host.options, "--teardown", "atexit", "--csv", csv)
    assert result.returncode == 0, result.stderr[-3000:]
    rows = host_rows(csv)
    twin_rows, native_rows = rows[(0, 0, 0)], rows[(0, 1, 0)]
    inputs = 1 + sum(v.causality == "input" and v.type == "Real" for v in read_model_description(str(twin)).modelVariables)
    assert np.array_equal(twin_rows[:, :inputs], native_rows[:, :inputs])  # t and the inputs
    kind.assert_same(native_rows[:, inputs:], twin_rows[:, inputs:], kind.exact)
    kind.c_host.check(twin_rows)


@pytest.mark.foreign
@pytest.mark.parametrize(("kind", "platforms"), [pytest.param(kind, platforms, id=f"{kind.model}-{platforms.case}")
                                                 for kind in TWINS for platforms in kind.platforms])
def test_the_c_host_on_linux64_win64_and_aarch64_gives_the_same_numbers(builds, cross_hosts, tmp_path, kind, platforms):
    native, _ = kind.pair(builds, platforms.case)
    vr = {v.name: v.valueReference for v in read_model_description(str(native)).modelVariables}
    plan = platforms.plan(vr)
    outputs = plan.count("output ")
    printed = cross_hosts.run_on_every_platform(native, plan, tmp_path)
    reference = printed["linux64"].reshape(-1, outputs)
    platforms.check(reference)
    for platform in ("aarch64-linux", "win64"):
        kind.assert_same(printed[platform].reshape(-1, outputs), reference, exact=False)


@pytest.mark.foreign
@requires_valgrind
@pytest.mark.parametrize("kind", TWINS, ids=repr)
def test_valgrind_finds_no_invalid_access_and_no_leak(builds, tmp_path, kind):
    case, driver = kind.valgrind
    run_driver_under_valgrind(kind.pair(builds, case)[0], driver, tmp_path)
