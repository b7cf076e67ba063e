"""What a shaper costs and what it leaves on the measured spectrum, by Klipper's definitions, evaluated
for many designs at once: remaining vibration, smoothing, max_accel and score.

Each definition is Klipper's (``klippy/extras/shaper_calibrate.py`` at commit 84104bbb, the functions
named below; Klipper's docs/Measuring_Resonances.md describes what they mean), re-derived here and
checked in the tests against the figures Klipper's own functions print for the development recordings
(1e-6 relative, pinned with the commit). Nothing here is Klipper's code.

Remaining vibration (``_estimate_remaining_vibrations``). A shaper with impulses A_i at T_i leaves, of a
mode (f, zeta) excited by a move, the share

    V(f, zeta) = |sum_i A_i exp(-zeta w (T_n - T_i)) exp(j w sqrt(1 - zeta^2) T_i)| / sum_i A_i,  w = 2 pi f

(Singer and Seering's percent residual vibration, measured from the last impulse T_n). On a spectrum
P(f), cut at ``MAX_FREQ`` (``fit_shaper``: max(200 Hz, the shaper's frequency)), with the threshold
T = max P / 20 (``SHAPER_VIBRATION_REDUCTION``: what a shaper can reduce a resonance by), the share of
the spectrum above T that the shaper leaves at one damping is

    R(zeta) = sum_f max(P(f) V(f, zeta) - T, 0) / sum_f max(P(f) - T, 0),

and the remaining vibration is the worst R(zeta) over the test dampings 0.075, 0.1 and 0.15 (and over
the spectra, when several are judged together). Note the order: the worst of the per-damping shares,
not the share of a per-bin worst V.

Smoothing (``_get_shaper_smoothing``). With t_c = sum A_i T_i / sum A the shaper's centre,
d_i = T_i - t_c, the acceleration a and the square-corner velocity v, the toolhead's deviation at a
90-degree corner counts the impulses at or after t_c, at a 180-degree reversal all of them:

    s90 = sqrt(2) sum_{T_i >= t_c} A_i (v + a d_i / 2) d_i / sum A,   s180 = sum_i A_i a d_i^2 / 2 / sum A,

and the smoothing is max(s90, s180), at a = 5000 mm/s^2 and v = 5 mm/s by default.

max_accel (``find_shaper_max_accel``): the largest a with smoothing <= 0.12 mm. Klipper bisects to
1e-8 mm/s^2; both terms are linear in a, so it is the closed form min of the two lines' crossings
(equal to the bisection to about 1e-12 relative), 0 when v alone exceeds the bound.

Score (``fit_shaper``): smoothing (at 5000 mm/s^2) * (R^1.5 + 0.2 R + 0.01), which Klipper's own
comment calls empirical; it ranks frequencies and shapers in Klipper's pick.
"""

from __future__ import annotations

import math

import numpy as np

THRESHOLD_SHARE = 1 / 20  # T = max P / 20 (SHAPER_VIBRATION_REDUCTION)
KLIPPER_DAMPINGS = (0.075, 0.1, 0.15)  # TEST_DAMPING_RATIOS
MAX_FREQ = 200.0  # Hz: the spectrum judged ends here (MAX_FREQ), or at the shaper's frequency if higher
DEFAULT_SCV = 5.0  # mm/s, square-corner velocity
DEFAULT_ACCEL = 5000.0  # mm/s^2, where smoothing and the score are taken
DEFAULT_MAX_SMOOTHING = 0.12  # mm, TARGET_SMOOTHING of find_shaper_max_accel


def residual(times, amplitudes, freq, dampings) -> np.ndarray:
    """V (module docstring) of impulse sets at frequencies and dampings.

    ``times`` and ``amplitudes`` are (..., n) arrays (a batch of designs), ``freq`` (m,) Hz, ``dampings``
    (z,); returns (..., m, z). Measured from the last impulse, as Klipper does, so nothing overflows.

    >>> float(residual([0.0, 0.01], [1.0, 1.0], [50.0], [0.0])[0, 0]) < 1e-12  # ZV at 50 Hz
    True
    """
    t = np.asarray(times, dtype=float)[..., None, None, :]
    a = np.asarray(amplitudes, dtype=float)[..., None, None, :]
    w = 2 * np.pi * np.asarray(freq, dtype=float)[:, None, None]
    z = np.asarray(dampings, dtype=float)[None, :, None]
    last = t[..., -1:]
    terms = a * np.exp(z * w * (t - last) + 1j * w * np.sqrt(1 - z * z) * t)
    return np.abs(terms.sum(axis=-1)) / np.abs(a.sum(axis=-1))


def residual_sampled(taps, ts: float, freq, dampings) -> np.ndarray:
    """``residual`` of taps at k ts, (m, z): sum_k a_k e^{(zeta w + j w_d)(t_k - t_N)} by Horner's rule in
    w = e^{-(zeta w + j w_d) ts} (|w| <= 1, so nothing overflows), one complex multiply-add per tap
    instead of an exponential.

    >>> float(residual_sampled([1.0, 1.0], 0.01, [50.0], [0.0])[0, 0]) < 1e-12
    True
    """
    taps = np.asarray(taps, dtype=float)
    w = 2 * np.pi * np.asarray(freq, dtype=float)[:, None]
    z = np.asarray(dampings, dtype=float)[None, :]
    step = np.exp(-(z * w + 1j * w * np.sqrt(1 - z * z)) * ts)
    total = np.zeros(step.shape, dtype=complex)
    for tap in taps:
        total = total * step + tap
    return np.abs(total) / abs(taps.sum())


