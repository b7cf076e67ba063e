"""The native C EKFTuner FMU equals its pythonfmu twin (paper 001's EKF-tuned shaper).

Both FMUs watch the same noisy 10 Hz ring-down and shape the same moving-resting command: the
native one's y, omega_est, zeta_est and converged equal the pythonfmu one's to 1e-12 of their range
in fmpy with steps of Ts and with random steps, in libcosimpy and ecospy, and through the C host
(t += h) on linux64, win64 under Wine and aarch64 under qemu. Its FMU state restores exactly,
parameters set before initialisation are used as the twin uses them, bad values are refused with a
logged message, and valgrind finds nothing.
"""

import math
import shutil
import zipfile

import numpy as np
import pytest
from cross_hosts import run_on_every_platform
from fixtures_fmi import EKF_STARTS
from fmpy.validation import validate_fmu
from fmu_drivers import configured, fmpy_slave, initialised, set_start_values, variable_references
from fmu_signal_drivers import run_ecos, run_fmpy, run_libcosim
from native_drivers import declared, twin_driver
from test_fmu_ekf import OMEGA, OUTPUTS, _drive, _signals

from shapefmu.fmi.native.ekf_tuner import build_native_ekf_tuner

H = EKF_STARTS["Ts"]


@pytest.fixture(scope="module")
def native_ekf(tmp_path_factory):
    return build_native_ekf_tuner(tmp_path_factory.mktemp("native_ekf") / "EKFTuner.fmu", **EKF_STARTS)


def assert_same(native_rows, twin_rows):
    native, twin = np.asarray(native_rows, dtype=float), np.asarray(twin_rows, dtype=float)
    scale = np.maximum(np.ptp(twin, axis=0), 1.0)
    np.testing.assert_allclose(native / scale, twin / scale, rtol=0, atol=1e-12)


def test_validation_passes_and_the_variables_are_the_twins(native_ekf, ekf_fmu):
    assert validate_fmu(str(native_ekf)) == []
    assert declared(native_ekf) == declared(ekf_fmu)
    assert "binaries/aarch64-linux/EKFTuner.so" in zipfile.ZipFile(native_ekf).namelist() or not shutil.which(
        "aarch64-linux-gnu-gcc")


def test_equals_the_pythonfmu_twin_with_steps_of_ts(native_ekf, ekf_fmu):
    inputs = _signals(2500)
    twin = run_fmpy(ekf_fmu, inputs, H, OUTPUTS)
    assert twin[-1][3] == 1.0 and twin[-1][1] == pytest.approx(OMEGA, rel=0.01)  # it converged and tuned
    assert_same(run_fmpy(native_ekf, inputs, H, OUTPUTS), twin)


def test_equals_the_twin_in_libcosim_and_ecos(native_ekf, ekf_fmu):
    inputs = _signals(800, seed=1)
    twin = run_fmpy(ekf_fmu, inputs, H, OUTPUTS)
    for run in (run_libcosim, run_ecos):
        assert_same(run(native_ekf, inputs, H, OUTPUTS), twin)


def _random_steps(path, times, inputs):
    """Outputs after each step of a run over the communication points ``times`` (random steps)."""
    slave, vr = initialised(path)
    rows = []
    for (t, t_next), values in zip(zip(times[:-1], times[1:]), inputs):
        slave.setReal([vr["u"], vr["vibration"]], [values["u"], values["vibration"]])
        slave.doStep(t, t_next - t)
        rows.append(slave.getReal([vr[name] for name in OUTPUTS]))
    slave.terminate()
    slave.freeInstance()
    return rows


def test_equals_the_twin_with_random_steps(native_ekf, ekf_fmu):
    rng = np.random.default_rng(7)
    steps = rng.choice([0.3, 0.5, 1.0, 1.7, 2.5], size=1500) * H
    steps[::13] = 1e-12  # a host's sliver of a step
    times = np.concatenate([[0.0], np.cumsum(steps)])
    inputs = _signals(len(steps), seed=5)
    twin = _random_steps(ekf_fmu, times, inputs)
    assert twin[-1][3] == 1.0
    assert_same(_random_steps(native_ekf, times, inputs), twin)


def test_parameters_set_before_initialisation_are_used_as_the_twin_uses_them(native_ekf, ekf_fmu):
    changed = {"kind": "mzv", "omega0": 2 * math.pi * 8.0, "Ts": 2e-3, "retune_fraction": 0.02}
    inputs = _signals(1200, seed=3)
    twin = run_fmpy(ekf_fmu, inputs, 2e-3, OUTPUTS, start_values=changed)
    assert twin[-1][3] == 1.0
    assert_same(run_fmpy(native_ekf, inputs, 2e-3, OUTPUTS, start_values=changed), twin)


