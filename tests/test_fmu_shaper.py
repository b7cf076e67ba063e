"""The Shaper FMU: modelDescription, output against the design layer, state, errors, isolation."""

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
from support.fixtures_fmi import MULTIMODE_STARTS, SHAPER_STARTS, command_signal
from support.fmpy_slaves import (
    assert_nan_input_fails_that_step_only,
    assert_state_restores_exactly,
    initialised,
    y_after_each_set,
)
from support.hosts import run_ecos, run_fmpy, run_libcosim, y_of_u

from shapefmu.shapers import design

H = 1e-3


def _sampled_outputs(path, commands):
    """y read right after u is set at each communication point k H, then one step (feed-through)."""
    return np.array(y_after_each_set(path, commands, [(k * H, H) for k in range(len(commands))]))


def test_model_description_passes_fmpy_validation(shaper_fmu):
    assert validate_fmu(str(shaper_fmu)) == []


def test_model_description_declares_feed_through_units_and_state_handling(shaper_fmu):
    root = model_xml(shaper_fmu)
    index = assert_documented(root)
    (output,) = root.find("ModelStructure/Outputs")
    # ZV's first impulse is at t = 0: y feeds through from u, with the factor fixed at initialisation.
    assert (output.get("index"), output.get("dependencies"), output.get("dependenciesKind")) == (index["y"], index["u"], "fixed")
    (initial,) = root.find("ModelStructure/InitialUnknowns")
    assert initial.get("index") == index["y"] and index["u"] in initial.get("dependencies").split()
    experiment = root.find("DefaultExperiment")
    assert float(experiment.get("stepSize")) == SHAPER_STARTS["Ts"]


def test_output_equals_the_design_layer_offline_shaping(shaper_fmu):
    commands = np.array(command_signal(200))
    shaper = design("zv", [(2 * math.pi * SHAPER_STARTS["f[1]"], 0.0)])
    t = np.arange(commands.size) * H
    before = np.concatenate([[SHAPER_STARTS["u0"]], commands])  # the command rests at u0 before t = 0
    expected = shaper.apply(np.concatenate([[-H], t]), before, hold="zoh")[1:]
    np.testing.assert_allclose(_sampled_outputs(shaper_fmu, commands), expected, rtol=0, atol=1e-12)


def test_simultaneous_multimode_output_equals_the_sampled_design(multimode_shaper_fmu):
    commands = np.array(command_signal(300))
    modes = [(2 * math.pi * MULTIMODE_STARTS[f"f[{i}]"], MULTIMODE_STARTS[f"zeta[{i}]"]) for i in (1, 2)]
    sampled = design("simultaneous", modes).on_grid(H)  # scipy's design, split onto the grid
    expected = sampled.apply(np.concatenate([[0.0], commands]))[1:]  # at rest on u0 = 0 before
    np.testing.assert_allclose(_sampled_outputs(multimode_shaper_fmu, commands), expected, rtol=0, atol=1e-10)


def test_ei_family_output_equals_the_sampled_design(tmp_path):
    from shapefmu.fmi import build_fmu

    # A damped three-hump EI at a 5 % tolerance, off the sample grid: designed inside the FMU by
    # runtime/ei.py, here by the design layer's scipy continuation.
    starts = {"kind": "ei3", "vtol": 0.05, "f[1]": 13.0, "zeta[1]": 0.1, "Ts": H}
    fmu = build_fmu("Shaper", tmp_path / "EI3.fmu", **starts)
    commands = np.array(command_signal(300))
    sampled = design("ei3", [(2 * math.pi * 13.0, 0.1)], vtol=0.05).on_grid(H)
    expected = sampled.apply(np.concatenate([[0.0], commands]))[1:]  # at rest on u0 = 0 before
    np.testing.assert_allclose(_sampled_outputs(fmu, commands), expected, rtol=0, atol=1e-12)


def test_outputs_identical_in_fmpy_libcosim_and_ecos(shaper_fmu):
    commands = command_signal(150)
    reference = y_of_u(run_fmpy, shaper_fmu, commands, H)
    for other in (y_of_u(run_libcosim, shaper_fmu, commands, H), y_of_u(run_ecos, shaper_fmu, commands, H)):
        np.testing.assert_allclose(other, reference, rtol=0, atol=1e-12)


def test_get_and_set_and_serialised_state_restore_exactly(shaper_fmu):
    assert_state_restores_exactly(shaper_fmu, command_signal(120), H, at=40)


def test_a_forged_state_is_refused_with_error_and_the_instance_lives_on(shaper_fmu):
    slave, vr = initialised(shaper_fmu)
    with pytest.raises(FMICallException) as failure:
        slave.setFMUState(slave.deserializeFMUState(b'{"not": "a state"}'))
    assert failure.value.status == 3  # fmi2Error
    slave.setReal([vr["u"]], [2.0])
    slave.doStep(0.0, H)
    assert slave.getReal([vr["y"]])[0] == pytest.approx(0.5 * 2.0 + 0.5 * SHAPER_STARTS["u0"], abs=1e-15)
    slave.freeInstance()


