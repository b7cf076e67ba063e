"""Residual-vibration analysis against closed forms and an exact state-space simulation."""

import math

import numpy as np
import pytest
from scipy.linalg import expm

from shapefmu.analysis import (
    insensitivity,
    log_decrement_damping,
    residual_vibration,
    sensitivity,
    settling_time,
    spectrum,
)
from shapefmu.shapers import ImpulseShaper, SampledShaper, ei, zv, zvd


def _simulated_amplitude(shaper, omega, zeta):
    """Vibration amplitude of omega^2/(s^2 + 2 zeta omega s + omega^2) after the last impulse,
    propagating the state exactly with matrix exponentials (independent of analysis.py)."""
    a = np.array([[0.0, 1.0], [-(omega**2), -2 * zeta * omega]])
    x = np.zeros(2)
    previous = 0.0
    for t, amplitude in zip(shaper.times, shaper.amplitudes):
        x = expm(a * (t - previous)) @ x
        x[1] += omega**2 * amplitude  # an impulse of the input kicks the velocity by omega^2 * A
        previous = t
    sigma, omega_d = zeta * omega, omega * math.sqrt(1 - zeta**2)
    # x(t) = C e^{-sigma t} sin(omega_d t + phi): amplitude C at the last impulse
    return math.hypot(x[0], (x[1] + sigma * x[0]) / omega_d)


@pytest.mark.parametrize("q", [0.5, 0.9, 1.3, 2.2])
@pytest.mark.parametrize("zeta", [0.0, 0.05, 0.3])
def test_absolute_residual_equals_simulated_vibration_amplitude(q, zeta):
    shaper = ei(2.0, zeta)
    got = residual_vibration(shaper, 2.0 * q, zeta, definition="absolute")
    assert got == pytest.approx(_simulated_amplitude(shaper, 2.0 * q, zeta), rel=1e-9)


def test_percent_residual_is_absolute_over_unit_impulse_amplitude():
    shaper, zeta = zvd(3.0, 0.1), 0.1
    omega = np.linspace(0.5, 9.0, 50)
    ratio = residual_vibration(shaper, omega, zeta, "absolute") / residual_vibration(shaper, omega, zeta)
    np.testing.assert_allclose(ratio, omega / math.sqrt(1 - zeta**2), rtol=1e-12)


def test_unit_impulse_has_full_residual_at_every_frequency():
    omega = np.linspace(0.1, 100.0, 20)
    np.testing.assert_allclose(residual_vibration(ImpulseShaper((0.0,), (1.0,)), omega, 0.2), 1.0, rtol=1e-14)


def test_percent_residual_of_zero_sum_command_is_refused():
    with pytest.raises(ValueError, match="use definition='absolute'"):
        residual_vibration(SampledShaper([1.0, -1.0], 0.1), 3.0, 0.0)


def test_sampled_shaper_is_analysed_like_the_same_impulses():
    taps = np.array([0.1, 0.0, 0.4, 0.3, 0.2])
    sampled = SampledShaper(taps, 0.01)
    impulses = ImpulseShaper((0.0, 0.02, 0.03, 0.04), (0.1, 0.4, 0.3, 0.2))
    omega = np.linspace(1.0, 300.0, 40)
    np.testing.assert_allclose(residual_vibration(sampled, omega, 0.05), residual_vibration(impulses, omega, 0.05))


def test_undamped_percent_residual_is_spectrum_magnitude():
    shaper = ei(1.0, 0.0)
    omega = np.linspace(0.1, 3.0, 30)
    np.testing.assert_allclose(residual_vibration(shaper, omega, 0.0), np.abs(spectrum(shaper, omega)), rtol=1e-12)


def test_spectrum_of_zv_is_cosine_closed_form():
    # ZV at zeta = 0: H = (1 + e^{-j w T/2})/2, |H| = |cos(w T / 4)|, T = 2 pi / omega_n.
    omega = np.linspace(0.0, 5.0, 11)
    np.testing.assert_allclose(np.abs(spectrum(zv(1.0, 0.0), omega)), np.abs(np.cos(omega * math.pi / 2)), atol=1e-15)


def test_sensitivity_is_residual_at_scaled_frequency():
    q = np.linspace(0.0, 2.0, 21)
    curve = sensitivity(zvd(5.0, 0.02), 5.0, 0.02, q)
    np.testing.assert_allclose(curve.residual, residual_vibration(zvd(5.0, 0.02), 5.0 * q, 0.02))


def test_zv_insensitivity_matches_closed_form():
    # |cos(pi q / 2)| <= V  <=>  |q - 1| <= 2 asin(V) / pi
    band = insensitivity(zv(1.0, 0.0), 1.0, 0.0, 0.05)
    assert band.width == pytest.approx(4 * math.asin(0.05) / math.pi, rel=1e-9)
    assert band.q_low == pytest.approx(1 - 2 * math.asin(0.05) / math.pi, rel=1e-9)


def test_insensitivity_refuses_shaper_above_vtol_at_design_point():
    with pytest.raises(ValueError, match="no band"):
        insensitivity(zv(1.0, 0.0), 1.3, 0.0, 0.05)


def test_log_decrement_recovers_damping_of_exact_peaks():
    zeta, omega = 0.04, 10.0
    sigma, period = zeta * omega, 2 * math.pi / (omega * math.sqrt(1 - zeta**2))
    peaks = 3.0 * np.exp(-sigma * period * np.arange(8))
    assert log_decrement_damping(peaks) == pytest.approx(zeta, rel=1e-12)


def test_settling_time_of_decaying_exponential():
    t = np.linspace(0.0, 10.0, 100001)
    assert settling_time(t, np.exp(-t), 0.03) == pytest.approx(math.log(1 / 0.03), abs=2e-4)


def test_settling_time_of_record_that_never_settles_is_infinite():
    t = np.linspace(0.0, 1.0, 11)
    assert settling_time(t, np.ones_like(t), 0.1) == math.inf


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: residual_vibration(zv(1.0), 1.0, 1.0), "zeta must be in [0, 1), got 1.0"),
        (lambda: residual_vibration(zv(1.0), -1.0, 0.0), "omega must be finite and >= 0 rad/s, got -1.0"),
        (lambda: residual_vibration(zv(1.0), 1.0, 0.0, "relative"), "definition must be one of"),
        (lambda: insensitivity(zv(1.0), 1.0, 0.0, 1.0), "vtol must be in (0, 1), got 1.0"),
        (lambda: sensitivity(zv(1.0), 0.0, 0.0), "omega_model must be > 0, got 0.0"),
        (lambda: log_decrement_damping([1.0]), "at least 2 successive peak amplitudes"),
        (lambda: log_decrement_damping([1.0, -0.5]), "peak amplitudes must be finite and > 0"),
        (lambda: settling_time([0, 1], [0, 1], 0.0), "tolerance must be > 0, got 0.0"),
    ],
)
def test_bad_input_names_the_parameter(call, message):
    with pytest.raises(ValueError) as error:
        call()
    assert message in str(error.value)
