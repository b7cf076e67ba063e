"""Power spectra of recordings: Welch's method with its settings stated, axes combined, and
Klipper's sweep excitation undone on request.

Klipper's ``TEST_RESONANCES`` moves the toolhead back and forth at a frequency rising at a constant
rate (1 Hz/s by default) with an acceleration proportional to that frequency (``accel_per_hz``). The
energy the sweep puts in per hertz therefore grows as f^2, and a recorded spectrum is the machine's
response times that slope; ``undo_sweep`` divides it out so that the spectrum is the machine's alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.signal import welch


# ``Recording`` (identification.recordings) is named in annotations only: recordings imports this module.
AXIS_CHOICES = ("x", "y", "z", "xyz")
RESOLUTION = 0.1  # Hz: Welch segments of 1/RESOLUTION s resolve a 0.02-damped mode at 10 Hz (0.4 Hz wide)
MIN_SEGMENTS = 4


@dataclass(frozen=True)
class Spectrum:
    """A power spectral density ``psd`` ((unit)^2/Hz) at ``freq`` (Hz) of one recording's axis.

    ``settings`` says how it was made (window, segment, overlap, or the file it was read from);
    ``sweep_undone`` is True when the f^2 of a Klipper sweep has been divided out.
    """

    source: str
    axis: str
    freq: np.ndarray = field(repr=False)
    psd: np.ndarray = field(repr=False)
    settings: str
    sweep_undone: bool = False

    def band(self, low: float, high: float) -> "Spectrum":
        keep = (self.freq >= low) & (self.freq <= high)
        return replace(self, freq=self.freq[keep], psd=self.psd[keep])


def axis_samples(recording: Recording, axis) -> np.ndarray:
    """The samples along ``axis``: a channel name, or a direction (dx, dy, dz) projected onto."""
    if isinstance(axis, str):
        if axis not in recording.channels:
            raise ValueError(f"{recording.source}: axis {axis!r} was not recorded; it has {', '.join(recording.channels)}")
        return recording.channels[axis]
    direction = np.asarray(axis, dtype=float)
    if direction.shape != (3,) or not np.all(np.isfinite(direction)) or not np.any(direction):
        raise ValueError(f"a direction must be three finite numbers dx,dy,dz not all 0, got {axis!r}")
    missing = [a for a, d in zip("xyz", direction) if d and a not in recording.channels]
    if missing:
        raise ValueError(f"{recording.source}: the direction needs axis {missing[0]!r}, which was not recorded")
    direction = direction / np.linalg.norm(direction)
    return sum(d * recording.channels[a] for a, d in zip("xyz", direction) if d)


def spectrum(recording: Recording, axis="xyz", *, resolution: float = RESOLUTION, undo_sweep: bool = False) -> Spectrum:
    """Welch's PSD of ``recording`` along ``axis`` (``x``, ``y``, ``z``, a channel name, a direction,
    or ``xyz``: the sum of the recorded axes' spectra, as Klipper's ``psd_xyz``).

    Hann windows, segments of the power of two nearest 1/``resolution`` s but at most a quarter of
    the record, 75 % overlap over the record padded with zeros by 3/4 of a segment at each end (so
    every sample weighs the same: a swept excitation's spectrum is not rippled by the segmenting),
    the mean removed (gravity is not vibration).
    """
    if not (math.isfinite(resolution) and resolution > 0):
        raise ValueError(f"resolution must be a positive frequency step in Hz, got {resolution!r}")
    n = len(next(iter(recording.channels.values())))
    wanted = 2 ** round(math.log2(max(recording.fs / resolution, 16)))
    segment = int(min(wanted, 2 ** math.floor(math.log2(max(n // MIN_SEGMENTS, 16)))))
    settings = (f"Welch: Hann window, {segment} samples ({segment / recording.fs:.3g} s, "
                f"{recording.fs / segment:.3g} Hz resolution), 75 % overlap, mean removed")
    if axis == "xyz":
        names = [a for a in recording.channels]
        signals = [recording.channels[a] for a in names]
    else:
        signals = [axis_samples(recording, axis)]
    psd = None
    pad = 3 * segment // 4
    for samples in signals:
        # Hann windows overlapping by 3/4 have squares that sum to a constant, and the record padded by
        # 3/4 of a segment at each end is covered four times everywhere: every sample weighs the same.
        # (At 1/2 overlap a sweep's energy is weighted with a ripple of one hop's worth of frequency.)
        padded = np.concatenate([np.zeros(pad), samples - np.mean(samples), np.zeros(pad)])
        freq, p = welch(padded, recording.fs, window="hann", nperseg=segment, noverlap=pad, detrend=False)
        psd = p if psd is None else psd + p
    result = Spectrum(recording.source, axis if isinstance(axis, str) else "direction", freq[1:], psd[1:], settings)
    return undo_sweep_excitation(result) if undo_sweep else result


def undo_sweep_excitation(spectrum: Spectrum) -> Spectrum:
    """``spectrum`` divided by f^2: the machine's response per unit of the sweep's acceleration per
    hertz, squared (see the module docstring)."""
    if spectrum.sweep_undone:
        return spectrum
    return replace(spectrum, psd=spectrum.psd / spectrum.freq**2, sweep_undone=True,
                   settings=spectrum.settings + "; Klipper's sweep excitation (f^2) divided out")


def klipper_spectrum(names: list[str], values: np.ndarray, *, source: str) -> dict[str, Spectrum]:
    """The spectra of a Klipper processed-spectrum table, by axis (``x``, ``y``, ``z``, ``xyz``) or,
    for a table of combined data sets, by column name. Shaper columns (``zv(59.0)`` ...) are not
    spectra and are left out."""
    freq = values[:, 0]
    if np.any(np.diff(freq) <= 0) or freq[0] < 0:
        bad = int(np.flatnonzero(np.diff(freq) <= 0)[0]) + 3 if np.any(np.diff(freq) <= 0) else 2
        raise ValueError(f"{source}: line {bad}: expected increasing frequencies >= 0 in the freq column")
    spectra = {}
    for i, column in enumerate(names[1:], start=1):
        if "(" in column:  # a fitted shaper's response, not a measurement
            continue
        axis = column.removeprefix("psd_")
        if np.any(values[:, i] < 0):
            row = int(np.flatnonzero(values[:, i] < 0)[0]) + 2
            raise ValueError(f"{source}: line {row}: expected a power spectral density >= 0 in {column!r}")
        spectra[axis] = Spectrum(source, axis, freq[freq > 0], values[freq > 0, i],
                                 f"read from a Klipper spectrum file ({column})")
    if not spectra:
        raise ValueError(f"{source}: line 1: expected psd_x, psd_y, psd_z, psd_xyz or data-set columns after freq")
    return spectra
