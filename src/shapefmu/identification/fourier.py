"""The three spectral tools the way from a recording to its modes needs, in NumPy alone: Welch's
averaged periodogram, the short-time Fourier transform and a peak finder with prominences.

They compute what ``scipy.signal.welch``, ``stft`` and ``find_peaks`` compute for the settings
``spectra`` and ``modes`` use (``tests/test_fourier.py`` holds them to SciPy's to 1e-12), from the
definitions cited in each docstring. SciPy's signal package is not imported for them because
importing it loads SciPy's stats, interpolate and integrate packages too, which costs a raw
recording's identification more time than its spectra do.

Segments are taken a batch at a time, each batch at most ``BATCH_SAMPLES`` samples, so that a long
recording at a high overlap never holds all its windowed segments at once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

BATCH_SAMPLES = 1 << 22  # 32 MB of float64 per batch of windowed segments


@dataclass(frozen=True)
class Periodogram:
    """A one-sided power spectral density ``psd`` ((unit)^2/Hz) at ``freq`` (Hz), the average of
    ``segments`` modified periodograms."""

    freq: np.ndarray = field(repr=False)
    psd: np.ndarray = field(repr=False)
    segments: int


@dataclass(frozen=True)
class ShortTimeSpectrum:
    """The short-time Fourier transform ``z[f, t]`` at ``freq`` (Hz) of segments centred at ``times`` (s)."""

    freq: np.ndarray = field(repr=False)
    times: np.ndarray = field(repr=False)
    z: np.ndarray = field(repr=False)


@dataclass(frozen=True)
class Peaks:
    """The local maxima of a sequence (``indices``) and their ``prominences``, in increasing index."""

    indices: np.ndarray
    prominences: np.ndarray


def periodic_hann(length: int) -> np.ndarray:
    """The periodic Hann window, w[k] = 0.5 - 0.5 cos(2 pi k / length), k = 0 .. length - 1: one
    period of the raised cosine, the window whose shifts by a quarter or half of its length sum to a
    constant (what ``scipy.signal.get_window('hann', length)`` returns). It is evaluated as
    0.5 + 0.5 cos(theta), theta from -pi to pi in ``length`` steps (the same values: cos(x - pi) =
    -cos x), which rounds as SciPy's does, so that the spectra are SciPy's to the last bit.

    >>> [round(float(w), 12) for w in periodic_hann(4)]
    [0.0, 0.5, 1.0, 0.5]
    """
    if not (isinstance(length, int) and length >= 2):
        raise ValueError(f"length must be an integer >= 2, got {length!r}")
    return 0.5 + 0.5 * np.cos(np.linspace(-np.pi, np.pi, length + 1)[:length])


def _segments_checked(samples, fs: float, window, overlap: int) -> tuple[np.ndarray, np.ndarray, int]:
    """(samples, window, hop) as arrays of float, or a ValueError naming what is out of range."""
    x = np.asarray(samples, dtype=float)
    w = np.asarray(window, dtype=float)
    if w.ndim != 1 or w.size < 2 or not np.all(np.isfinite(w)) or not np.any(w):
        raise ValueError(f"window must be a one-dimensional array of at least 2 finite values, not all 0, "
                         f"got shape {w.shape}")
    if not (math.isfinite(fs) and fs > 0):
        raise ValueError(f"fs must be a positive sampling rate in Hz, got {fs!r}")
    if not (isinstance(overlap, (int, np.integer)) and 0 <= overlap < w.size):
        raise ValueError(f"overlap must be an integer in [0, {w.size - 1}] (the window has {w.size} samples), "
                         f"got {overlap!r}")
    if x.ndim != 1 or x.size < w.size:
        raise ValueError(f"samples must be one-dimensional and at least as many as the window's {w.size}, "
                         f"got shape {x.shape}")
    return x, w, w.size - int(overlap)


def _windowed_spectra(x: np.ndarray, w: np.ndarray, hop: int, detrend: bool):
    """The Fourier transforms of the windowed segments x[k hop : k hop + len(w)], k = 0, 1, ... (the
    last whole one), a batch of rows at a time; with ``detrend``, each segment's mean removed first."""
    count = (x.size - w.size) // hop + 1
    per_batch = max(1, BATCH_SAMPLES // w.size)
    starts = np.lib.stride_tricks.sliding_window_view(x, w.size)[::hop]
    for first in range(0, count, per_batch):
        batch = starts[first:first + per_batch]
        if detrend:
            batch = batch - batch.mean(axis=1, keepdims=True)
        yield np.fft.rfft(batch * w, axis=1)


def welch_psd(samples, fs: float, window, overlap: int, *, detrend: bool) -> Periodogram:
    """Welch's power spectral density of ``samples`` taken at ``fs`` Hz: the mean of the modified
    periodograms of the segments of ``len(window)`` samples, each ``overlap`` samples over the one
    before, as many whole segments as fit from the first sample on; with ``detrend`` each segment's
    mean is removed before it is windowed.

    Welch (1967), "The use of fast Fourier transform for the estimation of power spectra: a method
    based on time averaging over short, modified periodograms", IEEE Trans. Audio Electroacoust.
    AU-15(2), 70-73: segment k windowed by W gives A_k(n) = sum_j X_k(j) W(j) exp(-2 pi i j n / L)
    (Welch writes it with a factor 1/L, and I_k with L^2 more), its modified periodogram
    I_k = |A_k|^2 / (L U) with U = sum_j W(j)^2 / L, and the estimate is the average of the I_k over
    the segments. In density units per hertz (what ``scaling='density'`` means in
    SciPy) that is |A_k|^2 / (fs sum_j W(j)^2). A real signal's power at -f equals that at +f, so the
    one-sided density doubles every bin but 0 Hz and, for an even L, fs/2, which have no mirror.

    >>> tone = np.cos(2 * np.pi * 100.0 * np.arange(4000) / 1000.0)
    >>> found = welch_psd(tone, 1000.0, periodic_hann(200), 100, detrend=False)
    >>> float(found.freq[np.argmax(found.psd)]), found.segments
    (100.0, 39)
    >>> round(float(np.sum(found.psd) * (found.freq[1] - found.freq[0])), 6)  # the mean square, 1/2
    0.5
    """
    x, w, hop = _segments_checked(samples, fs, window, overlap)
    total = np.zeros(w.size // 2 + 1)
    segments = 0
    for spectra in _windowed_spectra(x, w, hop, detrend):
        total += np.sum(spectra.real**2 + spectra.imag**2, axis=0)
        segments += spectra.shape[0]
    psd = total / (segments * fs * np.sum(w * w))
    mirrored = slice(1, -1) if w.size % 2 == 0 else slice(1, None)
    psd[mirrored] *= 2
    return Periodogram(np.fft.rfftfreq(w.size, 1 / fs), psd, segments)


def stft(samples, fs: float, window, overlap: int) -> ShortTimeSpectrum:
    """The short-time Fourier transform of ``samples`` taken at ``fs`` Hz: for each whole segment of
    ``len(window)`` samples, ``overlap`` samples over the one before, from the first sample on (no
    padding at either end), the one-sided transform of the windowed segment over the window's sum,
    Z[n, k] = sum_j x[k hop + j] W(j) exp(-2 pi i j n / L) / sum_j W(j), so that a sine of amplitude a
    on a bin has |Z| = a / 2 (SciPy's ``stft`` with ``boundary=None, padded=False``). Each segment's
    time is its centre, (k hop + L / 2) / fs.

    >>> found = stft(np.cos(2 * np.pi * 125.0 * np.arange(64) / 1000.0), 1000.0, periodic_hann(16), 8)
    >>> found.z.shape, found.times.tolist()[:2], round(float(np.abs(found.z[2, 0])), 12)
    ((9, 7), [0.008, 0.016], 0.5)
    """
    x, w, hop = _segments_checked(samples, fs, window, overlap)
    z = np.concatenate(list(_windowed_spectra(x, w, hop, detrend=False))) / np.sum(w)
    times = (np.arange(z.shape[0]) * hop + w.size / 2) / fs
    return ShortTimeSpectrum(np.fft.rfftfreq(w.size, 1 / fs), times, z.T)


def find_peaks(values, min_height: float = -math.inf) -> Peaks:
    """The local maxima of ``values`` at least ``min_height`` high, with their prominences (what
    ``scipy.signal.find_peaks(values, height=min_height, prominence=0)`` finds).

    A local maximum, as SciPy's documentation of ``find_peaks`` defines it, is one sample, or a run of
    equal samples (a plateau), with a smaller sample on each side: the first and last samples are
    never one. A plateau's index is its middle sample (the left one of the two middles of an even run).

    A peak's prominence, as SciPy's documentation of ``peak_prominences`` defines it (the topographic
    prominence): extend a level line from the peak to each side until it meets a strictly higher
    sample or the end; on each side the lowest sample passed over is that side's base; the prominence
    is the peak's height above the higher of its two bases.

    >>> found = find_peaks([0.0, 3.0, 1.0, 2.0, 2.0, 0.5, 4.0, 4.0, 4.0, 1.0])
    >>> found.indices.tolist(), found.prominences.tolist()
    ([1, 3, 7], [2.5, 1.0, 3.0])
    """
    x = np.asarray(values, dtype=float)
    if x.ndim != 1 or not np.all(np.isfinite(x)):
        raise ValueError(f"values must be a one-dimensional sequence of finite numbers, got shape {x.shape}"
                         + ("" if x.ndim != 1 else " with a value that is not finite"))
    if math.isnan(min_height):
        raise ValueError("min_height must be a number, got nan")
    steps = np.flatnonzero(np.diff(x))  # x[i + 1] != x[i] at each i of steps
    rises = x[steps + 1] > x[steps]
    # a rise followed, over equal samples only, by a fall: the plateau steps[k] + 1 .. steps[k + 1]
    tops = np.flatnonzero(rises[:-1] & ~rises[1:])
    peaks = (steps[tops] + 1 + steps[tops + 1]) // 2
    left = _bases(x, peaks)
    right = _bases(x[::-1], x.size - 1 - peaks[::-1])[::-1]
    keep = x[peaks] >= min_height
    return Peaks(peaks[keep], (x[peaks] - np.maximum(left, right))[keep])


def _bases(x: np.ndarray, peaks: np.ndarray) -> np.ndarray:
    """For each of ``peaks`` (increasing, none at 0), the lowest sample from it back to the nearest
    strictly higher sample or to the start (itself included): its base on the left.

    The nearest strictly higher sample lies in a run of samples higher than the peak, and such a run
    holds a local maximum unless it reaches the start; so the search need only visit the peaks and
    the first sample, with the lowest sample between each two neighbours. A stack of the peaks not
    yet topped (the monotonic stack of "previous greater element"), each with the lowest sample back
    to the one below it, does that in one pass: O(samples)."""
    if not peaks.size:
        return np.empty(0)
    marks = np.concatenate([[0], peaks])
    gaps = np.minimum.reduceat(x[:peaks[-1] + 1], marks[:-1] + 1).tolist()  # lowest in (marks[k - 1], marks[k]]
    heights, lows = [float(x[0])], [float(x[0])]
    bases = []
    for height, low in zip(x[peaks].tolist(), gaps):
        while heights and heights[-1] <= height:  # a level line passes an equal height
            heights.pop()
            low = min(low, lows.pop())
        bases.append(low)
        heights.append(height)
        lows.append(low)
    return np.array(bases)