def test_equals_the_twin_in_the_c_host_with_drifting_time_random_steps_and_exit_handler_teardown(
        native_ekf, ekf_fmu, c_host, tmp_path):
    """Both FMUs side by side in tests/hosts_c/fmi2_host.c: t += h with random steps (a third onto
    the grid), a 20 Hz vibration the EKF locks on to, instances freed from an exit handler."""
    from c_host import fmu_arguments, host_rows, run_host

    csv = tmp_path / "both.csv"
    result = run_host(c_host, [fmu_arguments(ekf_fmu, tmp_path / "twin"), fmu_arguments(native_ekf, tmp_path / "native")],
                      "--random", 11, 1e-9 * H, 7.3 * H, 8000, H, "--period", 50 * H, "--square", 0.0,
                      "--teardown", "atexit", "--csv", csv)
    assert result.returncode == 0, result.stderr[-3000:]
    rows = host_rows(csv)
    twin, native = rows[(0, 0, 0)], rows[(0, 1, 0)]
    assert np.array_equal(twin[:, :3], native[:, :3])  # the same times and inputs
    assert twin[-1, -1] == 1.0 and twin[-1, 4] == pytest.approx(2 * math.pi * 20.0, rel=1e-3)  # it tuned
    assert_same(native[:, 3:], twin[:, 3:])


def test_state_restores_the_ekf_and_the_shaper_exactly(native_ekf):
    inputs = _signals(1500, seed=2)
    slave, vr = initialised(native_ekf)
    _drive(slave, vr, inputs[:400], 0)
    state = slave.getFMUState()
    raw = slave.serializeFMUState(state)
    first = _drive(slave, vr, inputs[400:], 400)
    slave.setFMUState(state)
    again = _drive(slave, vr, inputs[400:], 400)
    slave.freeInstance()
    fresh, vr = initialised(native_ekf)
    fresh.setFMUState(fresh.deserializeFMUState(raw))
    restored = _drive(fresh, vr, inputs[400:], 400)
    fresh.freeInstance()
    assert again == first and restored == first and first[-1][3] == 1.0


@pytest.mark.parametrize(("starts", "words"), [
    ({"omega0": 4000.0}, "omega0 must be in (0, pi/Ts) = (0, 3141.59) rad/s, got 4000"),
    ({"kind": "ei"}, "kind must be one of zv, zvd, zvdd, zv_dn, mzv, got ei"),
    ({"Ts": -1e-3}, "Ts must be > 0, got -0.001"),
    ({"retune_fraction": 0.0}, "retune_fraction must be > 0, got 0"),
    ({"n": 63}, "n must be an integer in [0, 62], got 63"),
    ({"omega0": 1e-3}, "the EKF's convergence window; at most 1000000"),
])
def test_bad_parameters_are_refused_with_a_logged_message(native_ekf, capfd, starts, words):
    """Refused when set if the value alone is out of range, else at the exit of initialisation."""
    from fmpy.fmi1 import FMICallException

    slave = fmpy_slave(native_ekf, "bad")
    vr = variable_references(native_ekf)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    with pytest.raises(FMICallException) as refused:
        set_start_values(slave, vr, starts)
        slave.exitInitializationMode()
    slave.freeInstance()
    assert refused.value.status == 3  # fmi2Error
    assert words in capfd.readouterr().out


def test_a_non_finite_input_is_refused_when_set(native_ekf, capfd):
    slave, vr = configured(native_ekf)
    slave.exitInitializationMode()
    from fmpy.fmi1 import FMICallException

    with pytest.raises(FMICallException):
        slave.setReal([vr["vibration"]], [float("nan")])
    assert "vibration must be finite, got nan" in capfd.readouterr().out
    slave.freeInstance()


# ---------------------------------------------------------------- C hosts (t += h) on three platforms

