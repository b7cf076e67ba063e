"""The native C ProfileGenerator FMU equals its pythonfmu twin.

Three families (a twin-pulse kind of paper 003, time-frequency of paper 004, a ZVD-shaped bang-bang
of paper 002 starting at t_start): position, velocity and acceleration equal the pythonfmu ones bit
for bit in fmpy with a step that divides the breaks (t += h) and with random steps, with the move
started by the start input after initialisation (acceleration feeding through from it), in
libcosim and ecos, in our C host, and to 1e-12 on win64 under Wine and aarch64 under qemu. A
restored FMU state (before and after the start latched) replays as the twin runs. Design
parameters refuse another value, t_start may change, and valgrind finds nothing.
"""

import shutil

import numpy as np
import pytest
from cross_hosts import run_on_every_platform
from fmpy.validation import validate_fmu
from fmu_drivers import fmpy_slave, initialised, set_start_values, variable_references
from fmu_signal_drivers import run_ecos, run_fmpy, run_libcosim
from native_drivers import declared, replayed_run, twin_driver

from shapefmu.fmi import build_fmu
from shapefmu.fmi.native import profiles
from shapefmu.fmi.native.profiles import build_native_profile

CASES = {"twin-pulse": {},  # BC:TZ, the defaults
         "time-frequency": {"profile": "time-frequency", "omega_n": 60.0, "Ts": 1e-3, "move_time": 0.2, "distance": 0.1},
         "shaped bang-bang": {"profile": "bang-bang", "shaper": "zvd", "omega[1]": 20.0, "distance": 0.5, "t_start": 0.05}}
OUTPUTS = ["position", "velocity", "acceleration"]


@pytest.fixture(scope="module")
def generators(tmp_path_factory):
    folder = tmp_path_factory.mktemp("native_profiles")
    return {name: (build_native_profile(folder / f"native_{i}.fmu", **starts),
                   build_fmu("ProfileGenerator", folder / f"twin_{i}.fmu", **starts))
            for i, (name, starts) in enumerate(CASES.items())}


def test_validation_passes_and_the_variables_are_the_twins(generators):
    native, twin = generators["shaped bang-bang"]
    assert validate_fmu(str(native)) == []
    assert declared(native) == declared(twin)


@pytest.mark.parametrize("case", CASES)
def test_equals_the_twin_bit_for_bit(generators, case):
    native, twin = generators[case]
    runs = [run_fmpy(fmu, [{}] * 6000, 1e-3, OUTPUTS) for fmu in (native, twin)]
    assert runs[0] == runs[1]
    assert max(abs(row[2]) for row in runs[1]) > 0 and runs[1][-1][1] == pytest.approx(0.0, abs=1e-9)  # moved, rests


def _random_run(fmu, times, start_at):
    slave, vr = initialised(fmu)
    rows = []
    for t, t_next in zip(times[:-1], times[1:]):
        if t >= start_at:
            slave.setReal([vr["start"]], [1.0])
        rows.append(slave.getReal([vr[n] for n in OUTPUTS]))  # acceleration follows start at once
        slave.doStep(t, t_next - t)
        rows.append(slave.getReal([vr[n] for n in OUTPUTS]))
    slave.freeInstance()
    return rows


def test_equals_the_twin_with_random_steps_and_a_start_input(generators):
    rng = np.random.default_rng(8)
    steps = rng.uniform(1e-9, 3e-3, 1500)
    steps[::9] = 1e-15
    times = np.concatenate([[0.0], np.cumsum(steps)])
    for case in CASES:
        native, twin = generators[case]
        rows = [_random_run(fmu, times, 0.4) for fmu in (native, twin)]
        assert rows[0] == rows[1]
        assert any(r[2] != 0.0 for r in rows[1])


@pytest.mark.parametrize(("save_at", "replay_start"), [(200, 500), (400, 300)])
def test_a_restored_fmu_state_replays_as_the_twin_runs(generators, save_at, replay_start):
    """The state is taken before the start input rises at step 300 (the replay starts the move at
    step 500 instead) or in the middle of the move (the replay runs it on): the replayed rows are
    the native FMU's own and the twin's uninterrupted run with the replay's start."""
    native, twin = generators["twin-pulse"]
    rng = np.random.default_rng(3)
    times = np.concatenate([[0.0], np.cumsum(rng.uniform(1e-6, 3e-3, 1500))])
    starting = lambda at: lambda k: {"start": float(k >= at)}  # noqa: E731
    waiting = {"t_start": -1.0}
    rows, replayed = replayed_run(native, times, OUTPUTS, starting(300), save_at, starting(replay_start), waiting)
    twin_rows, _ = replayed_run(twin, times, OUTPUTS, starting(300), parameters=waiting)
    twin_replay, _ = replayed_run(twin, times, OUTPUTS, starting(replay_start), parameters=waiting)
    assert rows == twin_rows and replayed == twin_replay[save_at:]
    assert replayed[0] == twin_rows[save_at] and (replayed != rows[save_at:]) == (replay_start != 300)
    assert twin_replay[replay_start - 1][0] == 0.0 and twin_replay[replay_start][2] != 0.0  # the latch moved


