"""The native C STOSController FMU equals its pythonfmu twin (paper 002's STOS law).

Both FMUs close the loop around the same rigid body (the disk drive's, modes at 2 and 3 kHz): the
native one's u, read after setting the measurement (feed-through), equals the pythonfmu one's bit
for bit with and without the settle hand-over, with damping (back EMF) and with a convolved ZV
shaper; in fmpy with random steps, libcosim, ecos, our C host (t += h, random steps, exit-handler
teardown) and the C host on win64 under Wine and aarch64 under qemu to 1e-12 of U. Its FMU state
restores exactly, the design parameters refuse another value than their build value, and
valgrind finds nothing.
"""

import shutil

import numpy as np
import pytest
from cross_hosts import run_on_every_platform
from fixtures_fmi import STOS_STARTS
from fmpy.validation import validate_fmu
from fmu_drivers import fmpy_slave, initialised, set_start_values, variable_references
from fmu_signal_drivers import run_ecos, run_fmpy, run_libcosim
from native_drivers import declared, twin_driver
from test_fmu_stos import SETTLE, TARGET, TS, U, _fmu_loop

from shapefmu.fmi import build_fmu
from shapefmu.fmi.native.stos import build_native_stos

# (name, start values): the disk drive's simultaneous shaper, the settle law, back EMF, convolved ZV
CASES = {"simultaneous": STOS_STARTS, "settle": {**STOS_STARTS, "settle": True, **SETTLE},
         "back EMF": {**STOS_STARTS, "damping": 650.0}, "zv convolved": {**STOS_STARTS, "kind": "zv"}}


@pytest.fixture(scope="module")
def twins(tmp_path_factory):
    folder = tmp_path_factory.mktemp("native_stos")
    return {name: (build_native_stos(folder / f"native_{i}.fmu", **starts), build_fmu("STOSController",
                   folder / f"twin_{i}.fmu", **starts)) for i, (name, starts) in enumerate(CASES.items())}


def test_validation_passes_and_the_variables_are_the_twins(twins):
    native, twin = twins["simultaneous"]
    assert validate_fmu(str(native)) == []
    assert declared(native) == declared(twin)


@pytest.mark.parametrize("case", CASES)
def test_closed_loop_equals_the_twin_bit_for_bit(twins, case):
    runs = []
    for fmu in twins[case]:
        slave, vr = initialised(fmu)
        controls, (x, _) = _fmu_loop(slave, vr, 520)
        slave.freeInstance()
        runs.append((controls, x))
    (native, x_native), (twin, x_twin) = runs
    assert native == twin
    assert max(map(abs, twin)) > 0.9 * U and len(set(twin)) > 5  # it banged and switched
    assert abs(x_twin - TARGET) < 2e-2 * TARGET


def test_state_restores_the_settle_law_exactly(twins):
    native, _ = twins["settle"]
    slave, vr = initialised(native)
    controls, plant = _fmu_loop(slave, vr, 320)
    state = slave.getFMUState()
    first, _ = _fmu_loop(slave, vr, 200, plant, 320)
    slave.setFMUState(state)
    again, _ = _fmu_loop(slave, vr, 200, plant, 320)
    raw = slave.serializeFMUState(state)
    slave.freeInstance()
    fresh, vr = initialised(native)
    fresh.setFMUState(fresh.deserializeFMUState(raw))
    restored, _ = _fmu_loop(fresh, vr, 200, plant, 320)
    fresh.freeInstance()
    assert again == first and restored == first


def _recorded_inputs(fmu, count):
    """The measurements of a closed loop, replayed open loop in every host."""
    from test_fmu_stos import _plant_step

    slave, vr = initialised(fmu)
    x = v = 0.0
    inputs = []
    for k in range(count):
        inputs.append({"target": TARGET, "x_r": x, "x_r_dot": v})
        slave.setReal([vr["target"], vr["x_r"], vr["x_r_dot"]], [TARGET, x, v])
        x, v = _plant_step(x, v, slave.getReal([vr["u"]])[0])
        slave.doStep(k * TS, TS)
    slave.freeInstance()
    return inputs


