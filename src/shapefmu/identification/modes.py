"""Resonances in a spectrum: the peaks a person sees, each one's frequency and damping, and how
sure we are of them.

1. What a person sees. The peaks are looked for in the spectrum as Klipper plots it: for a swept
   excitation its normalised PSD (``spectra.klipper_normalised``), for a flat one (a tap, a shaker)
   the PSD itself. Every local maximum reaching ``min_share`` (a tenth) of the highest in the band
   is a peak, however shallow the dip between it and its neighbour: two peaks with a dip between
   them are two modes; a bump under a tenth of the highest is not one, so that neither the sweep's
   harmonics, nor its end, nor the floor are designed for.
2. Is anything there? The spectrum with the excitation divided out (the machine's |H(f)|^2 up to a
   constant: a sweep's f^2, a flat excitation's nothing) must rise somewhere above a smooth trend
   (a parabola in log-log: noise of any slope or curvature follows one) by more than
   ``NOISE_SIGMAS`` times the scatter of a bin: sqrt((1 + 2 rho^2) / K) for a Welch
   average of K segments whose neighbours correlate by rho, or, for a file that does not say how it
   was averaged, the scatter of its bins measured (the median absolute second difference of the
   log spectrum over 0.6745 sqrt 6, which is the standard deviation of white scatter). White noise
   gives none: the modes are empty and ``Modes.notes`` says why. A flat excitation's spectrum is
   random, so there every peak must stand out so; a sweep's is deterministic and every peak counts.
3. A steady tone is not a resonance. With the recording at hand (``spectrogram``), a sweep excites
   a resonance only while it passes it (and its thirds and fifths); a fan or a motor hums all the
   time. A peak whose power, over time, has a median above ``STEADY`` of its mean (most of it is
   there all the time) is a tone.
4. Each mode's frequency and damping: the local pole form every linear system has (``poles``) fitted
   to the machine's |H(f)|^2 around the peaks (the bins down to ``FIT_FLOOR`` of each top, about
   2.4 half-power widths each side, never past the cliff where a sweep ends). The pole p = -sigma +
   j f_d gives the mode: natural frequency |p| and damping ratio sigma / |p| (the eigenvalue
   definition, for any damping, proportional or not); a fit to the peak's shape and not only to its
   top is what keeps a 0.2-damped mode within 1 %: its peak sits 2-4 % off f_n.
   Where the spectrum resolves the peaks (half-widths of ``RESOLVED_BINS`` bins or more: a recording
   fitted at 0.1 Hz), all of them are fitted together, and a pole is kept if the form fits the
   spectrum within ``TRUSTED_MISFIT`` and the pole lies within its peak's half-power band. Otherwise
   (a Klipper spectrum file: 1.5 Hz bins hardly resolve a printer's peak, and its shape is not a
   clean pole's) each peak is read where it is seen: its damped frequency the top of the plotted
   spectrum (the vertex of the parabola through the log of its three highest bins), its damping
   that of one pole fitted alone to the bins around the top, as many on each side and no further
   than halfway to the neighbouring peaks; the half-power width alone if too few bins remain.
5. How sure: the fit's standard errors (``poles``), and, as the model's own error, how far the same
   fit moves on the peaks' tops alone (down to ``TOP_FLOOR``) and with the other background; the
   damping's 90 % interval is zeta * exp(+-1.645 sd(log zeta)), at most 1.

On a ring-down (``ring_down``) each mode is refined by the EKF of paper 001 on the signal band-passed
around it (``shapefmu.estimation.estimate_mode``) and checked by the log decrement.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from shapefmu.identification.fourier import find_peaks
from shapefmu.identification.poles import fit_poles
from shapefmu.identification.spectra import KLIPPER_MAX_FREQ, Spectrogram, Spectrum, klipper_normalised

# The slope p of the excitation's spectrum: Klipper's sweep puts in energy growing as f^2 (spectra),
# a tap, a ring-down or a white-noise shaker a flat spectrum.
EXCITATION_SLOPES = {"sweep": 2.0, "flat": 0.0}
MAX_MODES = 8
MIN_SHARE = 0.1
SEEN_RESOLUTION = 1.5625  # Hz: Klipper's spectrum (0.5 s windows, 2^k >= 1600 samples at 3.2 kHz)
NOISE_SIGMAS = 6.0  # the scatter of a few thousand bins stays below about 4.5 sigma
STEADY = 0.5
FIT_FLOOR = 0.15  # a mode is fitted down to this share of its peak: about 2.4 half-power widths each side
TOP_FLOOR = 0.4  # ... and checked on its top alone, down to this share: about 1.2 half-power widths
MAX_HALF_SPAN = 400  # bins each way: bounds the work of one fit
MAX_FIT_BINS = 240  # a wider band is fitted on every k-th bin
SHAPES = ((False, False), (True, False), (True, True))  # (asymmetric residues, tilted background)
RESOLVED_BINS = 4  # a peak narrower than this (half-width, in bins) is fitted alone, by its top
TRUSTED_MISFIT = 0.04  # a joint fit missing the spectrum by more (rms) places no pole away from the top seen
ON_TOP = 1.0  # a pole its half-width off a top, where a peak is at half its height, is not that peak
Z90 = 1.6448536269514722  # the standard normal's 95th percentile: a two-sided 90 % interval


@dataclass(frozen=True)
class Mode:
    """A resonance: natural ``frequency`` (Hz) and damping ratio ``zeta``, with their standard errors
    (``frequency_sd`` Hz, ``zeta_sd``) and the damping's 90 % interval ``zeta_interval``; ``peak`` is
    the plotted spectrum's value at its peak, ``peak_frequency`` where that peak is."""

    frequency: float
    zeta: float
    frequency_sd: float
    zeta_sd: float
    peak: float
    method: str
    log_decrement_zeta: float | None = None
    zeta_interval: tuple[float, float] | None = None
    peak_frequency: float | None = None

    @property
    def omega(self) -> float:
        return 2 * math.pi * self.frequency

    @property
    def damped_frequency(self) -> float:
        """f sqrt(1 - zeta^2): where the mode rings, and where its peak is."""
        return self.frequency * math.sqrt(max(1 - self.zeta**2, 0.0))

    def describe(self) -> str:
        """One line: frequency, damping and how sure.

        >>> Mode(40.0, 0.05, 0.02, 0.004, 1.0, "spectrum fit", zeta_interval=(0.044, 0.057)).describe()
        '   40.00 Hz +- 0.02   zeta 0.0500 +- 0.004 (90 %: 0.0440-0.0570)   (spectrum fit)'
        """
        text = f"{self.frequency:8.2f} Hz +- {self.frequency_sd:.2g}   zeta {self.zeta:.4f} +- {self.zeta_sd:.2g}"
        if self.zeta_interval is not None:
            text += f" (90 %: {self.zeta_interval[0]:.4f}-{self.zeta_interval[1]:.4f})"
        text += f"   ({self.method})"
        if self.log_decrement_zeta is not None:
            text += f", log decrement zeta {self.log_decrement_zeta:.4f}"
        return text


