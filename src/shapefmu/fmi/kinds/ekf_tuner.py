"""The EKFTuner FMU: watches a vibration, estimates its mode with the EKF, shapes the command for it.

Wraps ``runtime.ekf_tuner.EKFTunedShaperKernel`` (paper 001, Fig. 20): until the resonance EKF has
converged the command passes through; then a shaper of ``kind`` is designed for the estimated
(omega_n, zeta) and switched in once the command rests; a converged estimate that moves by more than
``retune_fraction`` re-designs it.

Sampled semantics (``runtime.sample_clock``). The kernel runs one sample at every instant
t0 + k ``Ts`` (t0 the start time, fs = 1 / Ts) wherever the communication points fall, with the
values of ``u`` and ``vibration`` in effect at that instant (set at the last communication point at
or before it, within 1e-6 Ts). Any step h > 0 is accepted; a step over more than 10^7 samples is
refused (fmi2Error). The outputs are the kernel's after the newest sample committed, held until the
next one: ``y`` the shaped command of that sample, ``omega_est`` and ``zeta_est`` the EKF's estimate
of the undamped frequency and damping ratio, ``converged`` 1 once the estimate has converged. So at
t0 + k Ts the outputs are those of sample k - 1 (one sample of delay, as with steps of Ts from t0).
Outputs change only in doStep, so none depends on an input at the same instant (ModelStructure
lists none).

State. fmi2GetFMUstate saves the whole kernel: the EKF's state, covariance, convergence window and
re-acquisition statistic, the shaper's ring buffer and any pending design.
"""

import math

from ...runtime.checks import check_count, check_positive
from ...runtime.ekf import ResonanceEKF
from ...runtime.ekf_tuner import KINDS, EKFTunedShaperKernel
from ...runtime.sample_clock import EKF_SAMPLE_SECONDS, SampleClock, samples_per_python_step
from ...runtime.shaper_filter import StreamingShaper
from .interface import Interface, input_, output, parameter, sampled_description
from .model import Model as _Model

INTERFACE = Interface(
    "EKFTuner",
    sampled_description(
        "EKF-tuned input shaper: estimates the vibration's mode and shapes the command for it (paper 001)",
        "u and vibration",
    ),
    (
        parameter("kind", "zvd", f"shaper designed for the estimated mode: {', '.join(KINDS)}"),
        parameter("n", 1, "derivative order of zv_dn (0 = ZV, 1 = ZVD, ...)", minimum=0),
        parameter("Ts", 1e-3, "sampling period of the EKF and the shaper", unit="s"),
        parameter("omega0", 2.0 * math.pi * 10.0, "initial guess of the vibration's frequency", unit="rad/s"),
        parameter("amplitude", 1.0, "scale of the vibration signal the EKF tuning is relative to"),
        parameter("retune_fraction", 0.05, "re-design when the estimate moves by more than this fraction"),
        input_("u", 0.0, "command to shape"),
        input_("vibration", 0.0, "measured vibration (ring-down) the EKF watches"),
        output("y", "shaped command (the command itself until a shaper is switched in)"),
        output("omega_est", "estimated undamped natural frequency", unit="rad/s"),
        output("zeta_est", "estimated damping ratio"),
        output("converged", "1 once the EKF estimate has converged, else 0"),
    ),
    command_in="u",
    command_out="y",
)


class Model(_Model):
    interface = INTERFACE
    kernels = (EKFTunedShaperKernel, ResonanceEKF, StreamingShaper, SampleClock)
    state_attributes = ("tuner", "clock")

    def initialize(self):
        values = self.values
        ts = check_positive(values["Ts"], "Ts")
        kind = values["kind"]
        if kind not in KINDS:
            raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
        self.tuner = EKFTunedShaperKernel(
            1.0 / ts,
            values["omega0"],
            kind,
            check_count(values["n"], "n", minimum=0),
            values["retune_fraction"],
            amplitude=values["amplitude"],
        )
        self.clock = SampleClock(ts, samples_per_python_step(EKF_SAMPLE_SECONDS))
        values["y"] = 0.0
        self._estimates()

    def _estimates(self):
        ekf = self.tuner.ekf
        self.values["omega_est"] = ekf.omega_n
        self.values["zeta_est"] = ekf.zeta
        self.values["converged"] = 1.0 if ekf.converged else 0.0

    def experiment(self):
        """DefaultExperiment: 200 periods of the guessed frequency, one sample per step."""
        ts = self.values["Ts"]
        return 0.0, ts * math.ceil(200 * 2.0 * math.pi / self.values["omega0"] / ts), ts

    def picture(self):
        """The ring-down the EKF watches: four periods of the guessed frequency, decaying."""
        return [("line", [(k / 32, math.exp(-k / 64) * math.cos(math.pi * k / 16)) for k in range(129)])]

    def step(self, t, h):
        values, tuner = self.values, self.tuner

        def commit(sample):
            values["y"] = tuner.step(*sample)

        self.clock.advance(t, h, (values["u"], values["vibration"]), commit)
        self._estimates()
