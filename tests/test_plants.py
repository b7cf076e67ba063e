"""Plant models: the papers' plants, the model files in models/, conversions and modes."""

import glob
import math
from pathlib import Path

import control
import numpy as np
import pytest
from scipy.linalg import eigh

from shapefmu.plants import (
    Plant,
    as_plant,
    describe,
    disk_drive,
    linear_synchronous_motor,
    load,
    loads,
    mass_spring_chain,
    ten_pendula,
)

MODELS = Path(__file__).resolve().parent.parent / "models"
MODEL_FILES = sorted(glob.glob(str(MODELS / "*.toml")))

# Paper 002, Table I and Sec. IV.
B2 = 2.7e3
OMEGAS = (2 * math.pi * 2.0e3, 2 * math.pi * 3.0e3)
ZETA = 0.01


def test_disk_drive_matrices_are_eq1_with_table1_values():
    w1, w2 = OMEGAS
    A = np.array([
        [0, 1, 0, 0, 0, 0],
        [0, 0, 0, 0, 0, 0],
        [0, 0, 0, 1, 0, 0],
        [0, 0, -w1**2, -2 * ZETA * w1, 0, 0],
        [0, 0, 0, 0, 0, 1],
        [0, 0, 0, 0, -w2**2, -2 * ZETA * w2],
    ])
    B = np.array([[0], [B2], [0], [-B2], [0], [-B2]])
    plant = disk_drive()
    np.testing.assert_array_equal(plant.A, A)
    np.testing.assert_array_equal(plant.B, B)
    assert plant.limits["voltage"] == 11.0


def test_disk_drive_file_is_the_library_disk_drive():
    plant = load(MODELS / "disk_drive.toml")
    np.testing.assert_allclose(plant.A, disk_drive().A, rtol=1e-15)
    np.testing.assert_array_equal(plant.B, disk_drive().B)
    assert plant.limits == {"voltage": 11.0}


def test_back_emf_damps_rigid_body_by_kt_squared_over_r_j():
    plant = load(MODELS / "disk_drive_back_emf.toml")
    assert plant.A[1, 1] == pytest.approx(-(9.8e-2**2) / (7.25 * 5e-6), rel=1e-14)
    np.testing.assert_allclose(plant.A, disk_drive(back_emf=True).A, rtol=1e-15)


def test_disk_drive_modes_are_2_and_3_khz_with_zeta_001():
    modes = [m for m in load(MODELS / "disk_drive.toml").modes() if m.oscillatory]
    assert [m.hz for m in modes] == pytest.approx([2.0e3, 3.0e3], rel=1e-12)
    assert [m.zeta for m in modes] == pytest.approx([ZETA, ZETA], rel=1e-10)


def test_rigid_body_modes_are_reported_at_the_origin():
    rigid = [m for m in disk_drive().modes() if not m.oscillatory]
    assert len(rigid) == 2 and all(m.omega == 0.0 and m.participation == math.inf for m in rigid)


def test_mode_participation_is_the_modal_static_gain():
    # Mode i of eq. (1) is b4i / (s^2 + 2 zeta w s + w^2) on its deflection output; its residues
    # +-b4i / (2 j w_d) give 2 |r| / |p| = |b4i| / (w w_d).
    modes = [m for m in disk_drive().modes() if m.oscillatory]
    expected = [B2 / (w * w * math.sqrt(1 - ZETA**2)) for w in OMEGAS]
    assert [m.participation for m in modes] == pytest.approx(expected, rel=1e-12)


def test_flexible_modes_feed_the_shaper_designs():
    modes = disk_drive().flexible_modes()
    assert [w for w, _ in modes] == pytest.approx(OMEGAS, rel=1e-12)
    assert [z for _, z in modes] == pytest.approx([ZETA, ZETA], rel=1e-10)


@pytest.mark.parametrize("path", MODEL_FILES, ids=lambda p: Path(p).stem)
def test_round_trip_through_python_control_keeps_modes(path):
    plant = load(path)
    again = Plant.from_lti(plant.to_statespace())
    for a, b in zip(plant.modes(), again.modes(), strict=True):
        assert b.omega == pytest.approx(a.omega, rel=1e-12, abs=1e-12)
        assert (math.isnan(a.zeta) and math.isnan(b.zeta)) or b.zeta == pytest.approx(a.zeta, rel=1e-12, abs=1e-12)


def test_round_trip_through_transfer_function_keeps_lsm_modes():
    plant = load(MODELS / "linear_synchronous_motor.toml")
    again = as_plant(plant.to_transfer_function())
    for a, b in zip(plant.modes(), again.modes(), strict=True):
        assert b.omega == pytest.approx(a.omega, rel=1e-12)
        assert b.zeta == pytest.approx(a.zeta, rel=1e-12)


