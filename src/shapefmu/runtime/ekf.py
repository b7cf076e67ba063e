"""Extended Kalman filter for one decaying resonance (paper 001, eqs. 15-26), one sample per step.

The vibration is modelled as a ring-down sampled at ``fs`` (eq. 20),

    s(k) = A exp(-sigma k/fs) sin(omega k/fs + phi),       y_k = s(k) + n_k   (eq. 21),

with the four states of eq. (23): the in-phase and quadrature components
x1 = A exp(-sigma k/fs) sin(omega k/fs), x2 = A exp(-sigma k/fs) cos(omega k/fs), the damped
frequency x3 = omega (rad/s) and the decay rate x4 = sigma (1/s; eq. 23 calls it the "damping
ratio", but it is the attenuation coefficient of eq. 20). One sample advances the phasor (x1, x2) by
the angle omega/fs and shrinks it by exp(-sigma/fs): the transition of eq. (24).

Corrections to the OCR'd paper, re-derived here:

- eq. (22) prints the factor exp(+sigma/fs); expanding s(k+1) = s(k) advanced by one sample gives
  exp(-sigma/fs), which is also what eq. (24) uses.
- eqs. (25) and (26) disagree in sign. From eqs. (20) and (23),
  s(k) = A e^{-sigma k/fs} [sin(omega k/fs) cos(phi) + cos(omega k/fs) sin(phi)]
       = x1 cos(phi) + x2 sin(phi),
  so the measurement is h(x) = cos(phi) x1 + sin(phi) x2 and H = [cos(phi), sin(phi), 0, 0]:
  eq. (26) is right and the minus sign of eq. (25) is wrong.
- phi is unknown in practice. It only rotates the phasor coordinates: the filter with any fixed
  reference ``phase`` estimates the same omega and sigma (the test suite checks this), the
  unknown signal phase being absorbed by the initial (x1, x2). ``phase`` defaults to 0, where
  y = x1.

Tuning (``default_tuning``). The paper uses Q = 1e-2 I and R = 1e-3 for a signal of amplitude
~0.1 at 10 Hz; those numbers mix units (x1, x2 in signal units, omega in rad/s, sigma in 1/s) and
fail for other amplitudes and frequencies. Here every state is scaled to its own unit:

- phasor: initial state 0 with standard deviation ``amplitude`` (the signal scale); process noise
  a small fraction of the amplitude per sample, so unmodelled content does not freeze the phasor;
- omega: initial standard deviation 25 % of the guess omega0 (so a guess 20 % off lies within one
  sigma), process noise that lets omega wander by 0.01 % of omega0 per period: small enough that
  the estimate of a ring-down stays close to the Cramer-Rao bound once the signal has faded into
  the noise, large enough to keep following a slow drift (and a re-tune) instead of freezing;
- sigma: initial 0 with standard deviation 10 % of omega0 (damping ratios up to ~0.2 within two
  sigma), process noise 0.001 % of omega0 per period: sigma is itself small (zeta omega), and a
  larger random walk spoils the lightly damped case (zeta = 0.005: 0.01 % per period wanders by
  6 % of sigma in ten periods);
- R: the measurement noise variance, by default (0.1 amplitude)^2, a 17 dB SNR, slightly
  pessimistic for the usual sensors; an over-estimate costs a little speed, an under-estimate makes
  the filter trust the noise.

Missing samples (``None``, NaN or +-inf) skip the update of eqs. (17)-(19) but not the prediction, so the
time base stays aligned; they are counted in ``missing``. If a step leaves a non-finite state or
covariance, or a frequency outside (0, pi fs) where eq. (24) aliases, the filter goes back to its
last good estimate with the initial covariance, counts it in ``resets`` and sets ``reset_last``.

Re-acquisition. With the small process noise above, a filter that has converged cannot follow a
sudden change of the mode (a new payload, a new ring-down at another frequency): its covariance
says it is sure. The normalised innovation squared nu^2 / (H P- H^T + R), which averages 1 for a
consistent filter, is therefore averaged over one period (exponential forgetting); when the
average exceeds ``nis_limit`` (default 9: innovations three times larger than the filter expects,
sustained) the covariance is set back to its initial value around the current estimate, and the
filter pulls in again as from a fresh guess. Counted in ``reacquisitions``.
"""

