"""The TrackedShaper FMU: an impulse shaper kept on a moving mode by the EKF of paper 001 watching the
plant's measured vibration during the machine's own moves, no calibration run.

Each sample runs ``runtime.tracked_shaper.TrackedShaperKernel`` (the derivation of what the EKF
watches and of the convergence test is there): parameters ``f0`` (Hz) and ``zeta0``, the guess the
shaper starts with; ``kind``, ``n``, ``vtol``, ``resolution`` as the ScheduledShaper's; ``noise``
(the measurement's standard deviation), ``amplitude`` (the scale of the rings it will show) and
``drift`` (the relative frequency change per square root of a period the EKF follows), which set its
tuning (``runtime.tracked_shaper.tracking_tuning``); ``gain``, the measurement's equilibrium per unit
of held command (1 for an accelerometer on a driven mass, -1/g for a pendulum's angle), and ``rest``;
``band_low``, ``band_high`` (a plausible omega_n in [low, high] * 2 pi f0), ``zeta_max``,
``omega_tol``, ``sigma_tol``; ``Ts`` and ``u0``. Inputs ``u`` (the command) and ``measurement`` (the
plant's vibration at the sample, before the sample's shaped command acts), sampled as a pair; outputs
``y`` (the shaped command), ``f`` and ``zeta`` (the design point in force: the guess, then the EKF's
last good estimate).

Feed-through: y at a sample depends on both inputs there (the measurement may move the design point
before the command is shaped). An input set at a communication point updates y by running the sample
on a copy of the kernel, which the step then takes for real.
"""

import copy
import math

from ...runtime.checks import check_count, check_finite, check_positive, check_vtol
from ...runtime.ekf import ResonanceEKF
from ...runtime.sample_clock import EKF_SAMPLE_SECONDS, SampleClock, samples_per_python_step
from ...runtime.scheduled_shaper import CommandSegment, ModeFollowingShaper
from ...runtime.shaper_designs import KINDS
from ...runtime.tracked_shaper import TrackedShaperKernel, tracking_tuning
from .interface import Interface, input_, output, parameter, redesigned_shaper_parameters, sampled_description
from .model import Model as _Model

# A sample runs the EKF, may re-design (36 us at most, scheduled_shaper.SAMPLE_SECONDS) and, when an
# input was set, runs once more on a copy.
SAMPLE_SECONDS = 2.0 * EKF_SAMPLE_SECONDS + 50e-6

INTERFACE = Interface(
    "TrackedShaper",
    sampled_description(
        "Impulse shaper kept on a moving mode by the EKF of paper 001 watching the plant's measured vibration "
        "during the machine's own moves (no calibration run), re-designed for its last good estimate with no "
        "jump", "u and measurement"
    ),
    (
        *redesigned_shaper_parameters(KINDS),
        parameter("f0", 27.0, "natural frequency of the guess the shaper starts with", unit="Hz"),
        parameter("zeta0", 0.05, "damping ratio of the guess, in [0, 1)", minimum=0.0),
        parameter("noise", 0.02, "standard deviation of the measurement noise, in the measurement's unit"),
        parameter("amplitude", 2.0, "scale of the rings the measurement will show, in its unit"),
        parameter("drift", 1e-3, "relative frequency change per square root of a period the EKF follows"),
        parameter("gain", 1.0, "the measurement's equilibrium per unit of held command (1: an accelerometer on a "
                  "driven mass; -1/g: a pendulum's angle)"),
        parameter("rest", 0.0, "the command at which the measurement's equilibrium is zero"),
        parameter("band_low", 0.5, "lowest plausible natural frequency, as a factor of f0, in (0, 1)"),
        parameter("band_high", 2.0, "highest plausible natural frequency, as a factor of f0, > 1"),
        parameter("zeta_max", 0.5, "highest plausible damping ratio"),
        parameter("omega_tol", 1e-2, "frequency taken when its standard deviation is below this fraction of it"),
        parameter("sigma_tol", 4e-3, "decay rate taken when its standard deviation is below this fraction of omega"),
        parameter("resolution", 1e-3, "re-design when the estimate's frequency moved by more than this fraction, "
                  "or its damping ratio by more than this", minimum=0.0),
        parameter("Ts", 1e-3, "sampling period: u and measurement are sampled at startTime + k*Ts", unit="s"),
        parameter("u0", 0.0, "command before the start time (the filter starts at rest on it)"),
        input_("u", 0.0, "command to shape"),
        input_("measurement", 0.0, "the plant's measured vibration at the sample (an accelerometer, a swing angle)"),
        output("y", "shaped command, designed for the mode in force"),
        output("f", "natural frequency of the mode in force: the guess, then the EKF's last good estimate", unit="Hz"),
        output("zeta", "damping ratio of the mode in force"),
    ),
    command_in="u",
    command_out="y",
)


class Model(_Model):
    interface = INTERFACE
    kernels = (TrackedShaperKernel, ResonanceEKF, ModeFollowingShaper, CommandSegment, SampleClock)
    state_attributes = ("kernel", "clock")

    def initialize(self):
        values = self.values
        ts = check_positive(values["Ts"], "Ts")
        omega0 = 2.0 * math.pi * check_positive(values["f0"], "f0")
        p0, q, r = tracking_tuning(1.0 / ts, omega0, values["amplitude"], values["noise"], values["drift"])
        self.kernel = TrackedShaperKernel(
            1.0 / ts, omega0, values["zeta0"], values["kind"], check_count(values["n"], "n", minimum=0),
            check_vtol(values["vtol"]), check_finite(values["gain"], "gain"), values["rest"],
            check_finite(values["u0"], "u0"), (values["band_low"], values["band_high"]), values["zeta_max"],
            values["resolution"], p0=p0, q=q, r=r, omega_tol=values["omega_tol"], sigma_tol=values["sigma_tol"])
        self.clock = SampleClock(ts, samples_per_python_step(SAMPLE_SECONDS))
        self._show(*self._inputs())

    def _inputs(self):
        return self.values["u"], self.values["measurement"]

    def _show(self, command, measurement):
        """The outputs of the current sample with these inputs: the sample run on a copy of the kernel."""
        probe = copy.deepcopy(self.kernel)
        self.values["y"] = probe.step(check_finite(command, "u"), check_finite(measurement, "measurement"))
        omega, zeta = probe.mode
        self.values["f"], self.values["zeta"] = omega / (2.0 * math.pi), zeta

    def _commit(self, sample):
        self.kernel.step(*sample)

    def output_dependencies(self):
        return {"y": ["u", "measurement"], "f": ["u", "measurement"], "zeta": ["u", "measurement"]}

    def experiment(self):
        """DefaultExperiment (start, stop, step): one sample per step, a second."""
        ts = self.values["Ts"]
        return 0.0, max(1.0, 10.0 * ts), ts

    def picture(self):
        """The impulses of the guess's design, on the sample grid."""
        ts = self.values["Ts"]
        return [("stems", [(d * ts, w) for d, w in self.kernel.shaper.taps])]

    def input_changed(self, name):
        if self.kernel is not None:
            self._show(*self.clock.current(self._inputs()))

    def step(self, t, h):
        self._show(*self.clock.advance(t, h, self._inputs(), self._commit))
