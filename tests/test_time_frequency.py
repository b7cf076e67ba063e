"""Time-frequency localised profile (paper 004): scale optimisation, spectra, rest-to-rest move."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from shapefmu.shapers.time_frequency import (
    energy_leakage,
    optimal_scale,
    phi,
    sampled_phi,
    time_frequency_profile,
    tradeoff_curve,
)

# Paper 004, section IV: hard-disk-drive seek.
OMEGA_0, TS, MOVE = 9.68e3, 2e-5, 2.5e-3


def dtft(g, w):
    k = np.arange(g.size)
    return np.array([np.sum(g * np.exp(-1j * x * k)) for x in np.atleast_1d(w)])


def test_optimal_scale_matches_paper_value():
    n, leakage = optimal_scale(OMEGA_0, TS, MOVE)
    assert n == pytest.approx(11.41, abs=0.05)
    assert leakage < 5e-5


def test_leakage_equals_quadrature_of_the_dtft():
    # Second method: adaptive quadrature of |G(omega)|^2 over [0, omega_0] and [0, pi] (eq. 18-19).
    n = 11.0
    g = sampled_phi(n, TS, MOVE)
    w0 = OMEGA_0 * TS

    def power(w):
        return abs(dtft(g, w)[0]) ** 2

    low = quad(power, 0.0, w0, epsabs=0, epsrel=1e-12, limit=200)[0]
    total = low + quad(power, w0, math.pi, epsabs=0, epsrel=1e-12, limit=200)[0]
    assert energy_leakage(n, OMEGA_0, TS, MOVE) == pytest.approx(1.0 - low / total, rel=1e-6)


def test_tiny_leakage_of_a_long_move_equals_quadrature_of_the_out_of_band_energy():
    # At 5 ms and its optimal n, 1 - J is ~2e-10: adaptive quadrature of |G|^2 over [omega_0, pi]
    # (the numerator of eq. 19) keeps its digits, which one minus the in-band share would not.
    move, n = 5e-3, 10.9278
    g = sampled_phi(n, TS, move)
    w0 = OMEGA_0 * TS
    outside = quad(lambda w: abs(dtft(g, w)[0]) ** 2, w0, math.pi, epsabs=0, epsrel=1e-11, limit=500)[0]
    assert energy_leakage(n, OMEGA_0, TS, move) == pytest.approx(outside / (math.pi * np.sum(g * g)), rel=1e-9)


def test_eq17_odd_m_magnitude_matches_dtft():
    n, m = 11.4, 125  # move 2.5 ms at 20 us: M odd
    g = sampled_phi(n, TS, m * TS)
    w = np.linspace(0.05, 3.0, 9)
    k = np.arange(1, (m + 1) // 2 + 1)
    eq17 = np.abs(2 * np.sum(phi((0.5 - k) * TS, n) * np.sin(np.outer(w, k - 0.5)), axis=1))
    np.testing.assert_allclose(eq17, np.abs(dtft(g, w)), rtol=1e-9, atol=1e-12 * np.abs(g).sum())


def test_eq16_even_m_magnitude_matches_dtft():
    n, m = 11.4, 126
    g = sampled_phi(n, TS, m * TS)
    w = np.linspace(0.05, 3.0, 9)
    k = np.arange(1, m // 2 + 1)
    eq16 = np.abs(2 * np.sum(phi(-k * TS, n) * np.sin(np.outer(w, k)), axis=1))
    np.testing.assert_allclose(eq16, np.abs(dtft(g, w)), rtol=1e-9, atol=1e-12 * np.abs(g).sum())


def test_phi_minimum_is_at_two_to_minus_n():
    n = 3.0
    t = np.linspace(0.0, 1.0, 200001)
    y = phi(t, n)
    assert t[np.argmin(y)] == pytest.approx(2.0**-n, abs=1e-5)
    assert y.min() == pytest.approx(-math.exp(-0.5) / 2.0**n, rel=1e-9)


def test_phi_fourier_transform_matches_eq13():
    n = 1.0
    for w in (0.5, 2.0, 5.0):
        real = quad(lambda t: phi(t, n) * math.cos(w * t), -20, 20, limit=200)[0]
        imag = quad(lambda t: -phi(t, n) * math.sin(w * t), -20, 20, limit=200)[0]
        eq13 = 1j * math.sqrt(2 * math.pi) * w * math.exp(-0.5 * w * w / 2 ** (2 * n)) / 2 ** (3 * n)
        assert complex(real, imag) == pytest.approx(eq13, abs=1e-10)


def test_half_millisecond_move_leaks_about_045_as_in_fig13():
    _, leakage = tradeoff_curve(OMEGA_0, TS, [0.5e-3])
    assert leakage[0] == pytest.approx(0.45, abs=0.01)


def test_leakage_falls_as_move_time_grows():
    _, leakage = tradeoff_curve(OMEGA_0, TS, [0.5e-3, 1e-3, 1.5e-3, 2.5e-3])
    assert np.all(np.diff(leakage) < 0)


def test_profile_is_rest_to_rest_over_the_distance():
    profile = time_frequency_profile(OMEGA_0, TS, MOVE, distance=100.0).profile
    peak_v = np.max(np.abs(profile.velocity))
    peak_a = np.max(np.abs(profile.acceleration))
    assert profile.velocity[0] == 0.0
    assert abs(profile.velocity[-1]) <= 1e-12 * peak_v
    assert profile.position[-1] == pytest.approx(100.0, rel=1e-9)
    assert abs(np.sum(profile.acceleration)) <= 1e-12 * peak_a * profile.acceleration.size


def test_profile_acceleration_is_the_scaled_kernel():
    design = time_frequency_profile(OMEGA_0, TS, MOVE, distance=1.0)
    a, g = design.profile.acceleration[:-1], design.profile.kernel.taps
    np.testing.assert_allclose(a / a[10], g / g[10], rtol=1e-12)


def test_n_outside_bounds_raises_with_range():
    with pytest.raises(ValueError, match=r"n must be in \[9\.6.*, 15\.6.*\].*got 20"):
        time_frequency_profile(OMEGA_0, TS, MOVE, distance=1.0, n=20.0)


def test_non_integer_sample_count_raises():
    with pytest.raises(ValueError, match="move_time / ts must be an integer"):
        time_frequency_profile(OMEGA_0, TS, 2.51e-3 + 1e-6, distance=1.0)


def test_non_positive_distance_raises():
    with pytest.raises(ValueError, match="distance must be > 0"):
        time_frequency_profile(OMEGA_0, TS, MOVE, distance=0.0)


def test_resonance_above_nyquist_raises():
    with pytest.raises(ValueError, match=r"first_resonance \* ts must be in \(0, pi\)"):
        energy_leakage(11.0, 2e5, TS, MOVE)