def test_lsm_frequency_response_is_eq33():
    num = [0.003346, 0.0108, -885.1, -1.224e5, 9.687e7]
    den = [1.0, 76.17, 4.944e4, 2.822e6, 1.016e8]
    plant = load(MODELS / "linear_synchronous_motor.toml")
    for s in (1j * 10.0, 1j * 215.0, 3.0 + 1j * 100.0):
        expected = np.polyval(num, s) / np.polyval(den, s)
        got = (plant.C @ np.linalg.solve(s * np.eye(4) - plant.A, plant.B) + plant.D)[0, 0]
        assert got == pytest.approx(expected, rel=1e-12)
    np.testing.assert_allclose(plant.A, linear_synchronous_motor().A)


def test_ten_pendula_span_the_papers_frequency_range():
    # Paper 003, Sec. V: masses 28.8 in to 34.2 in below the cart, 3.36 to 3.66 rad/s.
    omegas = [m.omega for m in ten_pendula().modes() if m.oscillatory]
    assert len(omegas) == 10
    assert omegas[0] == pytest.approx(math.sqrt(9.80665 / (34.2 * 0.0254)), rel=1e-12)
    assert omegas[-1] == pytest.approx(math.sqrt(9.80665 / (28.8 * 0.0254)), rel=1e-12)
    assert round(omegas[0], 2) == 3.36 and round(omegas[-1], 2) == 3.66


def test_ten_pendula_file_has_ten_angle_outputs_and_cart_acceleration_input():
    plant = load(MODELS / "ten_pendula.toml")
    assert plant.inputs == ("acceleration",)
    assert plant.outputs[1:] == tuple(f"theta_{i}" for i in range(1, 11))
    np.testing.assert_allclose(plant.A, ten_pendula().A, rtol=1e-15)


def test_mass_spring_chain_frequencies_solve_the_generalised_eigenproblem():
    masses, springs = [1.0, 0.5, 0.25], [400.0, 300.0]
    K = np.array([[400.0, -400.0, 0.0], [-400.0, 700.0, -300.0], [0.0, -300.0, 300.0]])
    expected = np.sqrt(np.clip(eigh(K, np.diag(masses), eigvals_only=True), 0.0, None))
    got = sorted(m.omega for m in mass_spring_chain(masses, springs).modes() if m.oscillatory)
    assert got == pytest.approx(expected[1:], rel=1e-12)


def test_python_control_transfer_function_is_accepted_as_a_plant():
    plant = as_plant(control.tf([4.0], [1.0, 0.4, 4.0]))
    (mode,) = plant.modes()
    assert (mode.omega, mode.zeta) == pytest.approx((2.0, 0.1), rel=1e-12)


def test_plant_show_lists_the_modes():
    text = describe(MODELS / "disk_drive.toml")
    assert "2000" in text and "3000" in text and "0.01" in text


GOOD = """
kind = "rigid_flexible"
[parameters]
b2 = { value = 2.7e3, unit = "1/(V*s^2)" }
f = { value = [2.0e3], unit = "Hz" }
zeta = { value = [0.01], unit = "1" }
b4 = { value = [-2.7e3], unit = "1/(V*s^2)" }
[inputs]
voltage = { unit = "V", max = 11.0 }
[outputs]
position = { unit = "rad" }
deflection_1 = { unit = "rad" }
"""


def test_good_model_text_loads():
    ((omega, zeta),) = loads(GOOD, "good.toml").flexible_modes()
    assert (omega, zeta) == pytest.approx((OMEGAS[0], ZETA), rel=1e-10)


@pytest.mark.parametrize(
    "old, new, field, problem",
    [
        ("b2 = {", "bb2 = {", "bb2", "unknown parameter"),
        ('unit = "Hz"', 'units = "Hz"', "parameters.f", "unknown field"),
        (', unit = "1" }', " }", "parameters.zeta.unit", "missing"),
        ("[-2.7e3]", "[nan]", "parameters.b4.value[0]", "finite"),
        ("value = 2.7e3", "value = inf", "parameters.b2.value", "finite"),
        ('unit = "Hz"', 'unit = "kHz"', "parameters.f.unit", "must be one of"),
        ("max = 11.0", "max = 0.0", "inputs.voltage.max", "> 0"),
        ('voltage = { unit = "V", max = 11.0 }', "voltage = { max = 11.0 }", "inputs.voltage.unit", "missing"),
    ],
)
def test_bad_model_file_names_file_field_and_problem(old, new, field, problem):
    assert old in GOOD
    with pytest.raises(ValueError) as error:
        loads(GOOD.replace(old, new), "bad.toml")
    message = str(error.value)
    assert "bad.toml" in message and field in message and problem in message


def test_missing_model_file_names_the_path(tmp_path):
    with pytest.raises(ValueError, match="nothing.toml"):
        load(tmp_path / "nothing.toml")
