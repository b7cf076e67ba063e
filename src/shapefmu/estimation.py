"""Resonance estimation from a vibration signal, and input shaping tuned by it (paper 001).

The per-sample work is the runtime EKF (``shapefmu.runtime.ekf``, eqs. 15-26 of the paper, with the
sign of eq. 25 corrected as derived there); this module validates input, chooses the signal scale,
and returns results as objects with named fields:

- ``estimate_mode(y, fs, omega0)``: one recorded signal in, a ``ModeEstimate`` out;
- ``ModeEstimator``: the same estimator fed one sample at a time;
- ``EKFTunedShaper``: watches a vibration signal and shapes commands with a shaper designed for the
  converged estimate (runtime kernel ``shapefmu.runtime.ekf_tuner``);
- ``TrackedShaper``: keeps a shaper on a mode that moves (a bed gaining mass), the EKF watching the
  plant ring after the machine's own moves, re-designed without a jump (``runtime.tracked_shaper``).

Damping from the estimate: the EKF tracks the damped frequency omega_d and the decay rate sigma of
eq. (20); for a mode e^{-zeta omega_n t} sin(omega_d t), sigma = zeta omega_n and
omega_d = omega_n sqrt(1 - zeta^2) (eq. 28), so omega_n = sqrt(sigma^2 + omega_d^2) and
zeta = sigma / sqrt(sigma^2 + omega_d^2). The log-decrement of eq. (31)
(``shapefmu.analysis.log_decrement_damping``) is the independent check, ``log_decrement_zeta``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from shapefmu.analysis import log_decrement_damping
from shapefmu.runtime.checks import check_count, check_finite, check_positive
from shapefmu.runtime.ekf import ResonanceEKF
from shapefmu.runtime.ekf_tuner import KINDS, EKFTunedShaperKernel
from shapefmu.runtime.tracked_shaper import TrackedShaperKernel, tracking_tuning
from shapefmu.runtime.units import RadPerSecond
from shapefmu.shapers import ImpulseShaper

__all__ = [
    "EKFTunedShaper",
    "ModeEstimate",
    "ModeEstimator",
    "TrackedShaper",
    "estimate_mode",
    "log_decrement_zeta",
]


@dataclass(frozen=True)
class ModeEstimate:
    """An estimated mode: damped frequency ``omega_d`` (rad/s), decay rate ``sigma`` (1/s),
    natural frequency ``omega_n`` (rad/s) and damping ratio ``zeta``.

    ``history`` is an (N, 2) array of (omega_d, sigma) after each sample; ``converged`` is the
    EKF's convergence test at the last sample (covariance of omega and sigma below threshold and
    both stable over the last period); ``missing`` counts the samples skipped as None/NaN and
    ``resets`` the steps after which the filter had to return to its last good estimate.

    Examples
    --------
    >>> import numpy as np
    >>> e = ModeEstimate(62.8, 1.26, 62.81, 0.02, np.empty((0, 2)), True)
    >>> e.zeta, e.converged, e.missing
    (0.02, True, 0)
    """

    omega_d: float
    sigma: float
    omega_n: float
    zeta: float
    history: np.ndarray
    converged: bool
    missing: int = 0
    resets: int = 0


def _check_matrix_diagonal(values, name):
    """Q or P0 given as 4 variances, a 4x4 (diagonal used) matrix, or a scalar times I."""
    a = np.asarray(values, dtype=float)
    if a.ndim == 0:
        a = np.full(4, float(a))
    elif a.shape == (4, 4):
        a = np.diag(a)
    if a.shape != (4,):
        raise ValueError(f"{name} must be a scalar, 4 variances or a 4x4 matrix, got shape {a.shape}")
    if not np.all(np.isfinite(a)) or np.any(a < 0):
        raise ValueError(f"{name} must be finite and >= 0, got {a.tolist()}")
    return [float(v) for v in a]


def _ekf_options(fs, omega0, sigma0, amplitude, q, r, p0, omega_tol, sigma_tol):
    fs = check_positive(fs, "fs")
    omega0 = check_positive(omega0, "omega0")
    options = {
        "sigma0": check_finite(sigma0, "sigma0"),
        "amplitude": check_positive(amplitude, "amplitude"),
        "omega_tol": check_positive(omega_tol, "omega_tol"),
        "sigma_tol": check_positive(sigma_tol, "sigma_tol"),
    }
    if q is not None:
        options["q"] = _check_matrix_diagonal(q, "q")
    if r is not None:
        options["r"] = check_positive(r, "r")
    if p0 is not None:
        options["p0"] = _check_matrix_diagonal(p0, "p0")
    return fs, omega0, options


def _signal(y) -> np.ndarray:
    y = np.asarray(y, dtype=float).ravel()
    if y.size == 0:
        raise ValueError("y must hold at least one sample, got an empty signal")
    return y


def _signal_scale(y: np.ndarray) -> float:
    """Largest finite |y|: for a ring-down, its initial amplitude, the unit of the EKF's tuning."""
    finite = np.abs(y[np.isfinite(y)])
    peak = float(finite.max()) if finite.size else 0.0
    if peak <= 0.0:
        raise ValueError("y must contain a finite non-zero sample to set the amplitude scale; pass amplitude=")
    return peak


