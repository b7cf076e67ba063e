"""What a shaper costs and what it leaves, on the measured spectrum: the metrics Klipper documents,
derived here from their definitions and evaluated for many designs at once.

Remaining vibration. A shaper with impulses A_i at t_i leaves, of a mode (f, zeta) excited by a
move, the share V(f, zeta) of its vibration (Singer and Seering's percent residual vibration,
``shapefmu.analysis.residual_vibration``). The measured spectrum P(f) says how much vibration the
machine has at each frequency. Klipper's definition of the vibration a shaper leaves: the share of
the spectrum above a noise threshold that survives the shaper, worst case over a set of damping
ratios,

    R = sum_f max(P(f) V_max(f) - T, 0) / sum_f max(P(f) - T, 0),   V_max(f) = max_zeta V(f, zeta),

with the threshold T = max P / 20 (vibration below 1/20 of the strongest is not worth a shaper's
delay; 20 is also what an EI shaper's 5 % tolerance reduces a resonance by). Bins under T / max|V|
cannot contribute to the numerator and are left out before any work.

Smoothing. A shaper replaces the commanded position x(t) by sum_i A_i x(t - t_i) / sum A. Measured
from the shaper's centre of mass t_c = sum A_i t_i / sum A, an impulse at t_i > t_c moves the
toolhead by the distance travelled in (t_i - t_c) at the corner: with the square-corner velocity v
kept through a 90 degree corner and the acceleration a, that is (v + a/2 (t_i - t_c)) (t_i - t_c) per
axis, sqrt(2) of it across the corner; at a 180 degree reversal (speed 0) a/2 (t_i - t_c)^2. The
smoothing is the larger of the two deviations weighted by the impulses after t_c:

    s = max( sqrt(2) sum_{t_i > t_c} A_i (v + a/2 d_i) d_i,  sum_{t_i > t_c} A_i a/2 d_i^2 ) / sum A,  d_i = t_i - t_c

(Klipper's ``smoothing`` and its ``max_accel`` use this definition; its default v is 5 mm/s and its
bound on s 0.12 mm). Both terms are linear in a, so the largest acceleration that keeps s under a
bound is a closed form (``max_accel``), not a search.
"""

from __future__ import annotations

import math

import numpy as np

THRESHOLD_SHARE = 1 / 20  # T = max P / 20
DEFAULT_SCV = 5.0  # mm/s, square-corner velocity
DEFAULT_ACCEL = 5000.0  # mm/s^2, where smoothing is reported
DEFAULT_MAX_SMOOTHING = 0.12  # mm
KLIPPER_DAMPINGS = (0.075, 0.1, 0.15)


def residual(times, amplitudes, freq, dampings) -> np.ndarray:
    """V (percent residual vibration as a fraction) of impulse sets at frequencies and dampings.

    ``times`` and ``amplitudes`` are (..., n) arrays (a batch of designs), ``freq`` (m,) Hz, ``dampings``
    (z,); returns (..., m, z). Computed relative to the last impulse, so long shapers do not overflow.
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
    instead of an exponential."""
    taps = np.asarray(taps, dtype=float)
    w = 2 * np.pi * np.asarray(freq, dtype=float)[:, None]
    z = np.asarray(dampings, dtype=float)[None, :]
    step = np.exp(-(z * w + 1j * w * np.sqrt(1 - z * z)) * ts)
    total = np.zeros(step.shape, dtype=complex)
    for tap in taps:
        total = total * step + tap
    return np.abs(total) / abs(taps.sum())


class VibrationMeter:
    """Klipper's remaining-vibration metric (module docstring) for one spectrum and damping set,
    prepared once and applied to batches of V."""

    def __init__(self, freq, psd, dampings=KLIPPER_DAMPINGS, max_gain: float = 1.0):
        freq, psd = np.asarray(freq, dtype=float), np.asarray(psd, dtype=float)
        self.threshold = float(psd.max()) * THRESHOLD_SHARE
        self.total = float(np.maximum(psd - self.threshold, 0).sum())
        keep = psd * max_gain > self.threshold
        self.freq, self.psd = freq[keep], psd[keep]
        self.dampings = tuple(float(z) for z in dampings)

    def remaining(self, v_max) -> np.ndarray:
        """R for V_max given at ``self.freq`` (..., m) -> (...)."""
        if self.total <= 0:
            return np.zeros(np.shape(v_max)[:-1])
        return np.maximum(self.psd * v_max - self.threshold, 0).sum(axis=-1) / self.total


def _centre_sums(times, amplitudes):
    t = np.asarray(times, dtype=float)
    a = np.asarray(amplitudes, dtype=float)
    gain = a.sum(axis=-1, keepdims=True)
    centre = (a * t).sum(axis=-1, keepdims=True) / gain
    d = np.maximum(t - centre, 0.0)
    return (a * d).sum(axis=-1) / gain[..., 0], (a * d * d).sum(axis=-1) / gain[..., 0]


def smoothing(times, amplitudes, accel: float = DEFAULT_ACCEL, scv: float = DEFAULT_SCV) -> np.ndarray:
    """The smoothing s (mm) of impulse sets (..., n) at acceleration ``accel`` (mm/s^2) and
    square-corner velocity ``scv`` (mm/s); module docstring."""
    s1, s2 = _centre_sums(times, amplitudes)
    return np.maximum(math.sqrt(2) * (scv * s1 + 0.5 * accel * s2), 0.5 * accel * s2)


def max_accel(times, amplitudes, max_smoothing: float = DEFAULT_MAX_SMOOTHING, scv: float = DEFAULT_SCV) -> np.ndarray:
    """The largest acceleration (mm/s^2) at which ``smoothing`` stays at or under ``max_smoothing``
    (0 if the square-corner velocity alone exceeds it): both terms are linear in a."""
    s1, s2 = _centre_sums(times, amplitudes)
    s2 = np.maximum(s2, 1e-300)
    corner = (max_smoothing / math.sqrt(2) - scv * s1) * 2 / s2
    reversal = 2 * max_smoothing / s2
    return np.maximum(np.minimum(corner, reversal), 0.0)
