"""The ShapeFilter FMU: modelDescription, output against the design layer, hosts, state, errors."""

import json
import math
import subprocess
import sys
import zipfile

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from support import CTYPES_HOST
from support.declarations import assert_documented, model_xml
from support.fixtures_fmi import (
    FEEDTHROUGH_FILTER_STARTS,
    SHAPE_FILTER_F,
    SHAPE_FILTER_STARTS,
    SHAPE_FILTER_ZETA,
    command_signal,
)
from support.fmpy_slaves import (
    assert_nan_input_fails_that_step_only,
    assert_state_restores_exactly,
    configured,
    initialised,
    y_after_each_set,
)
from support.hosts import run_ecos, run_ecos_program, run_fmpy, run_libcosim, y_of_u
from support.sampled_reference import SampledRun

from shapefmu.runtime import time_frequency as runtime_time_frequency
from shapefmu.shapers import TWIN_PULSE_PROFILES, WINDOW_FILTERS, SampledShaper, time_frequency_profile

H = 1e-3
OMEGA = 2 * math.pi * SHAPE_FILTER_F


def _feedthrough_outputs(path, parameters, commands):
    """(y read right after u is set at each communication point k Ts_used, Ts_used): one sample per step."""
    slave, vr = initialised(path, parameters)
    (ts,) = slave.getReal([vr["Ts_used"]])
    slave.freeInstance()
    return np.array(y_after_each_set(path, commands, [(k * ts, ts) for k in range(len(commands))], parameters)), ts


def _offline(shaper, commands, u0=0.0):
    """The design layer's shaping of ``commands`` from rest at ``u0``, y[k] = sum_j taps[j] u[k - j]."""
    return shaper.apply(np.concatenate([[u0], commands]))[1:]


def _after_each_step(shaper, commands, u0):
    """y at the end of each step, u[k] still held: the offline output at k + 1 with u[k + 1] -> u[k]."""
    commands = np.asarray(commands, dtype=float)
    extended = np.concatenate([commands, [commands[-1]]])
    return _offline(shaper, extended, u0)[1:] + shaper.taps[0] * (extended[:-1] - extended[1:])


def _fixture_design():
    """The design layer's damped Hanning filter of order 2 that SHAPE_FILTER_STARTS describe."""
    return WINDOW_FILTERS["hanning"](OMEGA, SHAPE_FILTER_ZETA, H, SHAPE_FILTER_STARTS["order"])


# --- modelDescription -------------------------------------------------------------------------


def test_model_descriptions_pass_fmpy_validation(shape_filter_fmu, feedthrough_filter_fmu):
    assert validate_fmu(str(shape_filter_fmu)) == []
    assert validate_fmu(str(feedthrough_filter_fmu)) == []


def test_hanning_does_not_feed_through_and_every_variable_has_unit_and_description(shape_filter_fmu):
    root = model_xml(shape_filter_fmu)
    index = assert_documented(root)
    outputs = {o.get("index"): o for o in root.find("ModelStructure/Outputs")}
    # The Hanning window's first sample is 0.5 - 0.5 cos 0 = 0: y at t depends on u before t only.
    assert _fixture_design().taps[0] == 0.0
    assert outputs[index["y"]].get("dependencies") == "" and outputs[index["Ts_used"]].get("dependencies") == ""
    initial = {o.get("index"): o.get("dependencies").split() for o in root.find("ModelStructure/InitialUnknowns")}
    assert index["u"] not in initial[index["y"]] and index["f"] in initial[index["y"]]
    experiment = root.find("DefaultExperiment")
    assert float(experiment.get("stepSize")) == SHAPE_FILTER_STARTS["Ts"]


def test_rectangle_feeds_through_with_a_fixed_factor(feedthrough_filter_fmu):
    root = model_xml(feedthrough_filter_fmu)
    variables = root.find("ModelVariables").findall("ScalarVariable")
    index = {v.get("name"): str(i + 1) for i, v in enumerate(variables)}
    outputs = {o.get("index"): o for o in root.find("ModelStructure/Outputs")}
    y = outputs[index["y"]]
    assert (y.get("dependencies"), y.get("dependenciesKind")) == (index["u"], "fixed")
    # Setting u changes y at once by the first tap, 1/M damping-compensated (M = 100).
    slave, vr = initialised(feedthrough_filter_fmu)
    before = slave.getReal([vr["y"]])[0]
    slave.setReal([vr["u"]], [1.0])
    first_tap = WINDOW_FILTERS["rectangle"](OMEGA, SHAPE_FILTER_ZETA, H).taps[0]
    assert slave.getReal([vr["y"]])[0] - before == pytest.approx(first_tap, abs=1e-15)
    slave.freeInstance()


