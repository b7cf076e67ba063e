"""The EKFTuner FMU against the runtime EKF-tuned shaper kernel called directly (paper 001)."""

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from support.fixtures_fmi import EKF_STARTS
from support.fmpy_slaves import initialised, refused_initialisation
from support.hosts import run_ecos, run_fmpy, run_libcosim
from support.sampled_reference import SampledRun
from support.scenarios import EKF_OUTPUTS as OUTPUTS
from support.scenarios import OMEGA, drive_ekf, ekf_signals, ekf_state_replays

from shapefmu.runtime.ekf_tuner import EKFTunedShaperKernel

H = EKF_STARTS["Ts"]


def _kernel_rows(inputs):
    kernel = EKFTunedShaperKernel(1.0 / H, EKF_STARTS["omega0"], EKF_STARTS["kind"], amplitude=EKF_STARTS["amplitude"])
    rows = []
    for values in inputs:
        y = kernel.step(values["u"], values["vibration"])
        ekf = kernel.ekf
        rows.append([y, ekf.omega_n, ekf.zeta, 1.0 if ekf.converged else 0.0])
    return rows, kernel


def test_model_description_passes_fmpy_validation(ekf_fmu):
    assert validate_fmu(str(ekf_fmu)) == []


def test_outputs_equal_the_runtime_kernel_called_directly(ekf_fmu):
    inputs = ekf_signals(2500)
    expected, kernel = _kernel_rows(inputs)
    assert kernel.designs >= 1 and kernel.filter is not None  # it tuned and shaped within the run
    assert kernel.ekf.omega_n == pytest.approx(OMEGA, rel=0.01)
    np.testing.assert_allclose(run_fmpy(ekf_fmu, inputs, H, OUTPUTS), expected, rtol=0, atol=1e-12)


def test_outputs_identical_in_fmpy_libcosim_and_ecos(ekf_fmu):
    inputs = ekf_signals(800, seed=1)
    reference = run_fmpy(ekf_fmu, inputs, H, OUTPUTS)
    for other in (run_libcosim(ekf_fmu, inputs, H, OUTPUTS), run_ecos(ekf_fmu, inputs, H, OUTPUTS)):
        np.testing.assert_allclose(other, reference, rtol=0, atol=1e-12)


def test_state_restores_the_ekf_covariance_and_shaper_exactly(ekf_fmu):
    # Saved mid-convergence (covariance still moving) and replayed: bit-for-bit the same estimates.
    first, again, restored = ekf_state_replays(ekf_fmu, ekf_signals(1500, seed=2), 400)
    assert again == first and restored == first
    assert first[-1][3] == 1.0  # the replay covers the convergence and the switch-in


def test_nan_vibration_fails_that_step_and_the_run_continues_unchanged(ekf_fmu):
    inputs = ekf_signals(300, seed=3)
    slave, vr = initialised(ekf_fmu)
    rows = drive_ekf(slave, vr, inputs[:100], 0)
    slave.setReal([vr["vibration"]], [float("nan")])
    with pytest.raises(FMICallException) as failure:
        slave.doStep(100 * H, H)
    assert failure.value.status == 3
    rows += drive_ekf(slave, vr, inputs[100:], 100)
    slave.freeInstance()
    assert rows == run_fmpy(ekf_fmu, inputs, H, OUTPUTS)


def test_steps_of_2_5_samples_run_the_kernel_once_per_sample_and_hold_its_outputs(ekf_fmu):
    inputs = ekf_signals(1200, seed=4)
    step = 2.5 * H
    rows = run_fmpy(ekf_fmu, inputs, step, OUTPUTS)  # outputs after each step, at (k + 1) * step
    run = SampledRun(step * np.arange(len(inputs) + 1), [[v["u"], v["vibration"]] for v in inputs] + [[0.0, 0.0]], H)
    expected, _ = _kernel_rows([{"u": u, "vibration": v} for u, v in run.samples])
    # At sample k's instant the outputs are those after sample k - 1.
    np.testing.assert_allclose(rows, np.array(expected)[run.index[1:] - 1], rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    ("starts", "words"),
    [
        ({"omega0": 4000.0}, "omega0 must be in (0, pi*fs)"),
        ({"kind": "ei"}, "kind must be one of"),
        ({"Ts": -1e-3}, "Ts must be > 0"),
        ({"retune_fraction": 0.0}, "retune_fraction must be > 0"),
    ],
)
def test_bad_parameters_fail_initialisation_with_a_logged_error(ekf_fmu, capfd, starts, words):
    assert refused_initialisation(ekf_fmu, starts).status == 3  # fmi2Error
    assert words in capfd.readouterr().out