import math
from collections import deque

from .checks import check_count, check_finite, check_positive

# Process-noise and initial-uncertainty fractions of default_tuning (see the module docstring).
P0_OMEGA = 0.25
P0_SIGMA = 0.1
Q_PHASOR = 1e-3
Q_OMEGA_PER_PERIOD = 1e-4
Q_SIGMA_PER_PERIOD = 1e-5
R_AMPLITUDE = 0.1


def default_tuning(fs, omega0, amplitude=1.0):
    """Initial variances ``p0``, per-sample process variances ``q`` and measurement variance ``r``.

    Returns ``(p0, q, r)`` with ``p0`` and ``q`` lists of 4 variances for (x1, x2, omega, sigma);
    see the module docstring for the reasoning behind each number.
    """
    fs = check_positive(fs, "fs")
    omega0 = check_positive(omega0, "omega0")
    amplitude = check_positive(amplitude, "amplitude")
    samples_per_period = 2.0 * math.pi * fs / omega0
    # A random walk of per-sample variance v moves by sqrt(v * N) in N samples: spread the allowed
    # drift per period over the samples of one period.
    q_omega = (Q_OMEGA_PER_PERIOD * omega0) ** 2 / samples_per_period
    q_sigma = (Q_SIGMA_PER_PERIOD * omega0) ** 2 / samples_per_period
    p0 = [amplitude**2, amplitude**2, (P0_OMEGA * omega0) ** 2, (P0_SIGMA * omega0) ** 2]
    q = [(Q_PHASOR * amplitude) ** 2, (Q_PHASOR * amplitude) ** 2, q_omega, q_sigma]
    return p0, q, (R_AMPLITUDE * amplitude) ** 2


def _variances(values, name):
    if len(values) != 4:
        raise ValueError(f"{name} must hold 4 variances (x1, x2, omega, sigma), got {len(values)}")
    out = [check_finite(v, name) for v in values]
    for v in out:
        if v < 0.0:
            raise ValueError(f"{name} variances must be >= 0, got {v!r}")
    return out


def _diagonal(variances):
    return [[variances[i] if i == j else 0.0 for j in range(4)] for i in range(4)]