def _run(ekf: ResonanceEKF, y: np.ndarray) -> np.ndarray:
    history = np.empty((y.size, 2))
    for k, sample in enumerate(y.tolist()):
        ekf.step(sample)
        history[k] = ekf.x[2], ekf.x[3]
    return history


def estimate_mode(
    y,
    fs: float,
    omega0: RadPerSecond,
    sigma0: float = 0.0,
    *,
    amplitude: float | None = None,
    q=None,
    r: float | None = None,
    p0=None,
    passes: int = 2,
    omega_tol: float = 2e-3,
    sigma_tol: float = 5e-3,
) -> ModeEstimate:
    """Estimate the dominant decaying mode in ``y`` (sampled at ``fs`` Hz) with the EKF.

    ``omega0`` is the initial guess of the damped frequency (rad/s) and ``sigma0`` of the decay rate
    (1/s). ``amplitude`` (default: the largest finite |y|) is the scale of the default tuning
    (``runtime.ekf.default_tuning``); ``q`` (4 variances or a 4x4 matrix), ``r`` and ``p0`` override
    it. NaN samples are skipped and counted.

    ``passes``: with 2 (the default) the record is run through the filter a second time, started
    from the first pass's estimate. The first pass spends the early, strongest part of a ring-down
    pulling in from a guess up to 20 % off, where the linearisation of eq. (13) is poor; the second
    starts within the linear range and uses all of it, bringing the frequency error of a heavily
    damped ring-down (zeta = 0.1) from about twice to within a few percent of the Cramer-Rao bound.
    Use 1 for exactly what the streaming ``ModeEstimator`` would report at the end of the record.

    Examples
    --------
    >>> import math, numpy as np
    >>> fs, t, omega_d = 1000.0, np.arange(2000) / 1000.0, 2 * math.pi * 10.0 * math.sqrt(1 - 0.02**2)
    >>> y = np.exp(-2 * math.pi * 10.0 * 0.02 * t) * np.cos(omega_d * t)  # 10 Hz, 2 % damping, 2 s at 1 kHz
    >>> e = estimate_mode(y, fs, 0.9 * omega_d)  # from a guess 10 % low
    >>> round(e.omega_n / (2 * math.pi), 3), round(e.zeta, 3), e.converged
    (10.0, 0.02, True)
    """
    fs, omega0, options = _ekf_options(fs, omega0, sigma0, 1.0 if amplitude is None else amplitude, q, r, p0,
                                       omega_tol, sigma_tol)
    y = _signal(y)
    passes = check_count(passes, "passes", minimum=1)
    if amplitude is None:
        options["amplitude"] = _signal_scale(y)
    ekf = ResonanceEKF(fs, omega0, **options)
    history = _run(ekf, y)
    missing, resets = ekf.missing, ekf.resets
    for _ in range(passes - 1):
        options["sigma0"] = ekf.sigma
        ekf = ResonanceEKF(fs, ekf.omega_d, **options)
        history = _run(ekf, y)
        resets += ekf.resets
    return ModeEstimate(ekf.omega_d, ekf.sigma, ekf.omega_n, ekf.zeta, history, ekf.converged, missing, resets)


