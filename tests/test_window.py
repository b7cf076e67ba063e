"""Window-function shape filters (paper 000): nulls, robustness, sampling-period rules, profiles."""

import math

import numpy as np
import pytest

from shapefmu.analysis import insensitivity, residual_vibration, spectrum
from shapefmu.shapers.impulse import zv
from shapefmu.shapers.profile import velocity_profile
from shapefmu.shapers.window import (
    blackman_filter,
    convolved_filter,
    differenced_filter,
    hamming_filter,
    hamming_null_depth,
    hanning_filter,
    rectangle_filter,
    three_hanning_filter,
)


def paper_ts(zeta, omega=1.0):
    """The sampling period of paper 000's figures, Ts = pi / (100 omega_d)."""
    return math.pi / (100.0 * omega * math.sqrt(1.0 - zeta * zeta))


def test_hanning_at_paper_sampling_period_has_m_400():
    assert hanning_filter(1.0, 0.0, paper_ts(0.0)).taps.size == 400 + 1


def test_blackman_at_paper_sampling_period_has_m_600():
    assert blackman_filter(1.0, 0.0, paper_ts(0.0)).taps.size == 600 + 1


@pytest.mark.parametrize("design", [hanning_filter, blackman_filter])
@pytest.mark.parametrize("zeta", [0.0, 0.05, 0.2])
@pytest.mark.parametrize("order", [1, 2, 3])
def test_residual_vibration_vanishes_at_design_point(design, zeta, order):
    shaper = design(1.0, zeta, paper_ts(zeta), order)
    assert residual_vibration(shaper, 1.0, zeta) < 1e-9
    assert shaper.gain == pytest.approx(1.0, abs=1e-12)


def test_three_hanning_residual_vanishes_at_design_point():
    zeta = 0.2
    shaper = three_hanning_filter(1.0, zeta, paper_ts(zeta), c=0.25, adjust_ts=True)
    assert residual_vibration(shaper, 1.0, zeta) < 1e-9


def test_three_hanning_length_follows_eq6():
    c, zeta = 0.25, 0.2
    shaper = three_hanning_filter(1.0, zeta, paper_ts(zeta), c=c, adjust_ts=True)
    y = math.cos(math.sqrt(1.0 - zeta * zeta) * shaper.ts)
    b = c**2 * y**2 + 2 * c**2 * y + c**2 + 2 * c + 6 * c * y + 2 + 2 * y
    m = math.pi / math.acos((c * y - c + math.sqrt(b)) / (2 * c + 2))  # eq. (6) as printed
    assert shaper.taps.size == 2 * round(m) + 1
    assert m == pytest.approx(round(m), abs=1e-6)


def test_differenced_base_with_paper_weights_vanishes_at_design_point():
    zeta = 0.1
    shaper = differenced_filter(1.0, zeta, paper_ts(zeta), k1=1.0, k2=-25.0)
    assert residual_vibration(shaper, 1.0, zeta) < 1e-9


def test_convolved_base_with_paper_weights_vanishes_at_design_point():
    zeta = 0.1
    shaper = convolved_filter(1.0, zeta, paper_ts(zeta), k1=1.0, k2=1.0 / 125.0)
    assert residual_vibration(shaper, 1.0, zeta) < 1e-9


@pytest.mark.parametrize("design", [differenced_filter, convolved_filter])
def test_section8_bases_are_not_symmetric(design):
    h = design(1.0, 0.0, paper_ts(0.0)).taps
    assert np.max(np.abs(h - h[::-1])) > 0.1 * np.max(h)


def test_rectangle_sampled_at_half_damped_period_is_the_zv_shaper():
    zeta = 0.1
    shaper = rectangle_filter(2.0, zeta, math.pi / (2.0 * math.sqrt(1.0 - zeta**2)))
    np.testing.assert_allclose(shaper.taps, zv(2.0, zeta).amplitudes, rtol=1e-12)


def test_hamming_residual_equals_its_end_sample_closed_form():
    # h[M] = 2/23 is all that survives at 4 pi / M; H(0) = (25 M + 4) / 46, M = 400.
    shaper = hamming_filter(1.0, 0.0, paper_ts(0.0))
    assert residual_vibration(shaper, 1.0, 0.0) == pytest.approx(4.0 / (25 * 400 + 4), rel=1e-9)
    assert hamming_null_depth(1.0, 0.0, paper_ts(0.0)) == pytest.approx(4.0 / (25 * 400 + 4), rel=1e-9)


def test_order_n_spectrum_is_order_one_spectrum_to_the_n():
    ts = paper_ts(0.05)
    omega = np.linspace(0.1, 3.0, 7)
    one = spectrum(hanning_filter(1.0, 0.05, ts, 1), omega)
    three = spectrum(hanning_filter(1.0, 0.05, ts, 3), omega)
    np.testing.assert_allclose(three, one**3, rtol=1e-9, atol=1e-15)


def test_hanning_band_below_5_percent_is_wider_than_rectangle_band():
    zeta = 0.05
    ts = paper_ts(zeta)
    hanning = insensitivity(hanning_filter(1.0, zeta, ts), 1.0, zeta, 0.05)
    rectangle = insensitivity(rectangle_filter(1.0, zeta, ts), 1.0, zeta, 0.05)
    assert hanning.width > rectangle.width


def test_hanning_residual_above_q3_is_lower_than_rectangle():
    zeta = 0.05
    ts = paper_ts(zeta)
    q = np.linspace(3.0, 10.0, 1401)
    hanning = residual_vibration(hanning_filter(1.0, zeta, ts), q, zeta)
    rectangle = residual_vibration(rectangle_filter(1.0, zeta, ts), q, zeta)
    assert hanning.max() < rectangle.max()


def test_non_integer_m_raises_naming_valid_sampling_periods():
    with pytest.raises(ValueError, match=r"ts = 0\.0314 .*M = 400\)"):
        hanning_filter(1.0, 0.0, 0.0314)


def test_adjust_ts_uses_nearest_period_with_integer_m():
    shaper = hanning_filter(1.0, 0.0, 0.0314, adjust_ts=True)
    assert shaper.ts == pytest.approx(4.0 * math.pi / 400, rel=1e-15)
    assert residual_vibration(shaper, 1.0, 0.0) < 1e-9


def test_order_below_one_raises():
    with pytest.raises(ValueError, match="order must be an integer >= 1"):
        hanning_filter(1.0, 0.0, paper_ts(0.0), order=0)


def test_hanning_velocity_profile_reaches_distance_from_rest_to_rest():
    zeta = 0.2
    profile = velocity_profile(hanning_filter(1.0, zeta, paper_ts(zeta)), distance=2.5)
    peak = np.max(np.abs(profile.velocity))
    assert profile.velocity[0] == 0.0
    assert abs(profile.velocity[-1]) <= 1e-12 * peak
    assert profile.position[-1] == pytest.approx(2.5, rel=1e-9)
    assert abs(np.sum(profile.acceleration) * profile.ts) <= 1e-12 * peak


def test_blackman_velocity_profile_trapezoid_area_is_distance():
    # Second method: the trapezoid rule on the velocity samples is exact for a held acceleration.
    profile = velocity_profile(blackman_filter(1.0, 0.0, paper_ts(0.0), order=2), distance=0.7)
    assert np.trapezoid(profile.velocity, profile.t) == pytest.approx(0.7, rel=1e-9)


def test_rectangle_is_refused_as_velocity_profile():
    with pytest.raises(ValueError, match="first and last taps are 0"):
        velocity_profile(rectangle_filter(1.0, 0.0, paper_ts(0.0)), distance=1.0)