class ResonanceEKF:
    """The 4-state EKF of paper 001: ``step(y)`` once per sample, estimates in ``omega``/``sigma``.

    Parameters: ``fs`` sampling frequency (Hz, > 0); ``omega0`` initial damped-frequency guess
    (rad/s, in (0, pi fs)); ``sigma0`` initial decay-rate guess (1/s); ``amplitude`` the signal
    scale the defaults are relative to; ``phase`` the reference phase phi of eq. (26); ``p0``,
    ``q`` (4 variances each) and ``r`` override ``default_tuning``; convergence is declared when
    the standard deviations of omega and sigma, relative to omega, are below ``omega_tol`` and
    ``sigma_tol`` and omega and sigma have moved by less than those tolerances (times omega) over
    the last ``window`` samples (default: one period at omega0); ``nis_limit`` triggers
    re-acquisition (module docstring).
    """

    def __init__(
        self,
        fs,
        omega0,
        sigma0=0.0,
        amplitude=1.0,
        phase=0.0,
        p0=None,
        q=None,
        r=None,
        omega_tol=2e-3,
        sigma_tol=5e-3,
        window=None,
        nis_limit=9.0,
    ):
        self.fs = check_positive(fs, "fs")
        omega0 = check_positive(omega0, "omega0")
        if omega0 >= math.pi * self.fs:
            raise ValueError(f"omega0 must be in (0, pi*fs) = (0, {math.pi * self.fs:g}) rad/s, got {omega0!r}")
        sigma0 = check_finite(sigma0, "sigma0")
        amplitude = check_positive(amplitude, "amplitude")
        phase = check_finite(phase, "phase")
        d_p0, d_q, d_r = default_tuning(self.fs, omega0, amplitude)
        self.p0 = d_p0 if p0 is None else _variances(p0, "p0")
        self.q = d_q if q is None else _variances(q, "q")
        self.r = d_r if r is None else check_positive(r, "r")
        self.omega_tol = check_positive(omega_tol, "omega_tol")
        self.sigma_tol = check_positive(sigma_tol, "sigma_tol")
        if window is None:
            window = max(2, round(2.0 * math.pi * self.fs / omega0))
        self.window = check_count(window, "window", minimum=2)
        self.nis_limit = check_positive(nis_limit, "nis_limit")
        self._nis = 1.0
        self.dt = 1.0 / self.fs
        # H of eq. (26), as derived in the module docstring.
        self.h1 = math.cos(phase)
        self.h2 = math.sin(phase)
        self.x = [0.0, 0.0, omega0, sigma0]
        self.P = _diagonal(self.p0)
        self._good = (list(self.x), [row[:] for row in self.P])
        self._recent = deque(maxlen=self.window)
        self.samples = 0
        self.missing = 0
        self.resets = 0
        self.reset_last = False
        self.reacquisitions = 0

    # -- the two halves of the EKF -------------------------------------------------------------

    def predict(self):
        """Eqs. (15)-(16): propagate the state through eq. (24) and the covariance through F."""
        x1, x2, omega, sigma = self.x
        dt = self.dt
        decay = math.exp(-sigma * dt)
        c = decay * math.cos(omega * dt)
        s = decay * math.sin(omega * dt)
        f1 = c * x1 + s * x2  # eq. (24), first row
        f2 = -s * x1 + c * x2  # eq. (24), second row
        # Jacobian F of eq. (13) for eq. (24); rows 3 and 4 are the identity (random walks).
        # d f1/d omega = dt f2, d f2/d omega = -dt f1, d f/d sigma = -dt f.
        F1 = (c, s, dt * f2, -dt * f1)
        F2 = (-s, c, -dt * f1, -dt * f2)
        P = self.P
        # A = F P, then F A^T; only the first two rows of F differ from the identity.
        A1 = [F1[0] * P[0][j] + F1[1] * P[1][j] + F1[2] * P[2][j] + F1[3] * P[3][j] for j in range(4)]
        A2 = [F2[0] * P[0][j] + F2[1] * P[1][j] + F2[2] * P[2][j] + F2[3] * P[3][j] for j in range(4)]
        A3, A4 = P[2], P[3]
        q = self.q
        p11 = A1[0] * F1[0] + A1[1] * F1[1] + A1[2] * F1[2] + A1[3] * F1[3] + q[0]
        p12 = A1[0] * F2[0] + A1[1] * F2[1] + A1[2] * F2[2] + A1[3] * F2[3]
        p22 = A2[0] * F2[0] + A2[1] * F2[1] + A2[2] * F2[2] + A2[3] * F2[3] + q[1]
        p13, p14 = A1[2], A1[3]
        p23, p24 = A2[2], A2[3]
        p33, p34, p44 = A3[2] + q[2], A3[3], A4[3] + q[3]
        self.x = [f1, f2, omega, sigma]  # eq. (15)
        self.P = [  # eq. (16): P- = F P F^T + Q
            [p11, p12, p13, p14],
            [p12, p22, p23, p24],
            [p13, p23, p33, p34],
            [p14, p24, p34, p44],
        ]

    def update(self, z):
        """Eqs. (17)-(19) for the scalar measurement z = h1 x1 + h2 x2 + n (eq. 26)."""
        P = self.P
        h1, h2 = self.h1, self.h2
        pht = [h1 * P[i][0] + h2 * P[i][1] for i in range(4)]  # P- H^T
        innovation_var = h1 * pht[0] + h2 * pht[1] + self.r  # H P- H^T + R
        K = [v / innovation_var for v in pht]  # eq. (17)
        innovation = z - (h1 * self.x[0] + h2 * self.x[1])  # z - H m-, eq. (18)
        self.x = [xi + ki * innovation for xi, ki in zip(self.x, K)]  # eq. (18)
        self._nis += (innovation * innovation / innovation_var - self._nis) / self.window
        # eq. (19), (I - K H) P-, written as P- - K S K^T (H P- = S K^T): symmetric by construction,
        # so rounding cannot make P lose its symmetry over millions of steps.
        self.P = [[P[i][j] - pht[i] * K[j] for j in range(4)] for i in range(4)]

    def step(self, z):
        """One sample: predict, then update unless ``z`` is None or not finite. Returns True if updated."""
        self.samples += 1
        self.predict()
        # NaN (and +-inf, a broken sample rather than a measurement) count as missing.
        measured = z is not None and math.isfinite(z)
        if measured:
            self.update(float(z))
        else:
            self.missing += 1
        self.reset_last = not self._healthy()
        if self.reset_last:
            # Back to the last good estimate, with the initial covariance so that the filter can
            # re-acquire instead of repeating the step that failed.
            self.resets += 1
            self.x = list(self._good[0])
            self.P = _diagonal(self.p0)
            self._recent.clear()
        else:
            if self._nis > self.nis_limit:
                # The data contradict the model for a period: re-acquire (see the module docstring).
                self.reacquisitions += 1
                self.P = _diagonal(self.p0)
                self._nis = 1.0
                self._recent.clear()
            self._good = (list(self.x), [row[:] for row in self.P])
            self._recent.append((self.x[2], self.x[3]))
        return measured and not self.reset_last

    def restart_phasor(self):
        """A new ring-down begins: the plant was driven while the filter did not watch, so the
        amplitude and phase of what it now sees are unknown. The phasor (x1, x2) goes back to 0 with
        its initial variance and no correlation with omega and sigma, which keep their estimates and
        variances: what the filter learnt of the mode survives a move, what it knew of the last ring
        does not."""
        self.x[0] = self.x[1] = 0.0
        for i in (0, 1):
            for j in range(4):
                self.P[i][j] = self.P[j][i] = 0.0
            self.P[i][i] = self.p0[i]

    def _healthy(self):
        values = self.x + [v for row in self.P for v in row]
        if not all(math.isfinite(v) for v in values):
            return False
        if any(self.P[i][i] < 0.0 for i in range(4)):
            return False
        return 0.0 < self.x[2] < math.pi * self.fs

    # -- estimates -------------------------------------------------------------------------------

    @property
    def omega_d(self):
        """Damped frequency estimate (rad/s), the state x3."""
        return self.x[2]

    @property
    def sigma(self):
        """Decay-rate estimate (1/s), the state x4."""
        return self.x[3]

    @property
    def omega_n(self):
        """Undamped natural frequency sqrt(sigma^2 + omega_d^2) (rad/s)."""
        return math.hypot(self.x[2], self.x[3])

    @property
    def zeta(self):
        """Damping ratio sigma / sqrt(sigma^2 + omega_d^2)."""
        return self.x[3] / math.hypot(self.x[2], self.x[3])

    @property
    def omega_std(self):
        """Standard deviation of the frequency estimate from the covariance (rad/s)."""
        return math.sqrt(max(self.P[2][2], 0.0))

    @property
    def sigma_std(self):
        """Standard deviation of the decay-rate estimate from the covariance (1/s)."""
        return math.sqrt(max(self.P[3][3], 0.0))

    @property
    def omega_converged(self):
        """Standard deviation of omega below ``omega_tol`` times omega, and omega steady within that
        over the last window."""
        return self._steady(2, 0, self.omega_tol)

    @property
    def sigma_converged(self):
        """Standard deviation of sigma below ``sigma_tol`` times omega, and sigma steady within that
        over the last window."""
        return self._steady(3, 1, self.sigma_tol)

    @property
    def converged(self):
        """Covariance of omega and sigma small and both estimates stable over the last window."""
        return self.omega_converged and self.sigma_converged

    def _steady(self, state, column, tol):
        bound = tol * self.x[2]
        if math.sqrt(max(self.P[state][state], 0.0)) > bound or len(self._recent) < self.window:
            return False
        recent = [pair[column] for pair in self._recent]
        return max(recent) - min(recent) <= bound
