"""The standard-library simultaneous shaper (runtime.multimode) against the scipy design layer."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shapefmu.analysis import residual_vibration
from shapefmu.runtime import impulse_formulas
from shapefmu.runtime.least_squares import solve_least_squares
from shapefmu.runtime.multimode import simultaneous
from shapefmu.shapers import ImpulseShaper
from shapefmu.shapers import simultaneous as scipy_simultaneous

DISK_DRIVE = [(2 * math.pi * 2000.0, 0.01), (2 * math.pi * 3000.0, 0.01)]
THREE_MODES = [(10.0, 0.02), (27.0, 0.05), (41.0, 0.01)]


def assert_same_shaper(modes):
    times, amplitudes = simultaneous(modes)
    reference = scipy_simultaneous(modes)
    assert len(times) == len(reference.times) == len(modes) + 1
    # Times relative to the shaper's length (they scale with 1/omega), amplitudes absolute.
    np.testing.assert_allclose(times, reference.times, rtol=0, atol=1e-10 * reference.duration)
    np.testing.assert_allclose(amplitudes, reference.amplitudes, rtol=0, atol=1e-10)


def test_disk_drive_matches_the_scipy_design_layer():
    assert_same_shaper(DISK_DRIVE)


def test_three_modes_match_the_scipy_design_layer():
    assert_same_shaper(THREE_MODES)


@settings(max_examples=12, deadline=None)
@given(
    omega=st.floats(0.5, 2000.0),
    ratio=st.floats(1.1, 5.0),
    zeta_1=st.floats(0.0, 0.3),
    zeta_2=st.floats(0.0, 0.3),
)
def test_random_two_mode_cases_match_the_scipy_design_layer(omega, ratio, zeta_1, zeta_2):
    assert_same_shaper([(omega, zeta_1), (omega * ratio, zeta_2)])


def test_disk_drive_shaper_leaves_no_vibration_at_either_mode():
    shaper = ImpulseShaper(*map(tuple, simultaneous(DISK_DRIVE)))
    for omega, zeta in DISK_DRIVE:
        assert residual_vibration(shaper, omega, zeta) < 1e-12


def test_one_mode_gives_the_closed_form_zv_shaper():
    times, amplitudes = simultaneous([(5.0, 0.1)])
    zv_times, zv_amplitudes = impulse_formulas.zv_dn(5.0, 0.1, 0)
    np.testing.assert_allclose(times, zv_times, rtol=1e-13, atol=0)
    np.testing.assert_allclose(amplitudes, zv_amplitudes, rtol=1e-13, atol=0)


def test_modes_may_be_given_in_any_order():
    assert simultaneous(DISK_DRIVE[::-1]) == simultaneous(DISK_DRIVE)


@pytest.mark.parametrize(
    ("modes", "message"),
    [
        ([], "modes must hold at least 1"),
        ([(1.0, 0.0), (1.0, 0.1)], "modes must have distinct frequencies"),
        ([(1.0, 0.0), (-2.0, 0.0)], r"modes\[1\] omega must be > 0, got -2.0"),
        ([(1.0, 1.2)], r"modes\[0\] zeta must be in \[0, 1\), got 1.2"),
        ([(1.0, float("nan"))], r"modes\[0\] zeta must be a finite real number"),
        ([(1.0,)], r"modes\[0\] must be an \(omega, zeta\) pair"),
        (5.0, "modes must be a sequence of"),
    ],
)
def test_bad_modes_are_refused_naming_the_entry(modes, message):
    with pytest.raises(ValueError, match=message):
        simultaneous(modes)


def test_modes_too_close_for_positive_impulses_are_refused_like_the_design_layer():
    close = [(1.0, 0.0), (1.00001, 0.0)]
    with pytest.raises(ValueError, match="no simultaneous shaper"):
        scipy_simultaneous(close)
    with pytest.raises(ValueError, match="no simultaneous shaper with 3 positive impulses"):
        simultaneous(close)


def test_least_squares_matches_numpy_on_an_overdetermined_system():
    rng = np.random.default_rng(7)
    a = rng.normal(size=(9, 5))
    b = rng.normal(size=9)
    x = solve_least_squares(a.tolist(), b.tolist())
    np.testing.assert_allclose(x, np.linalg.lstsq(a, b, rcond=None)[0], rtol=1e-12, atol=1e-13)


def test_least_squares_reports_a_rank_deficient_matrix():
    assert solve_least_squares([[1.0, 2.0], [2.0, 4.0], [3.0, 6.0]], [1.0, 2.0, 3.0]) is None