# --- output against the design layer -----------------------------------------------------------


def test_output_equals_the_design_layer_offline_filtering(shape_filter_fmu):
    commands = np.array(command_signal(700))
    outputs, ts = _feedthrough_outputs(shape_filter_fmu, {}, commands)
    assert ts == H
    expected = _offline(_fixture_design(), commands, SHAPE_FILTER_STARTS["u0"])
    np.testing.assert_allclose(outputs, expected, rtol=0, atol=1e-12)


def test_blackman_starts_at_zero_and_runs_in_an_fmu_built_without_feed_through(shape_filter_fmu):
    # Its first sample is 0.42 - 0.5 + 0.08 = 0, which floating point leaves at ~1e-19: taken as the
    # zero it is, the Hanning-built FMU (y independent of u) accepts it.
    shaper = WINDOW_FILTERS["blackman"](OMEGA, SHAPE_FILTER_ZETA, H)
    assert abs(shaper.taps[0]) < 1e-15 * np.max(shaper.taps)
    commands = np.array(command_signal(500))
    outputs, _ = _feedthrough_outputs(shape_filter_fmu, {"kind": "blackman", "order": 1}, commands)
    np.testing.assert_allclose(outputs, _offline(shaper, commands, SHAPE_FILTER_STARTS["u0"]), rtol=0, atol=1e-12)


WINDOW_CASES = [
    ({"kind": "rectangle", "order": 3}, {}),
    ({"kind": "blackman"}, {}),
    ({"kind": "hamming", "order": 2}, {}),
    ({"kind": "three-hanning", "c": 0.5, "adjust_Ts": True}, {"c": 0.5, "adjust_ts": True}),
    ({"kind": "differenced", "base": "rectangle"}, {"base": "rectangle"}),
    ({"kind": "convolved", "base": "blackman"}, {"base": "blackman"}),
]


@pytest.mark.parametrize("parameters, options", WINDOW_CASES, ids=[p["kind"] for p, _ in WINDOW_CASES])
def test_window_filters_equal_the_design_layer(feedthrough_filter_fmu, parameters, options):
    commands = np.array(command_signal(500))
    outputs, ts = _feedthrough_outputs(feedthrough_filter_fmu, parameters, commands)
    shaper = WINDOW_FILTERS[parameters["kind"]](OMEGA, SHAPE_FILTER_ZETA, H, parameters.get("order", 1), **options)
    assert ts == shaper.ts
    np.testing.assert_allclose(outputs, _offline(shaper, commands), rtol=0, atol=1e-12)


TWIN_PULSE_CASES = [
    ({"kind": "TP"}, {}),
    ({"kind": "TP:BC", "null": 3}, {"null": 3}),
    ({"kind": "M-TP:BC", "delta_f": 0.5}, {"delta_omega": 2 * math.pi * 0.5}),
    ({"kind": "BC:TZ"}, {}),
    ({"kind": "M-BC:TZ:TP", "delta_f": 0.3}, {"delta_omega": 2 * math.pi * 0.3}),
]


@pytest.mark.parametrize("parameters, options", TWIN_PULSE_CASES, ids=[p["kind"] for p, _ in TWIN_PULSE_CASES])
def test_twin_pulse_kernels_equal_the_design_layer(feedthrough_filter_fmu, parameters, options):
    commands = np.array(command_signal(500))
    outputs, _ = _feedthrough_outputs(feedthrough_filter_fmu, {"zeta": 0.0, **parameters}, commands)
    # The kernel TP * BC is the same for any move (a move of 1 m at 1 m/s here).
    design = TWIN_PULSE_PROFILES[parameters["kind"]](OMEGA, 1.0, 1.0, ts=H, **options)
    kernel = design.profile.kernel
    assert kernel.gain == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(outputs, _offline(kernel, commands), rtol=0, atol=1e-12)


