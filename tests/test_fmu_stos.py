"""The STOSController FMU in closed loop with a rigid body, against the runtime STOS kernel called directly."""

import math
import zipfile
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from fixtures_fmi import STOS_STARTS
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu
from fmu_drivers import initialised, refused_initialisation
from fmu_signal_drivers import run_ecos, run_fmpy, run_libcosim

from shapefmu.runtime import shaper_designs
from shapefmu.runtime.stos import STOSKernel, stos_curves

B, U, TS = STOS_STARTS["b"], STOS_STARTS["U"], STOS_STARTS["Ts"]
MODES = [(2 * math.pi * 2000.0, 0.01), (2 * math.pi * 3000.0, 0.01)]
TARGET = 1e-3
# A hand-over region the loop below enters (x within 2 um, v within 0.2 m/s), gains that keep the
# linear law within U there.
SETTLE = {"kp": 2.75e6, "kd": 27.5, "ki": 1e8, "x_enter": 2e-6, "v_enter": 0.2, "x_exit": 4e-6, "v_exit": 0.4}


def _plant_step(x, v, u):
    """The rigid body x'' = b u over one sample with u held: exact."""
    return x + v * TS + 0.5 * B * u * TS * TS, v + B * u * TS


def _kernel_loop(count, settle=None):
    times, amplitudes = shaper_designs.design_impulses("simultaneous", MODES)
    kernel = STOSKernel(stos_curves(B, U, times, amplitudes), None if settle is None else settle | {"Ts": TS})
    x = v = 0.0
    controls = []
    for _ in range(count):
        u = kernel.control(TARGET, x, v)
        controls.append(u)
        x, v = _plant_step(x, v, u)
    return controls, kernel


def _fmu_loop(slave, vr, count, state=(0.0, 0.0), start=0):
    x, v = state
    controls = []
    for k in range(start, start + count):
        slave.setReal([vr["target"], vr["x_r"], vr["x_r_dot"]], [TARGET, x, v])
        (u,) = slave.getReal([vr["u"]])  # feed-through: the law at this instant's measurement
        controls.append(u)
        slave.doStep(k * TS, TS)
        x, v = _plant_step(x, v, u)
    return controls, (x, v)


def test_model_description_passes_fmpy_validation(stos_fmu):
    assert validate_fmu(str(stos_fmu)) == []


def test_u_feeds_through_from_target_and_the_measured_state(stos_fmu):
    root = ET.fromstring(zipfile.ZipFile(stos_fmu).read("modelDescription.xml"))
    names = [v.get("name") for v in root.iter("ScalarVariable")]
    (output,) = root.find("ModelStructure/Outputs")
    assert sorted(names[int(i) - 1] for i in output.get("dependencies").split()) == ["target", "x_r", "x_r_dot"]


def test_closed_loop_controls_equal_the_runtime_kernel_called_directly(stos_fmu):
    slave, vr = initialised(stos_fmu)
    controls, (x, _) = _fmu_loop(slave, vr, 400)
    slave.freeInstance()
    expected, _ = _kernel_loop(400)
    assert controls == expected  # bit for bit
    assert max(map(abs, controls)) == pytest.approx(U, rel=1e-12)  # it bangs at the limit
    assert abs(x - TARGET) < 1e-2 * TARGET  # and arrives


def test_settle_hand_over_and_its_integrator_equal_the_kernel_and_survive_a_state_restore(stos_fmu):
    starts = {"settle": True, **SETTLE}
    slave, vr = initialised(stos_fmu, starts)
    controls, plant = _fmu_loop(slave, vr, 320)
    state = slave.getFMUState()
    first, _ = _fmu_loop(slave, vr, 200, plant, 320)
    slave.setFMUState(state)
    again, _ = _fmu_loop(slave, vr, 200, plant, 320)
    slave.setFMUState(state)
    raw = slave.serializeFMUState(state)
    slave.freeInstance()
    expected, kernel = _kernel_loop(520, SETTLE)
    assert kernel.get_state()[0] == 1.0  # the linear law is in charge by the end
    assert controls + first == expected
    assert again == first
    fresh, vr = initialised(stos_fmu, starts)
    fresh.setFMUState(fresh.deserializeFMUState(raw))
    restored, _ = _fmu_loop(fresh, vr, 200, plant, 320)
    fresh.freeInstance()
    assert restored == first  # the serialised state carries the settling flag and the integrator


def test_outputs_identical_in_fmpy_libcosim_and_ecos(stos_fmu):
    # Open loop on a recorded trajectory: every host sees the same inputs at the same points.
    slave, vr = initialised(stos_fmu)
    x = v = 0.0
    inputs = []
    for k in range(300):
        inputs.append({"target": TARGET, "x_r": x, "x_r_dot": v})
        slave.setReal([vr["target"], vr["x_r"], vr["x_r_dot"]], [TARGET, x, v])
        x, v = _plant_step(x, v, slave.getReal([vr["u"]])[0])
        slave.doStep(k * TS, TS)
    slave.freeInstance()
    reference = run_fmpy(stos_fmu, inputs, TS, ["u"])
    for other in (run_libcosim(stos_fmu, inputs, TS, ["u"]), run_ecos(stos_fmu, inputs, TS, ["u"])):
        np.testing.assert_allclose(other, reference, rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    ("starts", "words"),
    [
        ({"zeta[1]": 1.0}, "zeta[1] must be in [0, 1)"),
        ({"f[2]": -3000.0}, "f[2] must be > 0"),
        ({"U": 0.0}, "U must be > 0"),
        ({"kind": "zvdx"}, "kind must be one of"),
        ({"kind": "um_zv"}, "must be > 0 (STOS needs a positive shaper)"),
        ({"settle": True, **SETTLE, "x_exit": 1e-7}, "settle['x_exit'] must be >= settle['x_enter']"),
    ],
)
def test_bad_parameters_fail_initialisation_with_a_logged_error(stos_fmu, capfd, starts, words):
    assert refused_initialisation(stos_fmu, starts).status == 3  # fmi2Error
    assert words in capfd.readouterr().out


def test_nan_measurement_fails_the_step_and_leaves_the_law_untouched(stos_fmu):
    slave, vr = initialised(stos_fmu)
    controls, plant = _fmu_loop(slave, vr, 50)
    slave.setReal([vr["x_r"]], [float("nan")])
    with pytest.raises(FMICallException) as failure:
        slave.doStep(50 * TS, TS)
    assert failure.value.status == 3
    rest, _ = _fmu_loop(slave, vr, 150, plant, 50)
    slave.freeInstance()
    assert controls + rest == _kernel_loop(200)[0]