def test_equals_the_twin_in_libcosim_and_ecos(twins):
    native, twin = twins["simultaneous"]
    inputs = _recorded_inputs(twin, 300)
    reference = run_fmpy(twin, inputs, TS, ["u"])
    for run in (run_fmpy, run_libcosim, run_ecos):
        np.testing.assert_allclose(run(native, inputs, TS, ["u"]), reference, rtol=0, atol=1e-12 * U)


def test_equals_the_twin_with_random_steps(twins):
    native, twin = twins["settle"]
    inputs = _recorded_inputs(twin, 600)
    rng = np.random.default_rng(3)
    steps = rng.choice([0.25, 0.5, 1.0, 1.5, 3.0], size=len(inputs)) * TS
    steps[::11] = 1e-13
    times = np.concatenate([[0.0], np.cumsum(steps)])
    rows = []
    for fmu in (native, twin):
        slave, vr = initialised(fmu)
        out = []
        for (t, t_next), values in zip(zip(times[:-1], times[1:]), inputs):
            slave.setReal([vr[n] for n in values], list(values.values()))
            out.append(slave.getReal([vr["u"]])[0])
            slave.doStep(t, t_next - t)
            out.append(slave.getReal([vr["u"]])[0])
        slave.freeInstance()
        rows.append(out)
    assert rows[0] == rows[1]


def test_equals_the_twin_in_the_c_host_with_drifting_time_random_steps_and_exit_handler_teardown(twins, c_host,
                                                                                                  tmp_path):
    from c_host import fmu_arguments, host_rows, run_host

    native, twin = twins["simultaneous"]
    csv = tmp_path / "both.csv"
    result = run_host(c_host, [fmu_arguments(twin, tmp_path / "twin"), fmu_arguments(native, tmp_path / "native")],
                      "--random", 5, 1e-9 * TS, 7.3 * TS, 3000, TS, "--amplitude", 1e-3, "--period", 200 * TS,
                      "--teardown", "atexit", "--csv", csv)
    assert result.returncode == 0, result.stderr[-3000:]
    rows = host_rows(csv)
    twin_rows, native_rows = rows[(0, 0, 0)], rows[(0, 1, 0)]
    assert np.array_equal(twin_rows[:, :4], native_rows[:, :4])
    assert np.ptp(twin_rows[:, 4]) > U  # the law switched
    np.testing.assert_allclose(native_rows[:, 4], twin_rows[:, 4], rtol=0, atol=1e-12 * U)


@pytest.mark.parametrize(("starts", "words"), [
    ({"f[1]": 2100.0}, "f[1] is 2000 in this native FMU, whose shaper is designed at build time; got 2100"),
    ({"b": -1.0}, "b must be > 0, got -1"),
    ({"zeta[2]": 1.0}, "zeta[2] must be in [0, 1), got 1"),
    ({"kind": "zvd"}, "kind is simultaneous in this native FMU"),
    ({"n_modes": 1}, "n_modes is 2 in this native FMU"),
    ({"Ts": 0.0}, "Ts must be > 0, got 0"),
    ({"settle": True, **SETTLE, "x_exit": 1e-7}, "with settle on, x_exit must be >= x_enter, got 1e-07"),
])
def test_bad_parameters_are_refused_with_a_logged_message(twins, capfd, starts, words):
    from fmpy.fmi1 import FMICallException

    native, _ = twins["simultaneous"]
    slave = fmpy_slave(native, "bad")
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    with pytest.raises(FMICallException) as refused:
        set_start_values(slave, variable_references(native), starts)
        slave.exitInitializationMode()
    slave.freeInstance()
    assert refused.value.status == 3 and words in capfd.readouterr().out


@pytest.mark.parametrize(("case", "changed"), [
    ("simultaneous", {"Ts": 2e-5, "settle": True, **SETTLE}),
    ("simultaneous", {"b": 3.1e3, "U": 9.0, "damping": 300.0}),  # the curves redesigned in C for this body
    ("zv convolved", {"kind": "mzv", "n_modes": 1, "f[1]": 1500.0, "zeta[1]": 0.05, "U": 12.0}),  # and this shaper
    ("zv convolved", {"kind": "zv_dn", "n": 2, "f[2]": 3500.0}),
])
def test_parameters_set_before_initialisation_act_as_on_the_twin(twins, case, changed):
    native, twin = twins[case]
    runs = []
    for fmu in (native, twin):
        slave, vr = initialised(fmu, changed)
        runs.append(_fmu_loop(slave, vr, 400)[0])
        slave.freeInstance()
    assert runs[0] == runs[1] and len(set(runs[1])) > 3