@pytest.mark.parametrize(
    "name, value, words",
    [("zeta[1]", 1.0, "zeta[1] must be in [0, 1)"), ("f[1]", -5.0, "f[1] must be > 0"), ("Ts", 0.0, "Ts must be > 0")],
)
def test_bad_parameters_fail_initialisation_with_error_and_a_logged_message(shaper_fmu, name, value, words):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(shaper_fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(shaper_fmu)), modelIdentifier="Shaper", instanceName="bad")
    slave.instantiate(loggingOn=False)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setReal([vr[name]], [value])
    with pytest.raises(FMICallException) as failure:
        slave.exitInitializationMode()
    assert failure.value.status == 3
    slave.freeInstance()


def test_bad_parameter_message_reaches_the_host_logger(shaper_fmu, capfd):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(shaper_fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(shaper_fmu)), modelIdentifier="Shaper", instanceName="bad")
    slave.instantiate()
    slave.enterInitializationMode()
    slave.setReal([vr["zeta[1]"]], [1.2])
    with pytest.raises(FMICallException):
        slave.exitInitializationMode()
    slave.freeInstance()
    assert "zeta[1] must be in [0, 1), got 1.2" in capfd.readouterr().out


def test_between_samples_y_holds_and_a_new_u_waits_for_the_next_sample(shaper_fmu):
    # ZV for 10 Hz at 1 ms: y[k] = (u[k] + u[k - 50]) / 2, the command at u0 = -1 before t = 0.
    slave, vr = initialised(shaper_fmu)

    def y_after_setting(u):
        slave.setReal([vr["u"]], [u])
        return slave.getReal([vr["y"]])[0]

    assert y_after_setting(2.0) == 0.5 * 2.0 - 0.5  # on sample 0: fed through
    slave.doStep(0.0, 1.5 * H)  # samples 0 and 1 (u = 2 in effect at 1 ms), then between samples
    assert y_after_setting(7.0) == 0.5 * 2.0 - 0.5  # held: sample 1's output; 7 waits
    slave.doStep(1.5 * H, 0.5 * H)  # onto sample 2, whose input is the 7 set at 1.5 ms
    assert slave.getReal([vr["y"]])[0] == 0.5 * 7.0 - 0.5
    slave.doStep(2 * H, 1e-16)  # a step of 1e-16 s stays on sample 2's instant: still fed through
    assert y_after_setting(3.0) == 0.5 * 3.0 - 0.5
    slave.freeInstance()


def test_state_restores_exactly_between_samples(shaper_fmu):
    # Steps of 1.5 ms: after step 41 (61.5 ms) the clock is between samples, its input latched.
    assert_state_restores_exactly(shaper_fmu, command_signal(120), 1.5 * H, at=41)


def test_nan_input_fails_that_step_and_leaves_the_state_untouched(shaper_fmu):
    assert_nan_input_fails_that_step_only(shaper_fmu, command_signal(80), H, at=30)


def test_runs_with_only_the_standard_library_and_two_builds_run_their_own_code(shaper_fmu, tmp_path, monkeypatch):
    from fmpy import extract

    from shapefmu.fmi.python import builder

    # A second build whose bundled design module differs: its "zv" designs a ZVD shaper.
    original = builder.bundled_sources

    def patched(name):
        files = original(name)
        source = files["runtime/shaper_designs.py"].decode()
        files["runtime/shaper_designs.py"] = source.replace("zv_dn(w, z, 0)", "zv_dn(w, z, 1)").encode()
        return files

    monkeypatch.setattr(builder, "bundled_sources", patched)
    other = builder.build_fmu("Shaper", tmp_path / "Other.fmu", **SHAPER_STARTS)
    monkeypatch.undo()
    packages = {json.loads(zipfile.ZipFile(p).read("resources/shapefmu_build.json"))["package"] for p in (shaper_fmu, other)}
    assert len(packages) == 2
    dirs = [extract(str(p), str(tmp_path / name)) for p, name in ((shaper_fmu, "a"), (other, "b"))]
    steps = 120
    result = subprocess.run(
        [sys.executable, "-I", "-S", str(CTYPES_HOST), ",".join(map(str, dirs)), str(steps), str(H)],
        capture_output=True, text=True, timeout=60,
    )
    assert result.returncode == 0, result.stderr
    zv_out, zvd_out = (np.array(json.loads(line)) for line in result.stdout.splitlines())
    commands = np.array(command_signal(steps))
    w = 2 * math.pi * SHAPER_STARTS["f[1]"]
    for kind, out in (("zv", zv_out), ("zvd", zvd_out)):
        taps = design(kind, [(w, 0.0)]).on_grid(H)
        # After step k the command is held at u[k]: y = (filter of u[0..k+1])[k+1] with u[k+1] -> u[k],
        # by linearity the filter's output plus w_0 (u[k] - u[k+1]).
        extended = np.concatenate([commands, [commands[-1]]])
        fed = taps.apply(np.concatenate([np.full(60, SHAPER_STARTS["u0"]), extended]))[61:]
        expected = fed + taps.taps[0] * (extended[:-1] - extended[1:])
        np.testing.assert_allclose(out, expected, rtol=0, atol=1e-12)