class ModeEstimator:
    """Streaming mode estimator: ``update(sample)`` once per sample, estimates always current.

    Same parameters as ``estimate_mode`` except that ``amplitude`` (the expected signal scale, which
    a stream cannot look ahead for) defaults to 1.

    Examples
    --------
    >>> import math, numpy as np
    >>> fs, t, omega_d = 1000.0, np.arange(2000) / 1000.0, 2 * math.pi * 10.0 * math.sqrt(1 - 0.02**2)
    >>> y = np.exp(-2 * math.pi * 10.0 * 0.02 * t) * np.cos(omega_d * t)  # 10 Hz, 2 % damping, 2 s at 1 kHz
    >>> estimator = ModeEstimator(fs, 0.9 * omega_d)
    >>> converged = [estimator.update(sample) for sample in y]
    >>> converged[-1], round(estimator.estimate().omega_n / (2 * math.pi), 2)
    (True, 10.0)
    """

    def __init__(self, fs: float, omega0: RadPerSecond, sigma0: float = 0.0, *, amplitude: float = 1.0, q=None,
                 r: float | None = None, p0=None, omega_tol: float = 2e-3, sigma_tol: float = 5e-3,
                 record: bool = True):
        fs, omega0, options = _ekf_options(fs, omega0, sigma0, amplitude, q, r, p0, omega_tol, sigma_tol)
        self.ekf = ResonanceEKF(fs, omega0, **options)
        self._history = [] if record else None

    def update(self, sample) -> bool:
        """Feed one sample (None or NaN: missing). Returns True if the estimate has converged."""
        self.ekf.step(sample)
        if self._history is not None:
            self._history.append((self.ekf.x[2], self.ekf.x[3]))
        return self.ekf.converged

    @property
    def converged(self) -> bool:
        return self.ekf.converged

    @property
    def reset_last(self) -> bool:
        """True if the last sample made the filter diverge and return to its last good estimate."""
        return self.ekf.reset_last

    def estimate(self) -> ModeEstimate:
        """The current estimate, with the recorded history (empty if ``record=False``)."""
        e = self.ekf
        history = np.array(self._history if self._history else np.empty((0, 2)), dtype=float).reshape(-1, 2)
        return ModeEstimate(e.omega_d, e.sigma, e.omega_n, e.zeta, history, e.converged, e.missing, e.resets)