def test_time_frequency_filter_is_the_normalised_velocity_of_the_design_layer_move(feedthrough_filter_fmu):
    move_time = 0.1
    commands = np.array(command_signal(400))
    outputs, _ = _feedthrough_outputs(
        feedthrough_filter_fmu, {"kind": "time-frequency", "zeta": 0.0, "move_time": move_time}, commands
    )
    # The runtime's bounded Brent search and scipy's agree on the scale to ~1e-6; the taps are
    # compared at the runtime's scale, which the FMU uses.
    n, _ = runtime_time_frequency.optimal_scale(OMEGA, H, move_time)
    scipy_design = time_frequency_profile(OMEGA, H, move_time, 1.0)
    assert n == pytest.approx(scipy_design.n, abs=1e-5)
    velocity = time_frequency_profile(OMEGA, H, move_time, 1.0, n=n).profile.velocity
    m = round(move_time / H)
    assert abs(velocity[m + 1]) < 1e-12 * np.max(np.abs(velocity))  # the move ends at rest
    shaper = SampledShaper(velocity[: m + 1] / np.sum(velocity[: m + 1]), H)
    np.testing.assert_allclose(outputs, _offline(shaper, commands), rtol=0, atol=1e-12)


def test_cli_bakes_a_design_and_refuses_a_bad_one_with_exit_code_2(tmp_path, capsys):
    from shapefmu.cli import main

    out = tmp_path / "HanningFilter.fmu"
    assert main(["build", "shape-filter", "--kind", "blackman", "--mode", "10", "--order", "2", "-o", str(out)]) == 0
    assert validate_fmu(str(out)) == []
    baked = json.loads(zipfile.ZipFile(out).read("resources/shapefmu_build.json"))["start_values"]
    assert (baked["kind"], baked["order"], baked["f"]) == ("blackman", 2, pytest.approx(10.0, rel=1e-15))
    commands = np.array(command_signal(200))
    outputs, _ = _feedthrough_outputs(out, {}, commands)
    shaper = WINDOW_FILTERS["blackman"](2 * math.pi * 10.0, 0.0, H, 2)
    np.testing.assert_allclose(outputs, _offline(shaper, commands), rtol=0, atol=1e-12)
    with pytest.raises(SystemExit) as refused:
        main(["build", "shape-filter", "--kind", "hanning", "--mode", "10", "--ts", "1.3e-3", "-o", str(tmp_path / "x.fmu")])
    assert refused.value.code == 2 and "which is not an integer" in capsys.readouterr().err
    assert not (tmp_path / "x.fmu").exists()


# --- hosts ------------------------------------------------------------------------------------


@pytest.mark.parametrize("fixture", ["shape_filter_fmu", "feedthrough_filter_fmu"])
def test_outputs_identical_in_fmpy_libcosim_and_ecos(fixture, request):
    path = request.getfixturevalue(fixture)
    commands = command_signal(400)
    reference = y_of_u(run_fmpy, path, commands, H)
    starts = SHAPE_FILTER_STARTS if fixture == "shape_filter_fmu" else FEEDTHROUGH_FILTER_STARTS
    shaper = WINDOW_FILTERS[starts["kind"]](OMEGA, SHAPE_FILTER_ZETA, H, starts.get("order", 1))
    np.testing.assert_allclose(reference, _after_each_step(shaper, commands, starts.get("u0", 0.0)), rtol=0, atol=1e-12)
    for other in (y_of_u(run_libcosim, path, commands, H), y_of_u(run_ecos, path, commands, H)):
        np.testing.assert_allclose(other, reference, rtol=0, atol=1e-12)


def test_runs_in_the_ecos_command_line_host_without_python_or_ld_preload(shape_filter_fmu, tmp_path):
    y = run_ecos_program(shape_filter_fmu, step=0.001, stop_time=0.5, workdir=tmp_path)["instance::y[REAL]"]
    # u stays at its start value 0 after resting at u0 = -1: the filter's step response; ecos
    # writes 6 decimals.
    expected = _offline(_fixture_design(), np.zeros(y.size), SHAPE_FILTER_STARTS["u0"])
    np.testing.assert_allclose(y, expected, rtol=0, atol=5e-7)


