"""Resonances found in a spectrum: frequency, damping and how sure we are of each.

1. Peaks: local maxima of the log spectrum (smoothed over five bins, so that the scatter of a Welch
   estimate is not taken for a resonance) whose prominence is at least ``prominence`` decades and
   that are at most ``below_peak`` decades below the highest one (the ripple of a swept excitation
   and the noise floor are not resonances).
2. First estimate of each: the half-power bandwidth, zeta = (f2 - f1) / (2 f_peak), from the side
   that reaches half the peak (both when both do).
3. Refinement: one least-squares fit of all modes at once to the log spectrum over the band that
   holds them, with the model of the recording (``response``):

   - ``"transmitted"`` (an accelerometer on the part the motion system carries, the default):
     S(f) = s f^p |sum_k c_k T_k(f)|^2 + n0, T_k = (1 + 2 j zeta_k r_k) / (1 - r_k^2 + 2 j zeta_k r_k);
   - ``"mode"`` (an encoder error, a displacement): the same with T_k = 1 / (1 - r_k^2 + 2 j zeta_k r_k),

   r_k = f / f_k; c_1 = 1 and the other shares c_k free (signed), the level s and the floor n0 free,
   the slope p that of the excitation (``excitation``: 2 for Klipper's sweep, 0 for a flat one or a
   spectrum whose sweep was divided out). Only the bins within three half-power bandwidths of a peak
   are fitted: farther out a swept excitation's spectrum has ripples of its own (a chirp's Fresnel
   ripple, the square wave's harmonics) that no model of the machine should absorb. Fitting the shape, not only the peak, is what keeps a 0.2-damped mode within
   1 % in frequency: its peak sits 2-4 % below f_n and the half-power points are no longer symmetric.
   The standard errors come from the fit's Jacobian (sigma^2 (J^T J)^-1); neighbouring Welch bins are
   correlated, so they are a lower bound, reported as such.
4. On a ring-down (``ring_down``) each mode is refined by the EKF of paper 001 on the signal
   band-passed around it (``shapefmu.estimation.estimate_mode``) and checked by the log decrement.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.ndimage import uniform_filter1d
from scipy.optimize import least_squares
from scipy.signal import find_peaks

from shapefmu.identification.spectra import Spectrum

RESPONSES = ("transmitted", "mode")
# The slope p of the excitation's spectrum: Klipper's sweep puts in energy growing as f^2 (spectra),
# a tap, a ring-down or a white-noise shaker a flat spectrum.
EXCITATION_SLOPES = {"sweep": 2.0, "flat": 0.0}
MAX_MODES = 6


@dataclass(frozen=True)
class Mode:
    """A resonance: natural ``frequency`` (Hz) and damping ratio ``zeta``, with their standard errors
    (``frequency_sd`` Hz, ``zeta_sd``), the spectrum's peak value there and how it was found."""

    frequency: float
    zeta: float
    frequency_sd: float
    zeta_sd: float
    peak: float
    method: str
    log_decrement_zeta: float | None = None

    @property
    def omega(self) -> float:
        return 2 * math.pi * self.frequency

    def describe(self) -> str:
        text = (f"{self.frequency:8.2f} Hz +- {self.frequency_sd:.2g}   zeta {self.zeta:.4f} +- {self.zeta_sd:.2g}"
                f"   ({self.method})")
        if self.log_decrement_zeta is not None:
            text += f", log decrement zeta {self.log_decrement_zeta:.4f}"
        return text


@dataclass(frozen=True)
class Modes:
    """The modes of one spectrum, strongest first, with the floor and threshold used to find them."""

    spectrum: Spectrum = field(repr=False)
    modes: tuple[Mode, ...]
    noise_floor: float
    response: str
    excitation: str = "sweep"


