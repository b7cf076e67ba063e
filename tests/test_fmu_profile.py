"""The ProfileGenerator FMU against the runtime profile kernels called directly (and so the design layer)."""

import math
import zipfile
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from fmpy.validation import validate_fmu

from support.fixtures_fmi import PROFILE_STARTS
from support.fmpy_slaves import instantiated, refused_initialisation, variable_references
from support.hosts import run_ecos, run_fmpy, run_libcosim

from shapefmu.runtime import shaped_bang_bang, shaper_designs, time_frequency, twin_pulse

OUTPUTS = ["position", "velocity", "acceleration"]
DISK_DRIVE = {"profile": "bang-bang", "distance": 0.05, "speed": 0.0, "acceleration_limit": 11.0 * 2.7e3, "shaper": "simultaneous",
              "n_modes": 2, "omega[1]": 2 * math.pi * 2000.0, "zeta[1]": 0.01, "omega[2]": 2 * math.pi * 3000.0,
              "zeta[2]": 0.01}


def _expected(motion, ends, start=0.0):
    return [list(motion.state(t - start)) if t >= start else [0.0, 0.0, 0.0] for t in ends]


def assert_equal_per_column(rows, expected, relative):
    # Each output to ``relative`` times its own peak (position, velocity, acceleration differ in scale).
    scale = np.max(np.abs(expected), axis=0)
    assert np.all(np.abs(np.asarray(rows) - expected) <= relative * scale)


def test_model_description_passes_fmpy_validation(profile_fmu):
    assert validate_fmu(str(profile_fmu)) == []


def test_only_the_acceleration_feeds_through_from_start(profile_fmu):
    root = ET.fromstring(zipfile.ZipFile(profile_fmu).read("modelDescription.xml"))
    names = [v.get("name") for v in root.iter("ScalarVariable")]
    dependencies = {names[int(o.get("index")) - 1]: o.get("dependencies") for o in root.find("ModelStructure/Outputs")}
    assert dependencies == {"position": "", "velocity": "", "acceleration": str(names.index("start") + 1)}


def test_twin_pulse_outputs_equal_the_runtime_profile(profile_fmu):
    p = PROFILE_STARTS
    design = twin_pulse.twin_pulse_profile(p["profile"], p["omega_n"], p["distance"], p["speed"],
                                           attenuation=p["attenuation"], ts=p["Ts"])
    h = 0.0137  # not a divisor of the profile's switch times
    count = math.ceil(1.1 * design.duration / h)
    rows = run_fmpy(profile_fmu, [{}] * count, h, OUTPUTS)
    np.testing.assert_allclose(rows, _expected(design.motion, [(k + 1) * h for k in range(count)]), rtol=0, atol=1e-12)


def test_shaped_bang_bang_outputs_equal_the_runtime_move(profile_fmu):
    times, amplitudes = shaper_designs.design_impulses("simultaneous", [(2 * math.pi * 2000.0, 0.01),
                                                                        (2 * math.pi * 3000.0, 0.01)])
    motion = shaped_bang_bang.shaped_bang_bang(0.05, 11.0 * 2.7e3, times, amplitudes)
    h = 2.3e-5
    count = math.ceil(1.1 * motion.breaks[-1] / h)
    rows = run_fmpy(profile_fmu, [{}] * count, h, OUTPUTS, start_values=DISK_DRIVE)
    expected = np.array(_expected(motion, [(k + 1) * h for k in range(count)]))
    assert_equal_per_column(rows, expected, 1e-12)


def test_time_frequency_outputs_equal_the_runtime_profile_with_its_optimal_scale(profile_fmu):
    starts = {"profile": "time-frequency", "omega_n": 9.68e3, "Ts": 2e-5, "move_time": 2.5e-3, "distance": 1e-3}
    design = time_frequency.time_frequency_profile(9.68e3, 2e-5, 2.5e-3, 1e-3)
    h = 2e-5
    rows = run_fmpy(profile_fmu, [{}] * 140, h, OUTPUTS, start_values=starts)
    expected = np.array(_expected(design.motion, [(k + 1) * h for k in range(140)]))
    assert_equal_per_column(rows, expected, 1e-12)