def test_runs_with_only_the_standard_library(shape_filter_fmu, tmp_path):
    from fmpy import extract

    directory = extract(str(shape_filter_fmu), str(tmp_path / "unzipped"))
    steps = 300
    result = subprocess.run(
        [sys.executable, "-I", "-S", str(CTYPES_HOST), str(directory), str(steps), str(H)],
        capture_output=True, text=True, timeout=60,
    )
    assert result.returncode == 0, result.stderr
    out = json.loads(result.stdout.splitlines()[0])
    expected = _after_each_step(_fixture_design(), command_signal(steps), SHAPE_FILTER_STARTS["u0"])
    np.testing.assert_allclose(out, expected, rtol=0, atol=1e-12)


# --- state ------------------------------------------------------------------------------------


def test_get_and_set_and_serialised_state_restore_exactly(shape_filter_fmu):
    assert_state_restores_exactly(shape_filter_fmu, command_signal(500), H, at=250)


# --- errors -----------------------------------------------------------------------------------

BAD_PARAMETERS = [
    ({"zeta": 1.0}, "zeta must be in [0, 1), got 1.0"),
    ({"f": -5.0}, "f must be > 0, got -5.0"),
    ({"kind": "kaiser"}, "kind must be a window filter"),
    ({"order": 0}, "order must be an integer >= 1, got 0"),
    # 1.3 ms makes the Hanning window 200 / 1.3 = 153.8 samples long; M = 153 needs Ts = 2 / (f_d M).
    ({"Ts": 1.3e-3}, "which is not an integer; valid ts make M an integer >= 4, the nearest are 0.001307189542 s"),
    ({"kind": "TP"}, "zeta must be 0 and order 1"),
    ({"kind": "time-frequency", "zeta": 0.0, "order": 1, "move_time": 0.1005}, "move_time / ts must be an integer"),
    ({"kind": "M-TP:BC", "zeta": 0.0, "order": 1, "delta_f": 12.0}, "delta_f must be in [0, f) = [0, 10.0125) Hz, got 12.0"),
    # Built declaring y independent of u, the FMU cannot become a rectangle, whose y feeds through.
    ({"kind": "rectangle", "order": 1}, "y feeds through from ['u']"),
]


@pytest.mark.parametrize("parameters, words", BAD_PARAMETERS, ids=[w for _, w in BAD_PARAMETERS])
def test_bad_parameters_fail_initialisation_with_error_and_a_logged_message(shape_filter_fmu, capfd, parameters, words):
    slave, vr = configured(shape_filter_fmu, parameters, "bad")
    with pytest.raises(FMICallException) as failure:
        slave.exitInitializationMode()
    assert failure.value.status == 3  # fmi2Error
    with pytest.raises(FMICallException):
        slave.doStep(0.0, H)  # the instance stays refused, and alive
    slave.freeInstance()
    logged = capfd.readouterr().out
    assert "ShapeFilter bad: invalid parameters" in logged and words in logged


@pytest.mark.parametrize("step", [3 * H, 1.5 * H, 0.4 * H])
def test_steps_of_any_size_sample_on_the_grid_and_hold_between_samples(shape_filter_fmu, step):
    commands = command_signal(300)
    out = y_after_each_set(shape_filter_fmu, commands, [(k * step, step) for k in range(len(commands))])
    run = SampledRun(step * np.arange(len(commands)), commands, H)
    expected = run.fir(_fixture_design().taps, SHAPE_FILTER_STARTS["u0"])
    np.testing.assert_allclose(out, expected, rtol=0, atol=1e-12)


def test_state_restores_exactly_between_samples(shape_filter_fmu):
    # Steps of 1.5 ms: after step 101 (151.5 ms) the clock is between samples, its input latched.
    assert_state_restores_exactly(shape_filter_fmu, command_signal(300), 1.5 * H, at=101)


def test_nan_input_fails_that_step_and_leaves_the_state_untouched(shape_filter_fmu):
    assert_nan_input_fails_that_step_only(shape_filter_fmu, command_signal(300), H, at=100)
