"""A shaper that tracks its mode online: the EKF of paper 001 watching the machine's normal moves, and
a shaper re-designed for the EKF's estimate without a jump (``scheduled_shaper``), as one kernel.

``TrackedShaperKernel.step(command, measurement)`` once per sample: ``command`` is the plant's input
before shaping (for the plants of ``models/``, the drive's acceleration), ``measurement`` the
vibration the plant shows at the same instant (a bed's accelerometer, a load's swing angle), taken
before this sample's shaped command acts.

What the EKF watches. The filter of ``runtime.ekf`` models a free ring-down, eq. (20). The plant rings
freely only while its input rests at the value around which the vibration is zero (``rest``: an
acceleration of 0, coasting or standing still); while a shaped move drives it, the measurement holds
the forced response the model has no term for. So a sample goes to the EKF only when the shaped
command has rested for the sample before it, which the kernel knows without a tolerance: the
command has equalled ``rest`` for as many samples as the designs in flight are long
(``ModeFollowingShaper.span``). Every other sample goes in as missing (the prediction keeps the time
base). When watching resumes after a move, a new ring-down begins whose amplitude and phase are
unknown: the phasor is restarted (``ResonanceEKF.restart_phasor``) while omega and sigma keep what
earlier moves taught. No calibration run: the rings the EKF learns from are the residual vibration
of the machine's own moves, which is largest exactly when the shaper is most wrong.

Taking the estimate (keep the last good design). The shaper is designed for the mode
(omega_n, zeta) = (hypot(omega_d, sigma), sigma / hypot(omega_d, sigma)) (paper 001, eq. 28) only
when the EKF's convergence test passes at a watched sample: the standard deviations of omega and
sigma below ``omega_tol`` and ``sigma_tol`` times omega and both estimates steady over the last
period (``ResonanceEKF.converged``), and the mode is plausible: omega_n within ``band`` (factors of
the initial guess) and zeta in [0, ``zeta_max``]. Otherwise the design in force stays, which
at the start is the initial guess (``omega0``, ``zeta0``). A sudden change of the mode (a heavier
part, a new tool) makes the innovations larger than the filter expects; the EKF's own
re-acquisition (normalised innovation averaged over a period above ``nis_limit``) opens its
covariance again, and the next converged estimate re-designs the shaper.

Tuning. ``tracking_tuning`` sets the EKF's variances for tracking rather than for one ring-down
(``ekf.default_tuning``). The measurement noise is the sensor's. The frequency may wander by
``drift`` (a fraction of omega0, default 0.2 %) per square root of a period instead of 0.01 %, which
would follow a mass growing during a print too slowly; the decay rate by 0.3 of that (the bed's
sigma = c / 2m moves a tenth as far as its omega). The phasor's own random walk is 0.01 % of the
ring's scale per sample instead of 0.1 %: the rings the filter learns from after a well-shaped move
are a percent of an unshaped one, and a walk of 0.1 % of the unshaped scale per sample would let the
phasor absorb their decay and bias sigma.
"""

import math

from .checks import check_finite, check_positive, check_zeta
from .ekf import P0_OMEGA, P0_SIGMA, ResonanceEKF
from .scheduled_shaper import ModeFollowingShaper


# Tracking tuning: the phasor's random walk per sample and the decay rate's per period, as fractions
# of the ring amplitude and of the frequency's walk (module docstring, Tuning).
Q_PHASOR = 1e-4
SIGMA_DRIFT = 0.3


