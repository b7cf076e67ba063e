"""The STOSController FMU in closed loop with a rigid body, against the runtime STOS kernel called directly."""

import math
import zipfile
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from support.fmpy_slaves import initialised, refused_initialisation
from support.hosts import run_ecos, run_fmpy, run_libcosim
from support.scenarios import B, SETTLE, TARGET, TS, U, plant_step, recorded_measurements, stos_loop

from shapefmu.runtime import shaper_designs
from shapefmu.runtime.stos import STOSKernel, stos_curves

MODES = [(2 * math.pi * 2000.0, 0.01), (2 * math.pi * 3000.0, 0.01)]


def _kernel_loop(count, settle=None):
    times, amplitudes = shaper_designs.design_impulses("simultaneous", MODES)
    kernel = STOSKernel(stos_curves(B, U, times, amplitudes), None if settle is None else settle | {"Ts": TS})
    x = v = 0.0
    controls = []
    for _ in range(count):
        u = kernel.control(TARGET, x, v)
        controls.append(u)
        x, v = plant_step(x, v, u)
    return controls, kernel


def test_model_description_passes_fmpy_validation(stos_fmu):
    assert validate_fmu(str(stos_fmu)) == []


def test_u_feeds_through_from_target_and_the_measured_state(stos_fmu):
    root = ET.fromstring(zipfile.ZipFile(stos_fmu).read("modelDescription.xml"))
    names = [v.get("name") for v in root.iter("ScalarVariable")]
    (output,) = root.find("ModelStructure/Outputs")
    assert sorted(names[int(i) - 1] for i in output.get("dependencies").split()) == ["target", "x_r", "x_r_dot"]


def test_closed_loop_controls_equal_the_runtime_kernel_called_directly(stos_fmu):
    slave, vr = initialised(stos_fmu)
    controls, (x, _) = stos_loop(slave, vr, 400)
    slave.freeInstance()
    expected, _ = _kernel_loop(400)
    assert controls == expected  # bit for bit
    assert max(map(abs, controls)) == pytest.approx(U, rel=1e-12)  # it bangs at the limit
    assert abs(x - TARGET) < 1e-2 * TARGET  # and arrives


def test_settle_hand_over_and_its_integrator_equal_the_kernel_and_survive_a_state_restore(stos_fmu):
    starts = {"settle": True, **SETTLE}
    slave, vr = initialised(stos_fmu, starts)
    controls, plant = stos_loop(slave, vr, 320)
    state = slave.getFMUState()
    first, _ = stos_loop(slave, vr, 200, plant, 320)
    slave.setFMUState(state)
    again, _ = stos_loop(slave, vr, 200, plant, 320)
    slave.setFMUState(state)
    raw = slave.serializeFMUState(state)
    slave.freeInstance()
    expected, kernel = _kernel_loop(520, SETTLE)
    assert kernel.get_state()[0] == 1.0  # the linear law is in charge by the end
    assert controls + first == expected
    assert again == first
    fresh, vr = initialised(stos_fmu, starts)
    fresh.setFMUState(fresh.deserializeFMUState(raw))
    restored, _ = stos_loop(fresh, vr, 200, plant, 320)
    fresh.freeInstance()
    assert restored == first  # the serialised state carries the settling flag and the integrator


def test_outputs_identical_in_fmpy_libcosim_and_ecos(stos_fmu):
    # Open loop on a recorded trajectory: every host sees the same inputs at the same points.
    inputs = recorded_measurements(stos_fmu, 300)
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
    controls, plant = stos_loop(slave, vr, 50)
    slave.setReal([vr["x_r"]], [float("nan")])
    with pytest.raises(FMICallException) as failure:
        slave.doStep(50 * TS, TS)
    assert failure.value.status == 3
    rest, _ = stos_loop(slave, vr, 150, plant, 50)
    slave.freeInstance()
    assert controls + rest == _kernel_loop(200)[0]