def test_equals_the_twin_in_libcosim_and_ecos(generators):
    native, twin = generators["time-frequency"]
    inputs = [{"start": 0.0}] * 20 + [{"start": 1.0}] * 280
    reference = run_fmpy(twin, inputs, 1e-3, OUTPUTS)
    for run in (run_libcosim, run_ecos):
        np.testing.assert_allclose(run(native, inputs, 1e-3, OUTPUTS), reference, rtol=0, atol=1e-12)


@pytest.mark.parametrize("changed", [
    {"distance": 0.8, "acceleration_limit": 2.5, "speed": 0.3},            # bang-coast-bang
    {"shaper": "mzv", "n_modes": 2, "omega[2]": 55.0, "zeta[2]": 0.1},     # another closed-form shaper
    {"shaper": "zv_dn", "n": 3, "omega[1]": 12.0, "speed": 0.0},
    {"shaper": "none", "distance": 0.2},
])
def test_a_bang_bang_is_re_designed_in_c_as_on_the_twin(generators, changed):
    native, twin = generators["shaped bang-bang"]
    runs = [run_fmpy(fmu, [{}] * 4000, 1e-3, OUTPUTS, start_values=changed) for fmu in (native, twin)]
    assert runs[0] == runs[1]
    assert runs[1][-1][0] == pytest.approx(changed.get("distance", 0.5), rel=1e-9)  # the move it was asked for


def test_t_start_may_change_before_initialisation_as_on_the_twin(generators):
    native, twin = generators["shaped bang-bang"]
    runs = [run_fmpy(fmu, [{}] * 2000, 1e-3, OUTPUTS, start_values={"t_start": 0.3}) for fmu in (native, twin)]
    assert runs[0] == runs[1] and runs[1][250][0] == 0.0 and runs[1][400][0] > 0.0


def test_equals_the_twin_in_the_c_host_with_drifting_time_and_exit_handler_teardown(generators, c_host, tmp_path):
    from c_host import fmu_arguments, host_rows, run_host

    native, twin = generators["twin-pulse"]
    csv = tmp_path / "both.csv"
    result = run_host(c_host, [fmu_arguments(twin, tmp_path / "twin"), fmu_arguments(native, tmp_path / "native")],
                      "--stop", 4.0, "--steps", 500, "--period", 0.7, "--teardown", "atexit", "--csv", csv)
    assert result.returncode == 0, result.stderr[-3000:]
    rows = host_rows(csv)
    assert np.array_equal(rows[(0, 0, 0)], rows[(0, 1, 0)]) and np.ptp(rows[(0, 0, 0)][:, 2]) > 0


@pytest.mark.parametrize(("starts", "words"), [
    ({"distance": 2.0}, "distance is 1.7 in this native FMU, whose move is designed at build time; got 2"),
    ({"profile": "TP"}, "profile is BC:TZ in this native FMU"),
    ({"null": 3}, "null is 2 in this native FMU"),
    ({"t_start": float("inf")}, "t_start must be finite, got inf"),
    ({"speed": -1.0}, "speed is 0.69999999999999996 in this native FMU"),  # a twin-pulse build: its design stays
])
def test_design_parameters_of_a_twin_pulse_keep_their_build_values(generators, capfd, starts, words):
    from fmpy.fmi1 import FMICallException

    native, _ = generators["twin-pulse"]
    slave = fmpy_slave(native, "bad")
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    with pytest.raises(FMICallException) as refused:
        set_start_values(slave, variable_references(native), starts)
    slave.freeInstance()
    assert refused.value.status == 3 and words in capfd.readouterr().out