def tracking_tuning(fs, omega0, amplitude, noise, drift=2e-3):
    """``(p0, q, r)`` for a ``ResonanceEKF`` that tracks a mode: ``amplitude`` the scale of the rings
    it will see, ``noise`` the measurement's standard deviation (same unit), ``drift`` the relative
    frequency change per square root of a period its random walk allows (module docstring)."""
    fs = check_positive(fs, "fs")
    omega0 = check_positive(omega0, "omega0")
    amplitude = check_positive(amplitude, "amplitude")
    noise = check_positive(noise, "noise")
    drift = check_positive(drift, "drift")
    samples_per_period = 2.0 * math.pi * fs / omega0
    p0 = [amplitude**2, amplitude**2, (P0_OMEGA * omega0) ** 2, (P0_SIGMA * omega0) ** 2]
    # A random walk of per-sample variance v moves by sqrt(v N) in N samples (as ekf.default_tuning).
    q = [(Q_PHASOR * amplitude) ** 2, (Q_PHASOR * amplitude) ** 2, (drift * omega0) ** 2 / samples_per_period,
         (SIGMA_DRIFT * drift * omega0) ** 2 / samples_per_period]
    return p0, q, noise**2


class TrackedShaperKernel:
    """``step(command, measurement) -> shaped command`` at ``fs``: a shaper of ``kind`` (``n``,
    ``vtol``, ``resolution`` as ``ModeFollowingShaper``) designed first for the guess
    (``omega0`` rad/s, ``zeta0``), then for the EKF's last good estimate (module docstring).

    ``rest`` is the command at which the plant rings freely about zero, ``u0`` the command before the
    first sample; ``band`` = (low, high) bounds a plausible omega_n to [low, high] * omega0,
    ``zeta_max`` a plausible damping ratio. The other keyword arguments (``p0``, ``q``, ``r``,
    ``amplitude``, ``omega_tol``, ``sigma_tol``, ``window``, ``nis_limit``) configure the
    ``ResonanceEKF``, started at the guess's damped frequency and decay rate.
    """

    def __init__(self, fs, omega0, zeta0=0.0, kind="zv", n=1, vtol=0.05, rest=0.0, u0=0.0, band=(0.5, 2.0),
                 zeta_max=0.5, resolution=1e-3, **ekf_options):
        omega0 = check_positive(omega0, "omega0")
        zeta0 = check_zeta(zeta0, "zeta0")
        self.shaper = ModeFollowingShaper(fs, omega0, zeta0, kind, n, vtol, u0, resolution)
        self.ekf = ResonanceEKF(fs, omega0 * math.sqrt(1.0 - zeta0 * zeta0), sigma0=zeta0 * omega0, **ekf_options)
        low, high = (check_positive(b, "band") for b in band) if len(band) == 2 else (0.0, 0.0)
        if not low < 1.0 < high:
            raise ValueError(f"band must be (low, high) with 0 < low < 1 < high, got {band!r}")
        self.band = (low * omega0, high * omega0)
        self.zeta_max = check_zeta(zeta_max, "zeta_max")
        self.rest = check_finite(rest, "rest")
        self.mode = (omega0, zeta0)  # the design point in force: the guess, then the last good estimate
        self.estimates = 0  # converged, plausible estimates taken
        # Commands in a row equal to rest, up to the last sample; u0 at rest counts as rested for ever.
        self._rested = math.inf if check_finite(u0, "u0") == self.rest else 0
        self._watching = False

    @property
    def watching(self):
        """Whether the EKF saw the last measurement (the plant was free before it)."""
        return self._watching

    def observe(self, measurement):
        """Feed one measurement to the EKF if the plant was free before it; take a good estimate."""
        if self._rested < self.shaper.span:
            self._watching = False
            self.ekf.step(None)
            return
        if not self._watching:
            self.ekf.restart_phasor()
            self._watching = True
        ekf = self.ekf
        if not ekf.step(measurement) or not self.band[0] <= ekf.omega_n <= self.band[1]:
            return  # nothing measured, or a ring of another mode
        omega, zeta = self.mode
        if ekf.omega_converged:
            omega = ekf.omega_n
        if ekf.sigma_converged and 0.0 <= ekf.zeta <= self.zeta_max:
            zeta = ekf.zeta
        if (omega, zeta) != self.mode:
            self.mode = (omega, zeta)
            self.estimates += 1

    def step(self, command, measurement):
        """Observe the measurement, then return the command shaped for the mode in force."""
        self.observe(measurement)
        shaped = self.shaper.step(command, *self.mode)
        self._rested = self._rested + 1 if command == self.rest else 0
        return shaped