def _half_power(freq, psd, i) -> tuple[float, float]:
    """(f_peak, zeta) from the half-power points around bin ``i`` (interpolated in the bins)."""
    half = psd[i] / 2
    widths = []
    for step in (-1, 1):
        j = i
        while 0 <= j + step < len(psd) and psd[j + step] > half:
            j += step
            if psd[j] > psd[i] * 1.05:  # climbing into another peak: this side does not reach half power
                j = None
                break
        if j is None or not 0 <= j + step < len(psd):
            continue
        k = j + step
        edge = freq[k] + (half - psd[k]) * (freq[j] - freq[k]) / (psd[j] - psd[k])
        widths.append(abs(edge - freq[i]))
    if not widths:
        return float(freq[i]), 0.05
    return float(freq[i]), max(float(np.mean(widths)) / freq[i], 0.5 * (freq[1] - freq[0]) / freq[i])


def _model(params, f, count, response, slope):
    level, floor = params[:2]
    total = np.zeros(f.size, dtype=complex)
    for k in range(count):
        fk, zk = math.exp(params[2 + 3 * k]), math.exp(params[3 + 3 * k])
        share = 1.0 if k == 0 else params[4 + 3 * k]
        r = f / fk
        numerator = 1 + 2j * zk * r if response == "transmitted" else 1.0
        total += share * numerator / (1 - r * r + 2j * zk * r)
    # the exponents clipped: a trial step of the fit may try any level, and inf is not a residual
    return np.exp(min(level, 700.0)) * f**slope * np.abs(total) ** 2 + np.exp(min(floor, 700.0))


def find_modes(spectrum: Spectrum, *, response: str = "transmitted", excitation: str = "sweep",
               prominence: float = 0.5, below_peak: float = 3.0, f_min: float | None = None, f_max: float | None = None,
               max_modes: int = MAX_MODES) -> Modes:
    """The resonances of ``spectrum`` between ``f_min`` and ``f_max`` (Hz), strongest first; see the
    module docstring. An empty ``modes`` means no resonance stands out: ``noise_floor`` says above
    what was searched."""
    if response not in RESPONSES:
        raise ValueError(f"response must be one of {', '.join(RESPONSES)}, got {response!r}")
    if excitation not in EXCITATION_SLOPES:
        raise ValueError(f"excitation must be one of {', '.join(EXCITATION_SLOPES)}, got {excitation!r}")
    for value, name in ((prominence, "prominence"), (below_peak, "below_peak")):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a positive number of decades, got {value!r}")
    low = spectrum.freq[0] if f_min is None else f_min
    high = spectrum.freq[-1] if f_max is None else f_max
    if not (0 <= low < high):
        raise ValueError(f"the band must have 0 <= f_min < f_max, got f_min = {low!r} Hz, f_max = {high!r} Hz")
    if high > spectrum.freq[-1] * (1 + 1e-9):
        raise ValueError(f"{spectrum.source}: f_max = {high:g} Hz is above the highest frequency of the spectrum, "
                         f"{spectrum.freq[-1]:g} Hz (half the sampling rate)")
    band = spectrum.band(low, high)
    freq, psd = band.freq, np.maximum(band.psd, np.finfo(float).tiny)
    if freq.size < 8:
        raise ValueError(f"{spectrum.source}: only {freq.size} spectrum bins between {low:g} and {high:g} Hz")
    floor = float(np.percentile(psd, 10))
    smooth = uniform_filter1d(np.log10(psd), 5, mode="nearest")
    peaks, props = find_peaks(smooth, prominence=prominence, height=smooth.max() - below_peak)
    order = np.argsort(props["peak_heights"])[::-1][:max_modes]
    peaks = peaks[order]
    if peaks.size == 0:
        return Modes(spectrum, (), floor, response)
    first = [_half_power(freq, psd, int(i)) for i in peaks]
    slope = EXCITATION_SLOPES[excitation] if not spectrum.sweep_undone else 0.0
    return Modes(spectrum, tuple(_refine(freq, psd, first, floor, response, slope)), floor, response, excitation)


