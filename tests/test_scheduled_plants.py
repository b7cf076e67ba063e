"""Plants whose modes move (issue 37): the scheduling input of models/*.toml, the modes along it from the
model's eigenvalues against closed forms, and the loader's checks of the [scheduling] table."""

import math
from pathlib import Path

import numpy as np
import pytest

from shapefmu.plants import describe, load, load_scheduled, loads, loads_scheduled, pendula, sprung_masses
from shapefmu.plants.simulation import run_loop, zero_order_hold

MODELS = Path(__file__).resolve().parent.parent / "models"
G = 9.80665

BED = """
name = "bed"
kind = "sprung_masses"
[parameters]
masses = { value = [1.0], unit = "kg" }
stiffnesses = { value = [35530.57584392168], unit = "N/m" }
dampers = { value = [18.84955592153876], unit = "N*s/m" }
[inputs]
acceleration = { unit = "m/s^2" }
[outputs]
carriage_position = { unit = "m" }
bed_deflection = { unit = "m" }
bed_acceleration = { unit = "m/s^2" }
[scheduling]
name = "added_mass"
unit = "g"
min = 0.0
max = 300.0
per_unit = { masses = [0.001] }
"""


def test_bed_mode_is_sqrt_k_over_m_at_every_added_mass():
    bed = load_scheduled("printer_bed")
    k, c = bed.plant.parameters["stiffnesses"].value[0], bed.plant.parameters["dampers"].value[0]
    for grams in (0.0, 37.5, 150.0, 300.0):
        m = 1.0 + grams / 1000.0
        ((omega, zeta),) = bed.flexible_modes_at(grams)
        assert omega == pytest.approx(math.sqrt(k / m), rel=1e-12)
        assert zeta == pytest.approx(c / (2.0 * math.sqrt(k * m)), rel=1e-10)


def test_bed_of_the_issue_goes_from_30_to_26_3_hz():
    curve = load_scheduled("printer_bed").mode_curve([0.0, 300.0])
    assert curve.frequencies[0] == pytest.approx(30.0, rel=1e-12)
    assert curve.frequencies[1] == pytest.approx(30.0 / math.sqrt(1.3), rel=1e-12)  # 26.31 Hz, Marlin #26655
    assert round(curve.frequencies[1], 1) == 26.3


def test_crane_mode_is_sqrt_g_over_rope_length():
    crane = load_scheduled(MODELS / "gantry_crane.toml")
    for length in (0.5, 1.0, 1.37, 2.0):
        ((omega, zeta),) = crane.flexible_modes_at(length)
        assert omega == pytest.approx(math.sqrt(G / length), rel=1e-12)
        assert zeta == pytest.approx(0.01, rel=1e-10)


def test_plant_at_a_value_is_the_library_plant_of_those_parameters():
    bed = load_scheduled("printer_bed")
    expected = sprung_masses([1.2], bed.plant.parameters["stiffnesses"].value, bed.plant.parameters["dampers"].value)
    np.testing.assert_allclose(bed.at(200.0).A, expected.A, rtol=1e-15)
    crane = load_scheduled("gantry_crane").at(1.5)
    np.testing.assert_allclose(crane.A, pendula([1.5], zeta=0.01).A, rtol=1e-15)
    assert crane.outputs == ("trolley_position", "swing_angle")


def test_load_reads_a_scheduled_model_as_the_plant_at_its_start_value():
    plant = load("gantry_crane")
    assert plant.parameters["lengths"].value == (1.0,)
    np.testing.assert_array_equal(plant.A, load_scheduled("gantry_crane").at(1.0).A)


def test_bed_acceleration_output_is_what_an_accelerometer_reads():
    """A held carriage acceleration a: once the ring has died the bed moves with the carriage, so the
    bed's accelerometer reads a (its static gain is 1, whatever the mass)."""
    bed = load_scheduled("printer_bed")
    for grams in (0.0, 300.0):
        plant = bed.at(grams)
        row = plant.outputs.index("bed_acceleration")
        gain = plant.C[row, 2:] @ np.linalg.solve(-plant.A[2:, 2:], plant.B[2:, 0])
        assert gain == pytest.approx(1.0, rel=1e-12)


def test_zero_order_hold_matches_the_closed_form_ring_of_a_held_step():
    """The sample-by-sample run against the closed-form step response of the mode:
    e(t) = -a/omega^2 (1 - exp(-sigma t) (cos(omega_d t) + sigma/omega_d sin(omega_d t)))."""
    bed = load_scheduled("printer_bed")
    ts, a = 5e-4, 3.0
    run = run_loop(bed, np.full(400, a), 300.0, ts)
    ((omega, zeta),) = bed.flexible_modes_at(300.0)
    sigma, omega_d = zeta * omega, omega * math.sqrt(1.0 - zeta**2)
    t = np.arange(400) * ts
    closed = -a / omega**2 * (1.0 - np.exp(-sigma * t) * (np.cos(omega_d * t) + sigma / omega_d * np.sin(omega_d * t)))
    np.testing.assert_allclose(run.outputs[:, 1], closed, rtol=0, atol=1e-9 * a / omega**2)
    Ad, _ = zero_order_hold(bed.at(300.0), ts)
    assert Ad[0, 1] == pytest.approx(ts, rel=1e-15)  # the carriage integrates: x' = v


def test_describe_shows_the_scheduling_input_and_the_mode_at_its_ends():
    text = describe("printer_bed")
    assert "scheduling input added_mass [g] in [0, 300], start 0" in text
    assert "added_mass = 300" in text and "lowest flexible mode 26.3117 Hz" in text


def test_a_value_outside_the_range_is_refused_naming_the_range():
    with pytest.raises(ValueError, match=r"added_mass must be in \[0, 300\] g, got 301"):
        load_scheduled("printer_bed").at(301.0)


def test_a_model_without_scheduling_is_no_scheduled_plant():
    with pytest.raises(ValueError, match="declares no \\[scheduling\\] table"):
        loads_scheduled(BED.split("[scheduling]")[0], "plain.toml")
    assert loads(BED, "bed.toml").name == "bed"


@pytest.mark.parametrize("old, new, message", [
    ('name = "added_mass"', 'name = "bed_acceleration"', "already a signal of the plant"),
    ('name = "added_mass"', 'name = "added mass"', "must be an identifier"),
    ("max = 300.0", "max = -1.0", "min must be < max"),
    ("per_unit = { masses = [0.001] }", "per_unit = { masses = [0.001, 0.0] }", "list of 1 numbers"),
    ("per_unit = { masses = [0.001] }", "per_unit = { mass = [0.001] }", "no such parameter"),
    ("per_unit = { masses = [0.001] }", "per_unit = {}", "must be a table naming the parameters"),
    ("per_unit = { masses = [0.001] }", "per_unit = { masses = [-0.01] }", "at added_mass = 300: masses\\[0\\] must be > 0"),
    ('unit = "g"', 'unit = "g"\nspeed = 1', "unknown field\\(s\\) \\['speed'\\]"),
])
def test_a_bad_scheduling_table_is_refused_with_one_line(old, new, message):
    with pytest.raises(ValueError, match=message) as error:
        loads(BED.replace(old, new), "bed.toml")
    assert "\n" not in str(error.value) and str(error.value).startswith("bed.toml: ")