def test_the_c_host_on_linux64_win64_and_aarch64_gives_the_same_numbers(native_ekf, tmp_path):
    """The host drives the vibration with its own sequence (u left at 0)."""
    from fmpy import read_model_description

    vr = {v.name: v.valueReference for v in read_model_description(str(native_ekf)).modelVariables}
    plan = f"input {vr['vibration']} 0.5\n" + "".join(f"output {vr[name]}\n" for name in OUTPUTS) + f"run 600 {H!r}\n"
    outputs = run_on_every_platform(native_ekf, plan, tmp_path)
    reference = outputs["linux64"].reshape(600, len(OUTPUTS))
    assert np.ptp(reference[:, 1]) > 0  # the EKF moved
    for platform in ("aarch64-linux", "win64"):
        assert_same(outputs[platform].reshape(600, len(OUTPUTS)), reference)


VALGRIND_DRIVER = twin_driver("ekf_tuner_model.h", "ekf_tuner_model", r"""
/* A 10 Hz ring-down at Ts = 1 ms and a command that moves and rests: the EKF converges, a shaper
 * is designed and switched in, so every buffer is used; steps of every kind. */
static int run(fmi2Component c, double *t, int steps, double *out) {
    static const double sizes[] = {1e-3, 2.5e-4, 1e-16, 3e-3, 7.5e-4, 1e-3};
    const fmi2ValueReference in[2] = {vr_of("u"), vr_of("vibration")};
    const fmi2ValueReference y[2] = {vr_of("y"), vr_of("converged")};
    for (int k = 0; k < steps; k++) {
        const double values[2] = {*t > 0.05 && *t < 0.3 ? 1.0 : *t > 1.5 ? 2.0 : 0.0,
                                  exp(-1.2566 * *t) * sin(62.83 * *t)};
        CHECK(fmi2SetReal(c, in, 2, values));
        CHECK(fmi2DoStep(c, *t, sizes[k % 6], fmi2True));
        *t += sizes[k % 6];
        CHECK(fmi2GetReal(c, y, 2, out));
    }
    return 0;
}

int main(void) {
    const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    double out[2] = {0.0, 0.0}, t = 0.0, value;
    fmi2Component c = fmi2Instantiate("c", fmi2CoSimulation, ekf_tuner_model.guid, "", &callbacks, fmi2False, fmi2True);
    if (c == NULL) return 1;
    REFUSED(fmi2DoStep(c, 0.0, 1e-3, fmi2True));                     /* before initialisation */
    CHECK(fmi2Reset(c));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    const fmi2ValueReference kind = vr_of("kind");
    const fmi2String mzv = "mzv";
    CHECK(fmi2SetString(c, &kind, 1, &mzv));
    CHECK(fmi2ExitInitializationMode(c));
    if (run(c, &t, 900, out)) return 1;
    fmi2FMUstate state = NULL;
    CHECK(fmi2GetFMUstate(c, &state));
    if (run(c, &t, 1500, out)) return 1;
    if (out[1] != 1.0) { fprintf(stderr, "the EKF did not converge\n"); return 1; }
    size_t size = 0;
    CHECK(fmi2SerializedFMUstateSize(c, state, &size));
    fmi2Byte *bytes = malloc(size);
    CHECK(fmi2SerializeFMUstate(c, state, bytes, size));
    fmi2FMUstate copy = NULL;
    CHECK(fmi2DeSerializeFMUstate(c, bytes, size, &copy));
    REFUSED(fmi2DeSerializeFMUstate(c, bytes, size - 1, &copy));        /* truncated */
    free(bytes);
    CHECK(fmi2SetFMUstate(c, copy));
    CHECK(fmi2FreeFMUstate(c, &copy));
    CHECK(fmi2FreeFMUstate(c, &state));
    REFUSED(fmi2DoStep(c, t, 2e7, fmi2True));                          /* too many samples */
    CHECK(fmi2Reset(c));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.5, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    const fmi2ValueReference omega0 = vr_of("omega0");
    value = 1.0 / 0.0;
    REFUSED(fmi2SetReal(c, &omega0, 1, &value));                       /* not finite */
    CHECK(fmi2Reset(c));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.5, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    CHECK(fmi2ExitInitializationMode(c));
    t = 0.5;
    if (run(c, &t, 300, out)) return 1;
    CHECK(fmi2Terminate(c));
    fmi2FreeInstance(c);
    printf("ok %g\n", out[0]);
    return 0;
}
""")


@pytest.mark.skipif(shutil.which("valgrind") is None or shutil.which("gcc") is None, reason="needs valgrind and gcc")
def test_valgrind_finds_no_invalid_access_and_no_leak(native_ekf, tmp_path):
    from test_plantgen_valgrind import run_driver_under_valgrind

    run_driver_under_valgrind(native_ekf, VALGRIND_DRIVER, tmp_path)