@dataclass(frozen=True)
class Modes:
    """The modes of one spectrum, strongest first. ``spectrum`` is the one fitted, ``view`` the one
    the peaks were seen in; ``notes`` says what was seen and not taken (a tone, the noise), and why
    there is no mode when there is none."""

    spectrum: Spectrum = field(repr=False)
    modes: tuple[Mode, ...]
    noise_floor: float
    excitation: str = "sweep"
    view: Spectrum | None = field(default=None, repr=False)
    notes: tuple[str, ...] = ()


def _recorded(spectrum: Spectrum) -> np.ndarray:
    """The PSD as recorded (Klipper's normalisation or the sweep's f^2 multiplied back; below 10 Hz a
    normalised spectrum keeps Klipper's taper)."""
    if spectrum.normalised:
        return spectrum.psd * (spectrum.freq + 0.1)
    return spectrum.psd * spectrum.freq**2 if spectrum.sweep_undone else spectrum.psd


def machine_response(spectrum: Spectrum, excitation: str = "sweep") -> np.ndarray:
    """The machine's |H(f)|^2 up to a constant: the recorded PSD over the excitation's spectrum.

    >>> import numpy as np
    >>> swept = Spectrum("s", "x", np.array([10.0, 20.0]), np.array([100.0, 400.0]), "")
    >>> machine_response(swept).tolist(), machine_response(swept, "flat").tolist()
    ([1.0, 1.0], [100.0, 400.0])
    """
    return _recorded(spectrum) / spectrum.freq ** EXCITATION_SLOPES[excitation]


