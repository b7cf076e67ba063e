"""Power spectra of recordings: Welch's method with its settings stated, axes combined, Klipper's
own spectrum and its normalisation, and Klipper's sweep excitation undone on request.

Two spectra of a recording serve two purposes. ``klipper_psd`` is the one Klipper computes from a
raw recording (``calc_freq_response`` of ``shaper_calibrate.py``, as its documentation and code
describe it: Welch's method with Kaiser windows, beta 6, of the power of two samples nearest above
half a second, half overlapping, each segment's mean removed): what Klipper plots and scores, so the
one a person sees and compares. ``spectrum`` is finer (0.1 Hz by default), to fit a mode's shape.

Klipper's ``TEST_RESONANCES`` moves the toolhead back and forth at a frequency rising at a constant
rate (1 Hz/s by default) with an acceleration proportional to that frequency (``accel_per_hz``). The
energy the sweep puts in per hertz therefore grows as f^2, and a recorded spectrum is the machine's
response times that slope; ``undo_sweep`` divides it out so that the spectrum is the machine's alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from shapefmu.identification.fourier import periodic_hann, stft, welch_psd


# ``Recording`` (identification.recordings) is named in annotations only: recordings imports this module.
AXIS_CHOICES = ("x", "y", "z", "xyz")
RESOLUTION = 0.1  # Hz: Welch segments of 1/RESOLUTION s resolve a 0.02-damped mode at 10 Hz (0.4 Hz wide)
MIN_SEGMENTS = 4
KLIPPER_WINDOW_SECONDS = 0.5  # shaper_calibrate.py's WINDOW_T_SEC
KLIPPER_KAISER_BETA = 6.0
KLIPPER_MIN_FREQ = 5.0  # shaper_calibrate.py's MIN_FREQ: its normalisation tapers the spectrum below twice this
KLIPPER_MAX_FREQ = 200.0  # shaper_calibrate.py's MAX_FREQ: where it stops plotting and scoring
WINDOWS = ("hann", "kaiser6", "")
DIRECTION_RANGE = (1e-9, 1e9)
MIN_SPECTRUM_ROWS = 8  # a spectrum file of fewer frequencies holds no peak to find


@dataclass(frozen=True)
class Spectrum:
    """A power spectral density ``psd`` ((unit)^2/Hz) at ``freq`` (Hz) of one recording's axis.

    ``settings`` says how it was made (window, segment, overlap, or the file it was read from);
    ``sweep_undone`` is True when the f^2 of a Klipper sweep has been divided out; ``normalised`` when
    Klipper's normalisation (``klipper_normalised``) has been applied. ``window`` is the segments'
    window (``hann``, ``kaiser6`` for Klipper's, ``""`` if unknown) and ``segments`` how many were
    averaged (0 if unknown): they say how a peak is smeared and how much a bin scatters.
    """

    source: str
    axis: str
    freq: np.ndarray = field(repr=False)
    psd: np.ndarray = field(repr=False)
    settings: str
    sweep_undone: bool = False
    normalised: bool = False
    window: str = ""
    segments: int = 0

    def band(self, low: float, high: float) -> "Spectrum":
        keep = (self.freq >= low) & (self.freq <= high)
        return replace(self, freq=self.freq[keep], psd=self.psd[keep])


def axis_samples(recording: Recording, axis) -> np.ndarray:
    """The samples along ``axis``: a channel name, or a direction (dx, dy, dz) projected onto (its
    components 0 or within ``DIRECTION_RANGE`` in magnitude: a 1e-320 or a 1e308 would under- or
    overflow its length).

    >>> import numpy as np
    >>> from shapefmu.identification.recordings import Recording
    >>> rec = Recording("r", "table", 100.0, {"x": np.ones(4), "y": 2 * np.ones(4)}, "g")
    >>> axis_samples(rec, (3.0, 4.0, 0.0)).tolist()
    [2.2, 2.2, 2.2, 2.2]
    """
    if isinstance(axis, str):
        if axis not in recording.channels:
            raise ValueError(f"{recording.source}: axis {axis!r} was not recorded; it has {', '.join(recording.channels)}")
        return recording.channels[axis]
    direction = np.asarray(axis, dtype=float)
    size = np.abs(direction)
    if (direction.shape != (3,) or not np.any(direction)
            or not np.all((size == 0) | ((size >= DIRECTION_RANGE[0]) & (size <= DIRECTION_RANGE[1])))):
        raise ValueError(f"a direction must be three numbers dx,dy,dz, each 0 or of magnitude in "
                         f"[{DIRECTION_RANGE[0]:g}, {DIRECTION_RANGE[1]:g}], not all 0, got {axis!r}")
    missing = [a for a, d in zip("xyz", direction) if d and a not in recording.channels]
    if missing:
        raise ValueError(f"{recording.source}: the direction needs axis {missing[0]!r}, which was not recorded")
    direction = direction / np.linalg.norm(direction)
    return sum(d * recording.channels[a] for a, d in zip("xyz", direction) if d)


def _signals(recording: Recording, axis) -> list[np.ndarray]:
    if axis == "xyz":
        return list(recording.channels.values())
    return [axis_samples(recording, axis)]


def _axis_name(axis) -> str:
    return axis if isinstance(axis, str) else "direction"


def spectrum(recording: Recording, axis="xyz", *, resolution: float = RESOLUTION, undo_sweep: bool = False) -> Spectrum:
    """Welch's PSD of ``recording`` along ``axis`` (``x``, ``y``, ``z``, a channel name, a direction,
    or ``xyz``: the sum of the recorded axes' spectra, as Klipper's ``psd_xyz``).

    Hann windows, segments of the power of two nearest 1/``resolution`` s but at most a quarter of
    the record, 75 % overlap over the record padded with zeros by 3/4 of a segment at each end (so
    every sample weighs the same: a swept excitation's spectrum is not rippled by the segmenting),
    the mean removed (gravity is not vibration).

    >>> import numpy as np
    >>> from shapefmu.identification.recordings import Recording
    >>> tone = Recording("tone", "table", 1000.0, {"a": np.sin(2 * np.pi * 50.0 * np.arange(20000) / 1000)}, "g")
    >>> found = spectrum(tone, "a")
    >>> float(found.freq[np.argmax(found.psd)]), found.window
    (50.048828125, 'hann')
    """
    if not (math.isfinite(resolution) and resolution > 0):
        raise ValueError(f"resolution must be a positive frequency step in Hz, got {resolution!r}")
    n = len(next(iter(recording.channels.values())))
    wanted = 2 ** round(math.log2(max(recording.fs / resolution, 16)))
    segment = int(min(wanted, 2 ** math.floor(math.log2(max(n // MIN_SEGMENTS, 16)))))
    settings = (f"Welch: Hann window, {segment} samples ({segment / recording.fs:.3g} s, "
                f"{recording.fs / segment:.3g} Hz resolution), 75 % overlap, mean removed")
    psd = 0.0
    pad = 3 * segment // 4
    window = periodic_hann(segment)
    for samples in _signals(recording, axis):
        # Hann windows overlapping by 3/4 have squares that sum to a constant, and the record padded by
        # 3/4 of a segment at each end is covered four times everywhere: every sample weighs the same.
        # (At 1/2 overlap a sweep's energy is weighted with a ripple of one hop's worth of frequency.)
        padded = np.concatenate([np.zeros(pad), samples - np.mean(samples), np.zeros(pad)])
        found = welch_psd(padded, recording.fs, window, pad, detrend=False)
        psd = psd + found.psd
    result = Spectrum(recording.source, _axis_name(axis), found.freq[1:], psd[1:], settings, window="hann",
                      segments=found.segments)
    return undo_sweep_excitation(result) if undo_sweep else result


def klipper_psd(recording: Recording, axis="xyz") -> Spectrum:
    """The spectrum Klipper computes from a raw recording (module docstring), along ``axis`` as
    ``spectrum`` takes it: Welch's PSD with Kaiser windows (beta 6) of 2^k >= fs / 2 samples, half
    overlapping, each segment's mean removed, the axes' spectra summed for ``xyz``. It is not
    normalised (``klipper_normalised``), as in Klipper's ``resonances_*.csv``. (Klipper takes the
    rate as the samples over the time they span and the samples as they come; here they are on the
    recording's uniform grid. A record of no more than one segment, which Klipper refuses, is cut
    into segments half as long until it holds two.)

    >>> import numpy as np
    >>> from shapefmu.identification.recordings import Recording
    >>> tone = Recording("tone", "table", 3200.0, {"x": np.sin(2 * np.pi * 40.0 * np.arange(64000) / 3200)}, "g")
    >>> found = klipper_psd(tone, "x")
    >>> float(found.freq[1] - found.freq[0]), float(found.freq[np.argmax(found.psd)]), found.segments
    (1.5625, 40.625, 61)
    """
    n = len(next(iter(recording.channels.values())))
    segment = 1 << int(recording.fs * KLIPPER_WINDOW_SECONDS - 1).bit_length()
    while n <= segment and segment > 16:  # shorter than Klipper takes: segments of half the record at most
        segment //= 2
    window = np.kaiser(segment, KLIPPER_KAISER_BETA)
    psd = 0.0
    for samples in _signals(recording, axis):
        found = welch_psd(samples, recording.fs, window, segment // 2, detrend=True)
        psd = psd + found.psd
    settings = (f"Klipper's: Welch, Kaiser window (beta 6), {segment} samples ({segment / recording.fs:.3g} s, "
                f"{recording.fs / segment:.3g} Hz resolution), 50 % overlap, each segment's mean removed")
    return Spectrum(recording.source, _axis_name(axis), found.freq[1:], psd[1:], settings, window="kaiser6",
                    segments=found.segments)


def klipper_normalised(spectrum: Spectrum) -> Spectrum:
    """The spectrum as Klipper plots and scores it (``normalize_to_frequencies`` in
    ``shaper_calibrate.py``): the PSD divided by (f + 0.1) Hz and, below 10 Hz, multiplied by
    exp(1 - (10 / (f + 0.1))^2), which removes the low-frequency noise. A spectrum already
    normalised (a Klipper file with shaper columns) is returned as it is.

    >>> import numpy as np
    >>> flat = Spectrum("flat", "x", np.array([5.0, 9.9, 20.0]), np.ones(3), "")
    >>> [round(float(v), 6) for v in klipper_normalised(flat).psd]
    [0.011403, 0.1, 0.049751]
    """
    if spectrum.normalised:
        return spectrum
    psd = spectrum.psd * spectrum.freq**2 if spectrum.sweep_undone else spectrum.psd
    psd = psd / (spectrum.freq + 0.1)
    low = spectrum.freq < 2 * KLIPPER_MIN_FREQ
    psd[low] *= np.exp(1 - (2 * KLIPPER_MIN_FREQ / (spectrum.freq[low] + 0.1)) ** 2)
    return replace(spectrum, psd=psd, normalised=True, sweep_undone=False,
                   settings=spectrum.settings + "; normalised as Klipper does (/ (f + 0.1), tapered below 10 Hz)")


def spectral_kernel(window: str, oversample: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """(offsets in bins, weights summing to 1) of how a Welch estimate with ``window`` smears one
    frequency: the window's squared Fourier transform, on a grid of 1/``oversample`` bin, out to where
    it is below 1e-4 of its peak. Empty ``window`` (unknown): no smearing.

    >>> offsets, weights = spectral_kernel("hann", 4)
    >>> float(offsets[np.argmax(weights)]), round(float(weights.sum()), 12), float(offsets.max())
    (0.0, 1.0, 2.75)
    """
    if window == "":
        return np.zeros(1), np.ones(1)
    if window not in WINDOWS:
        raise ValueError(f"window must be one of {', '.join(repr(w) for w in WINDOWS)}, got {window!r}")
    length = 256
    taps = np.hanning(length + 1)[:length] if window == "hann" else np.kaiser(length, KLIPPER_KAISER_BETA)
    response = np.abs(np.fft.fft(taps, length * oversample)) ** 2
    response = np.fft.fftshift(response)
    offsets = (np.arange(length * oversample) - length * oversample // 2) / oversample
    # out to the farthest side lobe above 1e-4 (Hann: the main lobe and the first side lobe)
    edge = np.max(np.abs(offsets[response >= 1e-4 * response.max()]))
    keep = np.abs(offsets) <= edge
    return offsets[keep], response[keep] / response[keep].sum()


@dataclass(frozen=True)
class Spectrogram:
    """Power ``power[t, f]`` of a recording in short segments starting at ``times`` (s): when
    each frequency was there."""

    freq: np.ndarray = field(repr=False)
    times: np.ndarray = field(repr=False)
    power: np.ndarray = field(repr=False)

    def steadiness(self, low: float, high: float) -> float:
        """The median over time of the power between ``low`` and ``high`` Hz over its mean: the share
        of it that is there all the time. Near 1 for a tone (a fan), near 0 for a resonance a sweep
        excites only as it passes."""
        band = (self.freq >= low) & (self.freq <= high)
        if not band.any():
            band = np.abs(self.freq - 0.5 * (low + high)) == np.min(np.abs(self.freq - 0.5 * (low + high)))
        level = self.power[:, band].sum(axis=1)
        mean = float(level.mean())
        return float(np.median(level)) / mean if mean > 0 else 1.0


def spectrogram(recording: Recording, axis="xyz", seconds: float = 0.5) -> Spectrogram:
    """Hann-windowed power of ``recording`` along ``axis`` in segments of about ``seconds``, half
    overlapping (the axes' powers summed for ``xyz``).

    >>> import numpy as np
    >>> from shapefmu.identification.recordings import Recording
    >>> t = np.arange(32000) / 3200
    >>> rec = Recording("r", "table", 3200.0, {"a": np.sin(2 * np.pi * 97 * t) + np.sin(2 * np.pi * 40 * t) * (t < 1)}, "g")
    >>> gram = spectrogram(rec, "a")
    >>> round(gram.steadiness(95, 99), 2), gram.steadiness(38, 42) < 0.01
    (1.0, True)
    """
    segment = 1 << int(recording.fs * seconds - 1).bit_length()
    window = periodic_hann(segment)
    power = 0.0
    for samples in _signals(recording, axis):
        found = stft(samples - np.mean(samples), recording.fs, window, segment // 2)
        power = power + np.abs(found.z.T) ** 2
    return Spectrogram(found.freq, found.times, power)


def undo_sweep_excitation(spectrum: Spectrum) -> Spectrum:
    """``spectrum`` divided by f^2: the machine's response per unit of the sweep's acceleration per
    hertz, squared (see the module docstring). A normalised spectrum is multiplied back by f + 0.1
    first (below 10 Hz Klipper's taper stays).

    >>> import numpy as np
    >>> undo_sweep_excitation(Spectrum("s", "x", np.array([10.0, 20.0]), np.array([100.0, 400.0]), "")).psd.tolist()
    [1.0, 1.0]
    """
    if spectrum.sweep_undone:
        return spectrum
    psd = spectrum.psd * (spectrum.freq + 0.1) if spectrum.normalised else spectrum.psd
    return replace(spectrum, psd=psd / spectrum.freq**2, sweep_undone=True, normalised=False,
                   settings=spectrum.settings + "; Klipper's sweep excitation (f^2) divided out")


def klipper_spectrum(names: list[str], values: np.ndarray, *, source: str) -> dict[str, Spectrum]:
    """The spectra of a Klipper processed-spectrum table, by axis (``x``, ``y``, ``z``, ``xyz``) or,
    for a table of combined data sets, by column name. Shaper columns (``zv(59.0)`` ...) are not
    spectra and are left out; where they are, Klipper wrote the spectra normalised (its
    ``calibrate_shaper.py`` says so and does not normalise them again).

    >>> import numpy as np
    >>> table = np.column_stack([np.arange(0.0, 20.0), np.ones((20, 4)), np.ones(20)])
    >>> found = klipper_spectrum(["freq", "psd_x", "psd_y", "psd_z", "psd_xyz", "zv(52.6)"], table, source="f.csv")
    >>> sorted(found), found["xyz"].normalised, found["xyz"].freq.size
    (['x', 'xyz', 'y', 'z'], True, 19)
    """
    if values.shape[0] < MIN_SPECTRUM_ROWS:
        raise ValueError(f"{source}: expected at least {MIN_SPECTRUM_ROWS} rows of frequencies in a Klipper spectrum "
                         f"file, got {values.shape[0]}")
    freq = values[:, 0]
    if np.any(np.diff(freq) <= 0) or freq[0] < 0:
        bad = int(np.flatnonzero(np.diff(freq) <= 0)[0]) + 3 if np.any(np.diff(freq) <= 0) else 2
        raise ValueError(f"{source}: line {bad}: expected increasing frequencies >= 0 in the freq column")
    normalised = any("(" in column for column in names[1:])
    spectra = {}
    for i, column in enumerate(names[1:], start=1):
        if "(" in column:  # a fitted shaper's response, not a measurement
            continue
        axis = column.removeprefix("psd_")
        if np.any(values[:, i] < 0):
            row = int(np.flatnonzero(values[:, i] < 0)[0]) + 2
            raise ValueError(f"{source}: line {row}: expected a power spectral density >= 0 in {column!r}")
        spectra[axis] = Spectrum(source, axis, freq[freq > 0], values[freq > 0, i],
                                 f"read from a Klipper spectrum file ({column})", normalised=normalised,
                                 window="kaiser6")
    if not spectra:
        raise ValueError(f"{source}: line 1: expected psd_x, psd_y, psd_z, psd_xyz or data-set columns after freq")
    return spectra