@pytest.mark.parametrize("case", ["back EMF", "settle"])
def test_the_c_host_on_linux64_win64_and_aarch64_gives_the_same_numbers(twins, tmp_path, case):
    """Back EMF: the law's log1p and expm1 from each platform's own libm; settle: the sub-sample
    blend (bisection on the predicted flow) every sample. The host drives the position error with
    its own sequence (+-1 mm), so the law visits many regions."""
    from fmpy import read_model_description

    native, _ = twins[case]
    vr = {v.name: v.valueReference for v in read_model_description(str(native)).modelVariables}
    outputs = run_on_every_platform(native, f"input {vr['x_r']} 1e-3\noutput {vr['u']}\nrun 800 {TS!r}\n", tmp_path)
    reference = outputs["linux64"]
    assert reference.size == 800 and np.ptp(reference) > 0.5 * U and len(set(reference)) > 3
    for platform in ("aarch64-linux", "win64"):
        np.testing.assert_allclose(outputs[platform], reference, rtol=0, atol=1e-12 * U, err_msg=platform)


VALGRIND_DRIVER = twin_driver("stos_model.h", "stos_variables", r"""
/* The closed loop around the rigid body x'' = b u, with steps of every kind. */
static int run(fmi2Component c, double *t, double *x, double *v, int steps) {
    static const double sizes[] = {1e-5, 2.5e-6, 1e-16, 3e-5, 7.5e-6, 1e-5};
    const fmi2ValueReference in[3] = {vr_of("target"), vr_of("x_r"), vr_of("x_r_dot")}, out = vr_of("u");
    for (int k = 0; k < steps; k++) {
        const double values[3] = {1e-3, *x, *v}, h = sizes[k % 6];
        double u;
        CHECK(fmi2SetReal(c, in, 3, values));
        CHECK(fmi2GetReal(c, &out, 1, &u));
        CHECK(fmi2DoStep(c, *t, h, fmi2True));
        *t += h;
        *x += *v * h + 0.5 * 2.7e3 * u * h * h;
        *v += 2.7e3 * u * h;
    }
    return 0;
}

int main(void) {
    const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    double t = 0.0, x = 0.0, v = 0.0, value;
    fmi2Component c = fmi2Instantiate("c", fmi2CoSimulation, stos_variables.guid, "", &callbacks, fmi2False, fmi2True);
    if (c == NULL) return 1;
    REFUSED(fmi2DoStep(c, 0.0, 1e-5, fmi2True));                     /* before initialisation */
    CHECK(fmi2Reset(c));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    const fmi2ValueReference f1 = vr_of("f[1]");
    value = 2100.0;
    REFUSED(fmi2SetReal(c, &f1, 1, &value));                           /* a design parameter */
    CHECK(fmi2Reset(c));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    CHECK(fmi2ExitInitializationMode(c));
    if (run(c, &t, &x, &v, 300)) return 1;
    fmi2FMUstate state = NULL;
    CHECK(fmi2GetFMUstate(c, &state));
    if (run(c, &t, &x, &v, 300)) return 1;
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
    REFUSED(fmi2DoStep(c, t, 2e3, fmi2True));                          /* too many samples */
    CHECK(fmi2Reset(c));                                                /* out of the error state */
    fmi2FreeInstance(c);
    printf("ok %g\n", x);
    return 0;
}
""")


@pytest.mark.skipif(shutil.which("valgrind") is None or shutil.which("gcc") is None, reason="needs valgrind and gcc")
def test_valgrind_finds_no_invalid_access_and_no_leak(twins, tmp_path):
    from test_plantgen_valgrind import run_driver_under_valgrind

    run_driver_under_valgrind(twins["settle"][0], VALGRIND_DRIVER, tmp_path)