def log_decrement_zeta(y, fs: float, omega_d: RadPerSecond, periods: int | None = None) -> float:
    """Damping ratio of a ring-down by the log-decrement of eq. (31), from its positive peaks.

    Peaks are taken one per damped period (2 pi / omega_d) from the start of ``y``, each refined by
    a parabola through the three samples around it; ``periods`` limits how many are used. An
    estimate independent of the EKF, for checking it.

    Examples
    --------
    >>> import math, numpy as np
    >>> fs, t, omega_d = 1000.0, np.arange(2000) / 1000.0, 2 * math.pi * 10.0 * math.sqrt(1 - 0.02**2)
    >>> y = np.exp(-2 * math.pi * 10.0 * 0.02 * t) * np.cos(omega_d * t)  # 10 Hz, 2 % damping, 2 s at 1 kHz
    >>> round(log_decrement_zeta(y, fs, omega_d), 3)
    0.02
    """
    y = _signal(y)
    fs = check_positive(fs, "fs")
    omega_d = check_positive(omega_d, "omega_d")
    per = 2.0 * math.pi * fs / omega_d
    count = int(y.size // per)
    if periods is not None:
        count = min(count, check_count(periods, "periods", minimum=2))
    if count < 2:
        raise ValueError(f"y must span at least 2 periods of omega_d = {omega_d:g} rad/s, got {y.size / per:.2f}")
    peaks = []
    for i in range(count):
        lo, hi = int(round(i * per)), int(round((i + 1) * per))
        k = lo + int(np.argmax(y[lo:hi]))
        if 0 < k < y.size - 1:
            a, b, c = y[k - 1], y[k], y[k + 1]
            curvature = a - 2.0 * b + c
            peaks.append(b - 0.125 * (c - a) ** 2 / curvature if curvature < 0 else b)
        else:
            peaks.append(y[k])
    return log_decrement_damping(peaks)


ShaperDesign = Callable[[float, float], ImpulseShaper]


class EKFTunedShaper:
    """Shape commands with a shaper designed for the resonance an EKF finds in a vibration signal.

    ``shaper`` is one of the runtime kinds ``"zv"``, ``"zvd"``, ``"zvdd"``, ``"zv_dn"`` (with
    ``n``), ``"mzv"``, or any callable ``(omega_n, zeta) -> ImpulseShaper`` from
    ``shapefmu.shapers`` (e.g. ``shapers.ei``). Until the estimate has converged commands pass
    through unshaped; a new design is switched in when the command rests (see
    ``shapefmu.runtime.ekf_tuner`` for why). Same EKF options as ``ModeEstimator``.

    Examples
    --------
    >>> import math, numpy as np
    >>> fs, t, omega_d = 1000.0, np.arange(2000) / 1000.0, 2 * math.pi * 10.0 * math.sqrt(1 - 0.02**2)
    >>> y = np.exp(-2 * math.pi * 10.0 * 0.02 * t) * np.cos(omega_d * t)  # 10 Hz, 2 % damping, 2 s at 1 kHz
    >>> tuner = EKFTunedShaper(fs, 0.9 * omega_d)  # ZVD for what the EKF finds
    >>> shaped = tuner.run(np.zeros(y.size), y)
    >>> tuner.designs, len(tuner.shaper), round(tuner.shaper.duration, 3)  # one damped period
    (1, 3, 0.1)
    """

    def __init__(
        self,
        fs: float,
        omega0: RadPerSecond,
        shaper: str | ShaperDesign = "zvd",
        *,
        n: int = 1,
        retune_fraction: float = 0.05,
        sigma0: float = 0.0,
        amplitude: float = 1.0,
        q=None,
        r: float | None = None,
        p0=None,
        omega_tol: float = 2e-3,
        sigma_tol: float = 5e-3,
    ):
        fs, omega0, options = _ekf_options(fs, omega0, sigma0, amplitude, q, r, p0, omega_tol, sigma_tol)
        if callable(shaper):
            design = shaper

            def kind(omega_n: RadPerSecond, zeta):
                s = design(omega_n, zeta)
                return list(s.times), list(s.amplitudes)

        elif shaper in KINDS:
            kind = shaper
        else:
            raise ValueError(f"shaper must be one of {', '.join(KINDS)} or a callable, got {shaper!r}")
        self.kernel = EKFTunedShaperKernel(fs, omega0, kind, n=n, retune_fraction=retune_fraction, **options)

    def step(self, command: float, measurement) -> float:
        """Observe one vibration sample (None/NaN: missing), return the shaped command."""
        return self.kernel.step(float(command), measurement)

    def run(self, commands, measurements) -> np.ndarray:
        """Step through two equally long sequences; returns the shaped commands."""
        u = np.asarray(commands, dtype=float).ravel()
        m = np.asarray(measurements, dtype=float).ravel()
        if u.shape != m.shape:
            raise ValueError(f"commands and measurements must have equal length, got {u.size} and {m.size}")
        return np.array([self.kernel.step(a, b) for a, b in zip(u.tolist(), m.tolist())])

    @property
    def shaper(self) -> ImpulseShaper | None:
        """The shaper in use (None while commands still pass through unshaped)."""
        if self.kernel.impulses is None:
            return None
        return ImpulseShaper.from_impulses(*self.kernel.impulses)

    @property
    def pending(self) -> bool:
        """True if a new design waits for the command to rest before it is switched in."""
        return self.kernel.pending is not None

    @property
    def designs(self) -> int:
        """How many shapers have been designed (the first design plus re-tunes)."""
        return self.kernel.designs

    def estimate(self) -> ModeEstimate:
        """The EKF's current estimate (no history)."""
        e = self.kernel.ekf
        return ModeEstimate(e.omega_d, e.sigma, e.omega_n, e.zeta, np.empty((0, 2)), e.converged, e.missing, e.resets)


@dataclass(frozen=True)
class TrackedShaper:
    """A shaper of ``kind`` kept on a mode that moves by the EKF of paper 001, no calibration run:
    the EKF watches the plant ring freely between changes of the machine's own shaped commands (about
    the equilibrium ``gain`` times the command; without a gain, only at ``rest``), and the shaper is
    re-designed for its last good estimate without a jump in the shaped command.

    ``fs`` sampling frequency (Hz); ``omega0`` (rad/s) and ``zeta0`` the guess the shaper starts
    with; ``noise`` the standard deviation of the measurement and ``amplitude`` the scale of the rings
    it will show (the measurement's unit); ``drift`` the relative frequency change per square root of a
    period the EKF is ready to follow (``runtime.tracked_shaper.tracking_tuning``). An estimate is taken
    when the EKF's standard deviation of omega is below ``omega_tol`` times omega (of sigma, below
    ``sigma_tol`` times omega) and steady over a period, and omega lies in ``band`` times ``omega0``.
    The per-sample kernel, what a tracked-shaper FMU will run, is ``kernel()``; the derivation of the
    watching and the convergence test is in ``shapefmu.runtime.tracked_shaper``.

    >>> import math
    >>> tracker = TrackedShaper(fs=2000.0, omega0=2 * math.pi * 27.0, noise=0.05, amplitude=2.0, zeta0=0.05)
    >>> kernel = tracker.kernel()
    >>> [round(x, 3) for x in kernel.mode]   # the design point starts at the guess
    [169.646, 0.05]
    >>> round(kernel.step(1.0, 0.0), 4), kernel.watching   # the plant rested before this sample
    (0.5392, True)
    >>> round(kernel.step(1.0, 0.0), 4), kernel.watching   # a move has begun: the EKF looks away
    (0.5392, False)
    """

    fs: float
    omega0: RadPerSecond
    noise: float
    amplitude: float
    zeta0: float = 0.0
    kind: str = "zv"
    n: int = 1
    vtol: float = 0.05
    drift: float = 1e-3
    gain: float | None = None
    rest: float = 0.0
    band: tuple[float, float] = (0.5, 2.0)
    zeta_max: float = 0.5
    omega_tol: float = 1e-2
    sigma_tol: float = 4e-3
    resolution: float = 1e-3

    def __post_init__(self):
        self.kernel()  # the kernel checks every field

    def kernel(self, u0: float = 0.0) -> TrackedShaperKernel:
        """The per-sample kernel, the command resting at ``u0`` before the first sample."""
        p0, q, r = tracking_tuning(self.fs, self.omega0, self.amplitude, self.noise, self.drift)
        return TrackedShaperKernel(self.fs, self.omega0, self.zeta0, self.kind, self.n, self.vtol, self.gain, self.rest,
                                   u0, tuple(self.band), self.zeta_max, self.resolution, p0=p0, q=q, r=r,
                                   omega_tol=self.omega_tol, sigma_tol=self.sigma_tol)