def test_start_input_starts_the_move_at_that_communication_point(profile_fmu):
    design = twin_pulse.twin_pulse_profile("M-BC:TZ:TP", 3.5, 1.7, 0.7, attenuation=0.05, ts=1e-3)
    vr = variable_references(profile_fmu)
    slave = instantiated(profile_fmu)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setReal([vr["t_start"]], [-1.0])
    slave.exitInitializationMode()
    h, rows, ends = 0.05, [], []
    for k in range(10):
        slave.doStep(k * h, h)
    assert slave.getReal([vr[n] for n in OUTPUTS]) == [0.0, 0.0, 0.0]
    slave.setReal([vr["start"]], [1.0])
    # Feed-through: the acceleration jumps to its first level as soon as start is set.
    assert slave.getReal([vr["acceleration"]]) == [design.motion.state(0.0)[2]]
    for k in range(10, 60):
        slave.doStep(k * h, h)
        rows.append(slave.getReal([vr[n] for n in OUTPUTS]))
        ends.append((k + 1) * h)
    slave.freeInstance()
    np.testing.assert_allclose(rows, _expected(design.motion, ends, start=10 * h), rtol=0, atol=1e-12)


def test_outputs_identical_in_fmpy_libcosim_and_ecos(profile_fmu):
    h = 0.01
    inputs = [{"start": 0.0}] * 5 + [{"start": 1.0}] * 120
    reference = run_fmpy(profile_fmu, inputs, h, OUTPUTS)
    assert max(abs(row[0]) for row in reference) > 0.0  # the move ran
    for other in (run_libcosim(profile_fmu, inputs, h, OUTPUTS), run_ecos(profile_fmu, inputs, h, OUTPUTS)):
        np.testing.assert_allclose(other, reference, rtol=0, atol=1e-12)


def test_state_restores_the_started_move_in_a_fresh_instance(profile_fmu):
    vr = variable_references(profile_fmu)
    outputs = [vr[n] for n in OUTPUTS]

    def fresh():
        slave = instantiated(profile_fmu)
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.setReal([vr["t_start"]], [-1.0])
        slave.exitInitializationMode()
        return slave

    slave = fresh()
    for k in range(30):
        slave.setReal([vr["start"]], [1.0 if k >= 7 else 0.0])
        slave.doStep(k * 0.02, 0.02)
    raw = slave.serializeFMUState(slave.getFMUState())
    expected = []
    for k in range(30, 90):
        slave.doStep(k * 0.02, 0.02)
        expected.append(slave.getReal(outputs))
    slave.freeInstance()
    other = fresh()
    other.setFMUState(other.deserializeFMUState(raw))
    got = []
    for k in range(30, 90):
        other.doStep(k * 0.02, 0.02)
        got.append(other.getReal(outputs))
    other.freeInstance()
    assert got == expected


@pytest.mark.parametrize(
    ("starts", "words"),
    [
        ({"profile": "S-curve"}, "profile must be one of"),
        ({"profile": "time-frequency", "omega_n": 9.68e3, "Ts": 2e-5, "move_time": 2.51e-3 + 1e-6},
         "move_time / ts must be an integer"),
        ({"profile": "bang-bang", "shaper": "zv", "zeta[1]": 1.0}, "zeta[1] must be in [0, 1)"),
        ({"omega_n": -3.5}, "omega_n must be > 0"),
        ({"distance": float("nan")}, "distance must be a finite real number"),
    ],
)
def test_bad_parameters_fail_initialisation_with_a_logged_error(profile_fmu, capfd, starts, words):
    assert refused_initialisation(profile_fmu, starts).status == 3  # fmi2Error
    assert words in capfd.readouterr().out