def plotted(spectrum: Spectrum, excitation: str = "sweep") -> Spectrum:
    """The spectrum a person looks at: Klipper's normalised PSD for a sweep, the PSD for a flat
    excitation.

    >>> import numpy as np
    >>> swept = Spectrum("s", "x", np.array([9.9, 20.0]), np.array([1.0, 1.0]), "")
    >>> [round(float(v), 4) for v in plotted(swept).psd], plotted(swept, "flat").psd.tolist()
    ([0.1, 0.0498], [1.0, 1.0])
    """
    if excitation == "sweep":
        return klipper_normalised(spectrum)
    return Spectrum(spectrum.source, spectrum.axis, spectrum.freq, _recorded(spectrum), spectrum.settings,
                    window=spectrum.window, segments=spectrum.segments)


def _scatter(spectrum: Spectrum, log_response: np.ndarray) -> float:
    """The standard deviation of one bin's log (module docstring, 2)."""
    if spectrum.segments > 0:
        overlap = _overlap_correlation(spectrum.window)
        return math.sqrt((1 + 2 * overlap**2) / spectrum.segments)
    second = np.diff(log_response, 2)
    return float(np.median(np.abs(second))) / (0.6745 * math.sqrt(6)) if second.size else math.inf


def _overlap_correlation(window: str) -> float:
    """How much two neighbouring Welch segments' estimates of one bin correlate (Welch 1967, eq. 11):
    the window's overlapping halves' product, squared, over its energy squared, for the overlaps
    ``spectra`` uses (Klipper's Kaiser windows: a half; our Hann windows: three quarters)."""
    length = 1024
    taps = np.kaiser(length, 6.0) if window == "kaiser6" else np.hanning(length + 1)[:length]
    hop = length // 2 if window == "kaiser6" else length // 4
    return float(np.dot(taps[hop:], taps[:-hop]) / np.dot(taps, taps))


