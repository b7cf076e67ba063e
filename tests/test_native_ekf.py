"""The native C EKFTuner FMU beyond the twin contract (tests/test_native_twin_contract.py: equal to
its pythonfmu twin in every host, on three platforms, under valgrind): its FMU state restores the EKF
and the shaper exactly, and bad values are refused with a logged message."""

import pytest
from fmpy.fmi1 import FMICallException

from support.fixtures_fmi import EKF_STARTS
from support.fmpy_slaves import configured, refused_start_values
from support.scenarios import ekf_signals, ekf_state_replays


@pytest.fixture(scope="module")
def native_ekf(builds):
    return builds.native("EKFTuner", **EKF_STARTS)


def test_state_restores_the_ekf_and_the_shaper_exactly(native_ekf):
    first, again, restored = ekf_state_replays(native_ekf, ekf_signals(1500, seed=2), 400)
    assert again == first and restored == first and first[-1][3] == 1.0


@pytest.mark.parametrize(("starts", "words"), [
    ({"omega0": 4000.0}, "omega0 must be in (0, pi/Ts) = (0, 3141.59) rad/s, got 4000"),
    ({"kind": "ei"}, "kind must be one of zv, zvd, zvdd, zv_dn, mzv, got ei"),
    ({"Ts": -1e-3}, "Ts must be > 0, got -0.001"),
    ({"retune_fraction": 0.0}, "retune_fraction must be > 0, got 0"),
    ({"n": 63}, "n must be an integer in [0, 62], got 63"),
    ({"omega0": 1e-3}, "the EKF's convergence window; at most 1000000"),
])
def test_bad_parameters_are_refused_with_a_logged_message(native_ekf, capfd, starts, words):
    """Refused when set if the value alone is out of range, else at the exit of initialisation."""
    assert refused_start_values(native_ekf, starts).status == 3  # fmi2Error
    assert words in capfd.readouterr().out


def test_a_non_finite_input_is_refused_when_set(native_ekf, capfd):
    slave, vr = configured(native_ekf)
    slave.exitInitializationMode()
    with pytest.raises(FMICallException):
        slave.setReal([vr["vibration"]], [float("nan")])
    assert "vibration must be finite, got nan" in capfd.readouterr().out
    slave.freeInstance()
