"""A shaper that tracks its mode online: the EKF of paper 001 watching the machine's normal moves, and
a shaper re-designed for the EKF's estimate without a jump (``scheduled_shaper``), as one kernel.

``TrackedShaperKernel.step(command, measurement)`` once per sample: ``command`` is the plant's input
before shaping (for the plants of ``models/``, the drive's acceleration), ``measurement`` the
vibration the plant shows at the same instant (a bed's accelerometer, a load's swing angle), taken
before this sample's shaped command acts.

What the EKF watches. The filter of ``runtime.ekf`` models a free ring-down, eq. (20). Between two
changes of the shaped command the plant's input holds one value, so the plant rings freely about the
equilibrium that value sets; when the command changes, a new ring begins whose amplitude and phase are
unknown, and the phasor is restarted (``ResonanceEKF.restart_phasor``) while omega and sigma keep
what earlier rings taught. The measurement is referred to that equilibrium through ``gain``, the
value the measurement settles to per unit of held command: 1 for an accelerometer on a mass that an
accelerating drive carries (once the ring has died it moves with the drive), -1/g for a pendulum's
angle under its trolley's acceleration (theta = -a/g). Every held stretch of a move then shows a ring:
the first impulse of a ZV shaper alone excites half the unshaped vibration for half a period, and the
rest after the move shows what the move left. Without a ``gain`` (a deflection, whose equilibrium
-a/omega^2 depends on the very mode being estimated) the EKF watches only while the command rests at
``rest``, where the equilibrium is zero: once the command has equalled ``rest`` for as many samples
as the designs in flight are long (``ModeFollowingShaper.span``), known exactly, without a tolerance.
Samples not watched go in as missing (the prediction keeps the time base). No calibration run: every
ring the EKF learns from is one the machine's own moves excite.

Taking the estimate (keep the last good design). The shaper is designed for the mode
(omega_n, zeta) = (hypot(omega_d, sigma), sigma / hypot(omega_d, sigma)) (paper 001, eq. 28) only from
what passed the EKF's convergence tests at a watched sample. The frequency is taken when the standard
deviation of omega is below ``omega_tol`` times omega and omega has stayed within that over the last
period (``ResonanceEKF.omega_converged``); the damping when the same holds for sigma with
``sigma_tol`` (``sigma_converged``) and zeta lies in [0, ``zeta_max``]. The two are taken apart
because a weak ring tells the frequency long before the decay. Neither is taken while omega_n lies
outside ``band`` (factors of the initial guess): a ring of another mode, or none. Otherwise the design
in force stays, which at the start is the initial guess (``omega0``, ``zeta0``). A sudden change of
the mode (a heavier part, a new tool) shows in the next rings; the random walk of the tuning below
lets omega follow, and the EKF's own re-acquisition (normalised innovation averaged over a period above
``nis_limit``) opens its covariance again if the change is too large for it.

Tuning. ``tracking_tuning`` sets the EKF's variances for tracking rather than for one ring-down
(``ekf.default_tuning``). The measurement noise is the sensor's. The frequency may wander by
``drift`` (a fraction of omega0, default 0.1 %) per square root of a period instead of 0.01 %, which
would follow a mass growing during a print too slowly; the decay rate by 0.3 of that (the bed's
sigma = c / 2m moves a tenth as far as its omega: room to spare). The phasor's own random walk is 0.01 % of the
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


def tracking_tuning(fs, omega0, amplitude, noise, drift=1e-3):
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

    ``gain`` is the measurement's equilibrium per unit of held command (None: unknown, watch only at
    rest), ``rest`` the command at which it is zero, ``u0`` the command before the first sample
    (module docstring, What the EKF watches); ``band`` = (low, high) bounds a plausible omega_n to
    [low, high] * omega0, ``zeta_max`` a plausible damping ratio. The other keyword arguments (``p0``, ``q``, ``r``,
    ``amplitude``, ``omega_tol``, ``sigma_tol``, ``window``, ``nis_limit``) configure the
    ``ResonanceEKF``, started at the guess's damped frequency and decay rate.
    """

    def __init__(self, fs, omega0, zeta0=0.0, kind="zv", n=1, vtol=0.05, gain=None, rest=0.0, u0=0.0,
                 band=(0.5, 2.0), zeta_max=0.5, resolution=1e-3, **ekf_options):
        omega0 = check_positive(omega0, "omega0")
        zeta0 = check_zeta(zeta0, "zeta0")
        self.shaper = ModeFollowingShaper(fs, omega0, zeta0, kind, n, vtol, u0, resolution)
        self.ekf = ResonanceEKF(fs, omega0 * math.sqrt(1.0 - zeta0 * zeta0), sigma0=zeta0 * omega0, **ekf_options)
        try:
            low, high = (check_finite(b, "band") for b in band)
        except (TypeError, ValueError):
            low = high = math.nan
        if not 0.0 < low < 1.0 < high:
            raise ValueError(f"band must be (low, high) with 0 < low < 1 < high, got {band!r}")
        self.band = (low * omega0, high * omega0)
        self.zeta_max = check_zeta(zeta_max, "zeta_max")
        self.gain = None if gain is None else check_finite(gain, "gain")
        self.rest = check_finite(rest, "rest")
        self.mode = (omega0, zeta0)  # the design point in force: the guess, then the last good estimate
        u0 = check_finite(u0, "u0")
        # Commands in a row equal to rest, up to the last sample; u0 at rest counts as rested for ever.
        self._rested = math.inf if u0 == self.rest else 0
        self._output, self._changed = u0, False  # the last shaped command, and whether it moved then
        self._watching = False

    @property
    def watching(self):
        """Whether the EKF saw the last measurement (the plant was free before it)."""
        return self._watching

    def observe(self, measurement):
        """Feed one measurement to the EKF if the plant rang freely before it; take a good estimate."""
        if self.gain is None and self._rested < self.shaper.span:
            self._watching = False
            self.ekf.step(None)
            return
        if not self._watching or self._changed:
            self.ekf.restart_phasor()  # a new ring began with the last sample's command
            self._watching = True
        if measurement is not None and self.gain is not None:
            measurement -= self.gain * (self._output - self.rest)
        ekf = self.ekf
        if not ekf.step(measurement) or not self.band[0] <= ekf.omega_n <= self.band[1]:
            return  # nothing measured, or a ring of another mode
        omega, zeta = self.mode
        if ekf.omega_converged:
            omega = ekf.omega_n
        if ekf.sigma_converged and 0.0 <= ekf.zeta <= self.zeta_max:
            zeta = ekf.zeta
        self.mode = (omega, zeta)

    def step(self, command, measurement):
        """Observe the measurement, then return the command shaped for the mode in force."""
        self.observe(measurement)
        shaped = self.shaper.step(command, *self.mode)
        self._rested = self._rested + 1 if command == self.rest else 0
        self._changed, self._output = shaped != self._output, shaped
        return shaped