class VibrationMeter:
    """Klipper's remaining vibration (module docstring) on one spectrum, prepared once and applied to
    batches of V.

    ``max_freq`` is where the spectrum is cut (Klipper: max(200 Hz, the shaper's frequency)).
    ``max_gain`` bounds V over the designs judged (1 for impulses of one sign, |V| <= 1): a bin with
    P max_gain <= T can never count and is left out before any work.

    >>> meter = VibrationMeter([10.0, 20.0, 30.0], [1.0, 10.0, 1.0])
    >>> round(float(meter.remaining(np.full((3, 1), 0.5))), 12)  # T = 0.5: (5 - 0.5) / (0.5 + 9.5 + 0.5)
    0.428571428571
    """

    def __init__(self, freq, psd, dampings=KLIPPER_DAMPINGS, max_freq: float = MAX_FREQ, max_gain: float = 1.0):
        freq, psd = np.asarray(freq, dtype=float), np.asarray(psd, dtype=float)
        within = freq <= max_freq
        freq, psd = freq[within], psd[within]
        if not freq.size or not np.all(np.isfinite(psd)) or float(psd.max()) <= 0:
            raise ValueError(f"the spectrum up to {max_freq:g} Hz must hold finite powers, some > 0, to judge a shaper on")
        self.threshold = float(psd.max()) * THRESHOLD_SHARE
        self.total = float(np.maximum(psd - self.threshold, 0).sum())
        keep = psd * max_gain > self.threshold
        self.freq, self.psd = freq[keep], psd[keep]
        self.dampings = tuple(float(z) for z in dampings)

    def remaining(self, v) -> np.ndarray:
        """R for V given at ``self.freq`` and ``self.dampings``, (..., m, z) -> (...): the worst over the
        dampings of the share left at each."""
        if self.total <= 0:  # a flat spectrum: nothing stands above the threshold
            return np.zeros(np.shape(v)[:-2])
        left = np.maximum(self.psd[:, None] * v - self.threshold, 0).sum(axis=-2)
        return left.max(axis=-1) / self.total


def _moments(times, amplitudes):
    """(sum A d, sum A d^2 over the impulses at or after the centre; sum A d^2 over all) / sum A."""
    t = np.asarray(times, dtype=float)
    a = np.asarray(amplitudes, dtype=float)
    gain = a.sum(axis=-1)
    d = t - (a * t).sum(axis=-1, keepdims=True) / gain[..., None]
    late = d >= 0
    return ((a * d * late).sum(axis=-1) / gain, (a * d * d * late).sum(axis=-1) / gain,
            (a * d * d).sum(axis=-1) / gain)


def smoothing(times, amplitudes, accel: float = DEFAULT_ACCEL, scv: float = DEFAULT_SCV) -> np.ndarray:
    """Klipper's smoothing (mm) of impulse sets (..., n) at ``accel`` (mm/s^2) and square-corner
    velocity ``scv`` (mm/s); module docstring.

    >>> float(smoothing([0.0, 0.01], [1.0, 1.0], 5000.0, 5.0))  # d = -+5 ms: s180 = 2500 * 2.5e-5 > s90
    0.0625
    """
    s1, s2_late, s2_all = _moments(times, amplitudes)
    return np.maximum(math.sqrt(2) * (scv * s1 + 0.5 * accel * s2_late), 0.5 * accel * s2_all)


def max_accel(times, amplitudes, max_smoothing: float = DEFAULT_MAX_SMOOTHING, scv: float = DEFAULT_SCV) -> np.ndarray:
    """The largest acceleration (mm/s^2) at which ``smoothing`` stays at or under ``max_smoothing``
    (0 if the square-corner velocity alone exceeds it): both terms are linear in a.

    >>> float(max_accel([0.0, 0.01], [1.0, 1.0]))  # the reversal binds: 2 * 0.12 / 2.5e-5
    9600.0
    """
    s1, s2_late, s2_all = _moments(times, amplitudes)
    with np.errstate(divide="ignore"):
        corner = (max_smoothing / math.sqrt(2) - scv * s1) * 2 / s2_late
        reversal = 2 * max_smoothing / s2_all
    return np.maximum(np.minimum(corner, reversal), 0.0)


def score(smoothing_mm, vibration) -> np.ndarray:
    """Klipper's score: smoothing * (R^1.5 + 0.2 R + 0.01).

    >>> round(float(score(0.1, 0.04)), 12)  # 0.1 (0.008 + 0.008 + 0.01)
    0.0026
    """
    v = np.asarray(vibration, dtype=float)
    return np.asarray(smoothing_mm, dtype=float) * (v**1.5 + 0.2 * v + 0.01)