@pytest.mark.parametrize(("starts", "words"), [
    ({"speed": -1.0}, "speed must be >= 0 (0: no speed limit), got -1"),
    ({"shaper": "ei"}, "shaper must be none or a kind this FMU designs in C (zv, zvd, zvdd, zv_dn, mzv), got ei"),
    ({"profile": "TP"}, "profile is bang-bang in this native FMU"),
])
def test_a_bang_bang_refuses_what_it_cannot_re_design(generators, capfd, starts, words):
    from fmpy.fmi1 import FMICallException

    native, _ = generators["shaped bang-bang"]
    slave = fmpy_slave(native, "bad")
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    with pytest.raises(FMICallException):
        set_start_values(slave, variable_references(native), starts)
    slave.freeInstance()
    assert words in capfd.readouterr().out


def test_a_move_larger_than_the_bound_is_refused_before_any_c_is_written(tmp_path, monkeypatch):
    monkeypatch.setattr(profiles, "MAX_LEVELS", 2)
    with pytest.raises(ValueError, match=r"the move has \d+ pieces, more than the 2 a native ProfileGenerator holds"):
        build_native_profile(tmp_path / "Big.fmu")
    assert not (tmp_path / "Big.fmu").exists()


def test_the_c_host_on_linux64_win64_and_aarch64_gives_the_same_numbers(generators, tmp_path):
    """The host's input sequence reaches 0.5 within a few steps: the start input starts the move."""
    from fmpy import read_model_description

    native, _ = generators["time-frequency"]
    vr = {v.name: v.valueReference for v in read_model_description(str(native)).modelVariables}
    plan = f"input {vr['start']} 1\n" + "".join(f"output {vr[n]}\n" for n in OUTPUTS) + "run 300 0.001\n"
    outputs = run_on_every_platform(native, plan, tmp_path)
    assert outputs["linux64"].size == 900 and np.ptp(outputs["linux64"]) > 0
    for platform in ("aarch64-linux", "win64"):
        np.testing.assert_allclose(outputs[platform], outputs["linux64"], rtol=0, atol=1e-12 * 100, err_msg=platform)


VALGRIND_DRIVER = twin_driver("motion_model.h", "motion_variables", r"""
int main(void) {
    const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    const fmi2ValueReference start = vr_of("start"), distance = vr_of("distance"), t_start = vr_of("t_start");
    const fmi2ValueReference outputs[3] = {vr_of("position"), vr_of("velocity"), vr_of("acceleration")};
    double out[3], t = 0.0, value;
    fmi2Component c = fmi2Instantiate("c", fmi2CoSimulation, motion_variables.guid, "", &callbacks, fmi2False, fmi2True);
    if (c == NULL) return 1;
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    value = 99.0;
    REFUSED(fmi2SetReal(c, &distance, 1, &value));
    CHECK(fmi2Reset(c));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    value = -1.0;
    CHECK(fmi2SetReal(c, &t_start, 1, &value));                        /* wait for the input */
    CHECK(fmi2ExitInitializationMode(c));
    fmi2FMUstate state = NULL;
    for (int k = 0; k < 3000; k++) {
        const double h = k % 5 == 0 ? 1e-16 : 1.3e-3, on = k >= 100 ? 1.0 : 0.0;
        CHECK(fmi2SetReal(c, &start, 1, &on));
        CHECK(fmi2DoStep(c, t, h, fmi2True));
        t += h;
        CHECK(fmi2GetReal(c, outputs, 3, out));
        if (k == 500) CHECK(fmi2GetFMUstate(c, &state));
    }
    size_t size = 0;
    CHECK(fmi2SerializedFMUstateSize(c, state, &size));
    fmi2Byte *bytes = malloc(size);
    CHECK(fmi2SerializeFMUstate(c, state, bytes, size));
    fmi2FMUstate copy = NULL;
    CHECK(fmi2DeSerializeFMUstate(c, bytes, size, &copy));
    REFUSED(fmi2DeSerializeFMUstate(c, bytes, size - 1, &copy));
    free(bytes);
    CHECK(fmi2SetFMUstate(c, copy));
    CHECK(fmi2FreeFMUstate(c, &copy));
    CHECK(fmi2FreeFMUstate(c, &state));
    CHECK(fmi2Terminate(c));
    fmi2FreeInstance(c);
    printf("ok %g\n", out[0]);
    return 0;
}
""")


@pytest.mark.skipif(shutil.which("valgrind") is None or shutil.which("gcc") is None, reason="needs valgrind and gcc")
def test_valgrind_finds_no_invalid_access_and_no_leak(generators, tmp_path):
    from test_plantgen_valgrind import run_driver_under_valgrind

    run_driver_under_valgrind(generators["twin-pulse"][0], VALGRIND_DRIVER, tmp_path)