def _refine(freq, psd, first, floor, response, slope):
    """Fit all modes at once (module docstring, 3) on the bins within three half-power bandwidths of
    a peak (farther out, the excitation's own ripple dominates); the half-power estimates where the
    fit fails."""
    df = freq[1] - freq[0]
    keep = np.zeros(freq.size, dtype=bool)
    for fk, zk in first:
        keep |= np.abs(freq - fk) <= max(3 * zk * fk, 4 * df)
    f, y = freq[keep], np.log(psd[keep])
    count = len(first)
    f0, z0 = first[0]
    start = [math.log(np.interp(f0, freq, psd) * (2 * z0) ** 2 / f0**slope), math.log(floor)]
    lower, upper = [-np.inf, -np.inf], [np.inf, np.inf]
    for k, (fk, zk) in enumerate(first):
        zk = min(max(zk, 1e-3), 0.5)
        ratio = math.sqrt(np.interp(fk, freq, psd) / np.interp(f0, freq, psd) * (f0 / fk) ** slope)
        start += [math.log(fk), math.log(zk), ratio * zk / z0]
        lower += [math.log(fk * 0.8), math.log(1e-4), -np.inf]
        upper += [math.log(fk * 1.25), math.log(0.7), np.inf]
    free = [i for i in range(len(start)) if i != 4]  # c_1 = 1: the level carries the scale
    x0 = np.array(start)

    def residual(values):
        x = x0.copy()
        x[free] = values
        return np.log(_model(x, f, count, response, slope)) - y

    fit = None
    if f.size > len(free):
        try:
            fit = least_squares(residual, x0[free], bounds=(np.array(lower)[free], np.array(upper)[free]),
                                x_scale="jac")
        except (ValueError, np.linalg.LinAlgError):
            fit = None
    if fit is None or not fit.success:
        return [Mode(fk, zk, df, 0.25 * zk, float(np.interp(fk, freq, psd)), "half-power") for fk, zk in first]
    x = x0.copy()
    x[free] = fit.x
    sigma2 = float(fit.fun @ fit.fun) / max(f.size - len(free), 1)
    covariance = np.linalg.pinv(fit.jac.T @ fit.jac) * sigma2
    position = {i: n for n, i in enumerate(free)}
    modes = []
    for k in range(count):
        fk, zk = math.exp(x[2 + 3 * k]), math.exp(x[3 + 3 * k])
        sd_f = fk * math.sqrt(max(covariance[position[2 + 3 * k], position[2 + 3 * k]], 0.0))
        sd_z = zk * math.sqrt(max(covariance[position[3 + 3 * k], position[3 + 3 * k]], 0.0))
        modes.append(Mode(fk, zk, sd_f, sd_z, float(np.interp(fk, freq, psd)), "spectrum fit"))
    return modes


def ring_down(samples, fs: float, modes: Modes | tuple[Mode, ...]) -> tuple[Mode, ...]:
    """The modes of a free decay refined by the EKF of paper 001 (``shapefmu.estimation``): the
    signal band-passed to +-30 % around each mode, the EKF started from the spectrum's estimate, the
    log decrement of the same band as the check."""
    from scipy.signal import butter, sosfiltfilt

    from shapefmu.estimation import estimate_mode, log_decrement_zeta

    found = modes.modes if isinstance(modes, Modes) else tuple(modes)
    y = np.asarray(samples, dtype=float)
    refined = []
    for mode in found:
        low, high = 0.7 * mode.frequency, min(1.3 * mode.frequency, 0.45 * fs)
        sos = butter(4, [low, high], btype="bandpass", fs=fs, output="sos")
        part = sosfiltfilt(sos, y)
        start = int(np.argmax(np.abs(part)))
        part = part[start:]
        omega_d = mode.omega * math.sqrt(max(1 - mode.zeta**2, 1e-6))
        estimate = estimate_mode(part, fs, omega_d, mode.zeta * mode.omega)
        # the peaks while the decay is above a tenth of its start: later ones are the noise's
        periods = max(2, int(math.log(10) / max(estimate.sigma, 1e-9) * estimate.omega_d / (2 * math.pi)))
        try:
            check = log_decrement_zeta(part, fs, estimate.omega_d, periods)
        except ValueError:
            check = None
        frequency = estimate.omega_n / (2 * math.pi)
        refined.append(Mode(frequency, estimate.zeta, abs(frequency - mode.frequency) / 2, abs(estimate.zeta - mode.zeta) / 2,
                            mode.peak, "EKF on the ring-down", check))
    return tuple(refined)
