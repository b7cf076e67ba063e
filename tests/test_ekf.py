"""The runtime resonance EKF (paper 001, eqs. 15-26) against closed forms and textbook matrices."""

import copy
import math

import numpy as np
import pytest

from shapefmu.runtime.ekf import ResonanceEKF

FS = 1000.0
OMEGA = 2 * math.pi * 10.0
SIGMA = 1.0 / 1.2


def _ringdown(n, phase=0.3, noise=0.0, seed=0):
    t = np.arange(n) / FS
    rng = np.random.default_rng(seed)
    return np.exp(-SIGMA * t) * np.sin(OMEGA * t + phase) + noise * rng.normal(size=n)


def test_prediction_follows_the_ringdown_of_eq_20():
    ekf = ResonanceEKF(FS, OMEGA, SIGMA)
    ekf.x = [0.0, 1.0, OMEGA, SIGMA]  # eq. (23) at k = 0 for A = 1
    for _ in range(750):
        ekf.predict()
    k = 750
    decay = math.exp(-SIGMA * k / FS)
    assert ekf.x[0] == pytest.approx(decay * math.sin(OMEGA * k / FS), abs=1e-12)
    assert ekf.x[1] == pytest.approx(decay * math.cos(OMEGA * k / FS), abs=1e-12)


def _transition(x):
    c = math.exp(-x[3] / FS) * math.cos(x[2] / FS)
    s = math.exp(-x[3] / FS) * math.sin(x[2] / FS)
    return np.array([c * x[0] + s * x[1], -s * x[0] + c * x[1], x[2], x[3]])


def test_covariance_prediction_uses_the_jacobian_of_eq_24():
    x = np.array([0.3, -0.7, 70.0, 1.5])
    # Central finite differences of eq. (24): an independent Jacobian.
    F = np.column_stack([(_transition(x + d) - _transition(x - d)) / (2e-6) for d in 1e-6 * np.eye(4)])
    rng = np.random.default_rng(1)
    m = rng.normal(size=(4, 4))
    P = m @ m.T + np.eye(4)
    q = [1e-3, 2e-3, 3e-3, 4e-3]
    ekf = ResonanceEKF(FS, 70.0, q=q)
    ekf.x, ekf.P = list(x), P.tolist()
    ekf.predict()
    np.testing.assert_allclose(np.array(ekf.P), F @ P @ F.T + np.diag(q), rtol=1e-7, atol=1e-9)


def test_update_matches_eqs_17_to_19_in_matrix_form():
    rng = np.random.default_rng(2)
    m = rng.normal(size=(4, 4))
    P = m @ m.T + np.eye(4)
    x = np.array([0.2, 0.5, 60.0, 0.8])
    phase, r, z = 0.7, 0.05, 0.9
    ekf = ResonanceEKF(FS, 60.0, phase=phase, r=r)
    ekf.x, ekf.P = list(x), P.tolist()
    ekf.update(z)
    H = np.array([[math.cos(phase), math.sin(phase), 0.0, 0.0]])
    K = P @ H.T / (H @ P @ H.T + r)  # eq. (17)
    np.testing.assert_allclose(ekf.x, x + (K * (z - H @ x)).ravel(), rtol=1e-12)  # eq. (18)
    np.testing.assert_allclose(np.array(ekf.P), (np.eye(4) - K @ H) @ P, rtol=1e-10, atol=1e-12)  # eq. (19)


@pytest.mark.parametrize("phase", [0.4, 1.3, -2.0])
def test_measurement_of_the_true_state_has_zero_innovation(phase):
    # eqs. (20) and (23) give s = x1 cos(phi) + x2 sin(phi); the OCR'd eq. (25) (minus sign) does not.
    k, amplitude = 123, 0.7
    e = amplitude * math.exp(-SIGMA * k / FS)
    x = [e * math.sin(OMEGA * k / FS), e * math.cos(OMEGA * k / FS), OMEGA, SIGMA]
    s = amplitude * math.exp(-SIGMA * k / FS) * math.sin(OMEGA * k / FS + phase)
    ekf = ResonanceEKF(FS, OMEGA, phase=phase)
    ekf.x = list(x)
    ekf.update(s)
    np.testing.assert_allclose(ekf.x, x, rtol=0, atol=1e-12)
    assert x[0] * math.cos(phase) - x[1] * math.sin(phase) != pytest.approx(s, abs=1e-3)


def test_estimates_do_not_depend_on_the_reference_phase():
    y = _ringdown(600, noise=0.05)
    estimates = []
    for phase in (0.0, 1.0):
        ekf = ResonanceEKF(FS, 55.0, phase=phase)
        for v in y:
            ekf.step(float(v))
        estimates.append((ekf.omega_d, ekf.sigma))
    assert estimates[0] == pytest.approx(estimates[1], rel=1e-8)


def test_clean_ringdown_converges_to_the_true_mode():
    ekf = ResonanceEKF(FS, 50.0)
    assert not ekf.converged
    for v in _ringdown(1000):
        ekf.step(float(v))
    assert ekf.converged
    assert ekf.omega_d == pytest.approx(OMEGA, rel=5e-4)
    assert ekf.sigma == pytest.approx(SIGMA, rel=2e-2)
    assert ekf.zeta == pytest.approx(SIGMA / math.hypot(SIGMA, OMEGA), rel=2e-2)
    assert ekf.omega_n == pytest.approx(math.hypot(SIGMA, OMEGA), rel=5e-4)


def test_missing_samples_only_predict_and_are_counted():
    y = _ringdown(1000, noise=0.05).tolist()
    gaps = set(range(5, 1000, 7)) | {3}
    for k in gaps:
        y[k] = None if k == 3 else math.nan
    ekf = ResonanceEKF(FS, 70.0)
    for k, v in enumerate(y):
        if k in gaps:
            predicted = copy.deepcopy(ekf)
            predicted.predict()
        assert ekf.step(v) == (k not in gaps)
        if k in gaps:
            assert ekf.x == predicted.x and ekf.P == predicted.P
    assert ekf.missing == len(gaps)
    assert ekf.resets == 0
    assert ekf.omega_d == pytest.approx(OMEGA, rel=1e-2)


def test_a_diverging_step_returns_to_the_last_good_estimate():
    ekf = ResonanceEKF(FS, 60.0)
    for v in _ringdown(300):
        ekf.step(float(v))
    good = list(ekf.x)
    assert not ekf.step(1e308)  # overflows the covariance / throws omega out of (0, pi fs)
    assert ekf.reset_last and ekf.resets == 1
    assert ekf.x == good
    assert all(math.isfinite(v) for row in ekf.P for v in row)
    for v in _ringdown(1000)[300:]:
        ekf.step(float(v))
    assert not ekf.reset_last
    assert ekf.omega_d == pytest.approx(OMEGA, rel=1e-3)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"fs": 0.0}, "fs"),
        ({"fs": -1.0}, "fs"),
        ({"omega0": 0.0}, "omega0"),
        ({"omega0": 4000.0}, "omega0"),
        ({"r": math.inf}, "r"),
        ({"r": 0.0}, "r"),
        ({"q": [0.0, 0.0, math.nan, 0.0]}, "q"),
        ({"p0": [1.0, 1.0, 1.0]}, "p0"),
    ],
)
def test_bad_parameters_raise_naming_them(kwargs, name):
    args = {"fs": FS, "omega0": 60.0, **kwargs}
    with pytest.raises(ValueError, match=rf"^{name} "):
        ResonanceEKF(**args)