def find_modes(spectrum: Spectrum, *, excitation: str = "sweep", f_min: float | None = None, f_max: float | None = None,
               max_modes: int = MAX_MODES, min_share: float = MIN_SHARE, fine: Spectrum | None = None,
               spectrogram: Spectrogram | None = None) -> Modes:
    """The resonances of ``spectrum`` between ``f_min`` and ``f_max`` (Hz; for a sweep up to 200 Hz,
    as Klipper plots it, by default), strongest first (module docstring). ``fine`` is a finer
    spectrum of the same recording to fit the modes' shapes on (the peaks are seen in ``spectrum``);
    ``spectrogram`` of the same recording tells a tone from a resonance. An empty ``modes`` means no
    resonance stands out, and ``notes`` says why.

    >>> import numpy as np
    >>> f = np.arange(1.0, 200.0, 0.25)
    >>> h = 1 / (1 - (f / 40) ** 2 + 0.1j * f / 40)             # one mode, 40 Hz, zeta 0.05
    >>> found = find_modes(Spectrum("m", "x", f, np.abs(h) ** 2, "model"), excitation="flat")
    >>> [(round(m.frequency, 2), round(m.zeta, 4)) for m in found.modes]
    [(40.0, 0.05)]
    """
    if excitation not in EXCITATION_SLOPES:
        raise ValueError(f"excitation must be one of {', '.join(EXCITATION_SLOPES)}, got {excitation!r}")
    if not (0 < min_share < 1):
        raise ValueError(f"min_share must be in (0, 1), got {min_share!r}")
    fine = spectrum if fine is None else fine
    if not (isinstance(max_modes, int) and 1 <= max_modes <= 32):
        raise ValueError(f"max_modes must be an integer in [1, 32], got {max_modes!r}")
    low = spectrum.freq[0] if f_min is None else f_min
    if f_max is None:  # Klipper plots and scores a sweep's spectrum up to its MAX_FREQ
        high = min(spectrum.freq[-1], KLIPPER_MAX_FREQ) if excitation == "sweep" else spectrum.freq[-1]
    else:
        high = f_max
    if not (0 <= low < high):
        raise ValueError(f"the band must have 0 <= f_min < f_max, got f_min = {low!r} Hz, f_max = {high!r} Hz")
    if high > spectrum.freq[-1] * (1 + 1e-9):
        raise ValueError(f"{spectrum.source}: f_max = {high:g} Hz is above the highest frequency of the spectrum, "
                         f"{spectrum.freq[-1]:g} Hz (half the sampling rate)")
    keep = (spectrum.freq >= low) & (spectrum.freq <= high)
    if np.count_nonzero(keep) < 8:
        raise ValueError(f"{spectrum.source}: only {np.count_nonzero(keep)} spectrum bins between {low:g} and {high:g} Hz")
    view = plotted(spectrum, excitation)
    seen, freq = view.psd[keep], view.freq[keep]
    if not np.all(np.isfinite(seen)) or not np.all(np.isfinite(spectrum.psd)):
        raise ValueError(f"{spectrum.source}: the spectrum is not finite (an overflow: a sample too large)")
    floor = float(np.median(seen))
    empty = Modes(fine, (), floor, excitation, view)
    top = float(seen.max())
    if top <= 0:
        return _replace_notes(empty, "the spectrum is zero: nothing moved")
    response = np.log(np.maximum(machine_response(spectrum, excitation)[keep], top * 1e-300))
    scatter = _scatter(spectrum, response)
    trend = np.polyval(np.polyfit(np.log(freq), response, 2), np.log(freq))
    if np.max(response - trend) <= NOISE_SIGMAS * scatter:
        return _replace_notes(empty, f"no resonance: the machine's response nowhere rises above a smooth trend by more "
                                     f"than the spectrum's scatter allows (a bin scatters by {100 * scatter:.2g} %; a "
                                     f"resonance must rise {NOISE_SIGMAS:g} times that)")
    # a finer spectrum than Klipper's is looked at as Klipper plots one: averaged over its resolution
    seen_step = max(float(freq[1] - freq[0]), SEEN_RESOLUTION)
    width = int(round(seen_step / (freq[1] - freq[0])))
    if width > 1:  # a moving average, the edges repeated
        seen = np.convolve(np.pad(seen, (width // 2, (width - 1) // 2), mode="edge"), np.ones(width) / width, "valid")
    top = float(seen.max())
    found = find_peaks(seen, min_share * top)
    peaks = found.indices
    notes = []
    if excitation == "flat":  # a random excitation's spectrum: each peak must rise out of the scatter
        kept = np.log(seen[peaks]) - np.log(seen[peaks] - found.prominences + top * 1e-300) > NOISE_SIGMAS * scatter
        peaks = peaks[kept]
    if spectrogram is not None and excitation == "sweep":
        width = 1.5 * seen_step
        steady = [spectrogram.steadiness(freq[i] - width, freq[i] + width) for i in peaks]
        notes += [f"{freq[i]:.1f} Hz: a steady tone (a fan, a motor), there all the time: not a resonance"
                  for i, s in zip(peaks, steady) if s > STEADY]
        peaks = np.array([i for i, s in zip(peaks, steady) if s <= STEADY], dtype=int)
    order = peaks[np.argsort(seen[peaks])[::-1]]
    if order.size > max_modes:
        notes.append(f"{order.size - max_modes} more peak(s) above {100 * min_share:g} % of the highest not fitted "
                     f"(max_modes = {max_modes})")
        order = order[:max_modes]
    if order.size == 0:
        return _replace_notes(empty, *notes, "no resonance: no peak reaches a tenth of the highest apart from tones")
    fitted = _fit_modes(fine, excitation, [(_top(freq, seen, np.array([i]))[0], float(seen[i])) for i in order],
                        seen_step)
    return Modes(fine, tuple(fitted), floor, excitation, view, tuple(notes))


def _replace_notes(modes: Modes, *notes: str) -> Modes:
    return Modes(modes.spectrum, modes.modes, modes.noise_floor, modes.excitation, modes.view, tuple(notes))


def _half_width(freq: np.ndarray, values: np.ndarray, i: int, walls: tuple[int, int]) -> float:
    """Half the width (Hz) at half of ``values[i]``, from the sides that fall to half before the
    ``walls`` (the bins halfway to the neighbouring peaks; both sides when both do); two bins when
    neither does."""
    half = values[i] / 2
    widths = []
    for step, wall in ((-1, walls[0]), (1, walls[1])):
        j = i
        while (j - wall) * step < 0 and values[j + step] > half:
            j += step
        if (j - wall) * step >= 0:
            continue
        k = j + step
        edge = freq[k] + (half - values[k]) * (freq[j] - freq[k]) / (values[j] - values[k])
        widths.append(abs(edge - freq[i]))
    bin_width = freq[1] - freq[0]
    return max(float(np.mean(widths)) if widths else 2 * bin_width, 0.5 * bin_width)


def _region(values: np.ndarray, i: int, share: float) -> tuple[int, int]:
    """The bins around peak ``i`` down to ``share`` of it (or into a dip deeper than that), at most
    ``MAX_HALF_SPAN`` bins each way."""
    floor = share * values[i]
    lo = i
    while lo > 0 and i - lo < MAX_HALF_SPAN and values[lo - 1] >= floor:
        lo -= 1
    hi = i
    while hi < values.size - 1 and hi - i < MAX_HALF_SPAN and values[hi + 1] >= floor:
        hi += 1
    return lo, hi


def _fit_modes(spectrum: Spectrum, excitation: str, peaks: list[tuple[float, float]], seen_step: float) -> list[Mode]:
    """Every peak's mode (module docstring, 4-5) from the peaks seen, (top, height)."""
    freq = spectrum.freq
    step = freq[1] - freq[0]
    response = machine_response(spectrum, excitation)
    view = plotted(spectrum, excitation).psd
    seen = sorted(at for at, _ in peaks)
    members, tops, walls = [], [], []
    for at, height in peaks:
        below, above = [x for x in seen if x < at], [x for x in seen if x > at]
        walls.append((int(np.searchsorted(freq, (below[-1] + at) / 2)) if below else 0,
                      int(np.searchsorted(freq, (above[0] + at) / 2)) - 1 if above else freq.size - 1))
        near = np.flatnonzero(np.abs(freq - at) <= max(seen_step, step))
        near = near if near.size else np.array([int(np.argmin(np.abs(freq - at)))])
        i = int(near[np.argmax(response[near])])
        members.append((i, _half_width(freq, response, i, walls[-1]), at, height))
        tops.append(_top(freq, view, near))
    resolved = [k for k, member in enumerate(members) if member[1] >= RESOLVED_BINS * step]
    joint = _resolved_modes(spectrum, response, [members[k] for k in resolved]) if resolved else []
    modes = {}
    for k, mode in zip(resolved, joint):
        # a pole outside the half-power band of the peak it stands for (its half-width, or half a
        # bin, off the top of the plotted fitted spectrum) is not the peak seen
        if mode is not None and abs(mode.damped_frequency - tops[k][0]) < max(ON_TOP * mode.zeta * mode.frequency,
                                                                               step / 2):
            modes[k] = mode
    for k, (at, height) in enumerate(peaks):
        if k not in modes:
            modes[k] = _unresolved_mode(spectrum, view, tops[k], walls[k], at, height)
    return sorted(modes.values(), key=lambda m: -m.peak)


def _top(freq: np.ndarray, values: np.ndarray, near: np.ndarray) -> tuple[float, int]:
    """(frequency, bin) of the top of the highest of ``values`` at the bins ``near``: the vertex of
    the parabola through the log of it and its neighbours (within half a bin of it)."""
    i = int(near[np.argmax(values[near])])
    top = float(freq[i])
    if 0 < i < freq.size - 1 and min(values[i - 1:i + 2]) > 0:
        left, middle, right = np.log(values[i - 1:i + 2])
        if left - 2 * middle + right < 0:
            top += float(np.clip(0.5 * (left - right) / (left - 2 * middle + right), -0.5, 0.5)) * (freq[1] - freq[0])
    return top, i


def _bins(values: np.ndarray, i: int, share: float, walls: tuple[int, int] | None = None) -> np.ndarray:
    """The bins of ``_region``, every k-th of a wide one; within ``walls`` (the bins halfway to the
    neighbouring peaks) and as far on both sides, if given: a one-sided tail would pull a pole
    fitted alone off its top."""
    lo, hi = _region(values, i, share)
    if walls is not None:
        lo, hi = max(lo, walls[0]), min(hi, walls[1])
        lo, hi = i - min(i - lo, hi - i), i + min(i - lo, hi - i)
    return np.arange(lo, hi + 1, max(1, (hi - lo + 1) // MAX_FIT_BINS))


def _resolved_modes(spectrum: Spectrum, response: np.ndarray, members) -> list[Mode | None]:
    """All poles in one form on the bins around every peak (the best of ``SHAPES``), checked on the
    tops alone and with the other background: how far these disagree with it is the model's own
    error, added to the fit's. None for every peak if the form misses the spectrum by more than
    ``TRUSTED_MISFIT``: a spectrum the form does not describe is read peak by peak."""
    whole = np.unique(np.concatenate([_bins(response, i, FIT_FLOOR) for i, _, _, _ in members]))
    tops = np.unique(np.concatenate([_bins(response, i, TOP_FLOOR) for i, _, _, _ in members]))
    starts = [(i, width) for i, width, _, _ in members]
    main = fit_poles(spectrum, response, whole, starts, SHAPES)
    if main is None or main.misfit > TRUSTED_MISFIT:
        return [None] * len(members)
    other_background = (main.form.asymmetric, not main.form.tilted)
    checks = [check for check in (fit_poles(spectrum, response, tops, starts, [main.shape()], main),
                                  fit_poles(spectrum, response, whole, starts, [other_background], main))
              if check is not None]
    modes = []
    for k, (_, _, seen_at, height) in enumerate(members):
        natural, zeta, sd_log_f, sd_log_z = main.mode(k)
        for check in checks:
            other_f, other_z = check.mode(k)[:2]
            sd_log_f, sd_log_z = math.hypot(sd_log_f, math.log(other_f / natural)), math.hypot(sd_log_z, math.log(other_z / zeta))
        modes.append(_mode(natural, zeta, natural * sd_log_f, sd_log_z, height, seen_at))
    return modes


def _mode(natural, zeta, frequency_sd, sd_log_zeta, height, seen_at) -> Mode:
    # log-normal, as zeta > 0; a resonance's damping ratio is below 1
    interval = (zeta * math.exp(-Z90 * sd_log_zeta), min(zeta * math.exp(Z90 * sd_log_zeta), 1.0))
    return Mode(natural, zeta, frequency_sd, zeta * sd_log_zeta, height, "spectrum fit", zeta_interval=interval,
                peak_frequency=seen_at)


def _unresolved_mode(spectrum: Spectrum, view: np.ndarray, top: tuple[float, int], walls: tuple[int, int], at: float,
                     height: float) -> Mode:
    """A peak fitted alone where it is seen: its damped frequency the ``top`` (frequency, bin) of the
    plotted spectrum, its damping that of one pole with a real residue and background fitted to the
    bins around the top (as many on each side, within the ``walls`` halfway to the neighbouring
    peaks), checked on the top alone."""
    freq = spectrum.freq
    frequency, i = top
    start = [(i, _half_width(freq, view, i, walls))]
    fixed = {0: math.log(frequency)}
    main = fit_poles(spectrum, view, _bins(view, i, FIT_FLOOR, walls), start, [(False, False)], fixed=fixed)
    if main is None:
        return _half_power_mode(frequency, start[0][1], at, height)
    check = fit_poles(spectrum, view, _bins(view, i, TOP_FLOOR, walls), start, [(False, False)], main, fixed)
    natural, zeta, _, sd_log_z = main.mode(0)
    if check is not None:
        sd_log_z = math.hypot(sd_log_z, math.log(check.mode(0)[1] / zeta))
    # the top is known to within its bin: a uniform error of one bin's width
    return _mode(natural, zeta, (freq[1] - freq[0]) / math.sqrt(12), sd_log_z, height, at)


def _half_power_mode(top: float, width: float, seen_at: float, height: float) -> Mode:
    """A mode from its ``top`` and half-power ``width`` (Hz) alone, where no fit holds (too few bins):
    zeta = width / top, the damping known to a factor 2; its damped frequency the top."""
    zeta = min(width / top, 0.7)
    return Mode(top / math.sqrt(1 - zeta**2), zeta, width, zeta / 2, height, "half-power",
                zeta_interval=(zeta / 2, min(2 * zeta, 1.0)), peak_frequency=seen_at)


def ring_down(samples, fs: float, modes: Modes | tuple[Mode, ...]) -> tuple[Mode, ...]:
    """The modes of a free decay refined by the EKF of paper 001 (``shapefmu.estimation``): the
    signal band-passed to +-30 % around each mode, the EKF started from the spectrum's estimate, the
    log decrement of the same band as the check.

    >>> import numpy as np
    >>> t = np.arange(4000) / 1000
    >>> decay = np.exp(-0.03 * 2 * np.pi * 18 * t) * np.sin(2 * np.pi * 18 * np.sqrt(1 - 0.03**2) * t)
    >>> (mode,) = ring_down(decay, 1000.0, (Mode(18.3, 0.04, 0.1, 0.01, 1.0, "guess"),))
    >>> round(mode.frequency, 1), round(mode.zeta, 2), round(mode.log_decrement_zeta, 2)
    (18.0, 0.03, 0.03)
    """
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
                            mode.peak, "EKF on the ring-down", check, peak_frequency=mode.peak_frequency))
    return tuple(refined)
