"""Klipper's side of a recommendation, rebuilt from its definitions: its six shapers, how it reads and
normalises a spectrum, its frequency scan of each shaper and its pick (``calibrate_shaper.py`` and
``SHAPER_CALIBRATE``), so that shapefmu can say what Klipper recommends and judge any design by the
numbers Klipper would print (``metrics``).

Sources, read at Klipper commit 84104bbb (``klippy/extras/shaper_defs.py``, ``shaper_calibrate.py``,
``scripts/calibrate_shaper.py``; docs/Measuring_Resonances.md, docs/Config_Reference.md
``[input_shaper]``); the code is Klipper's and GPL, none of it is copied here.

The shapers, for a frequency f and the damping ratio zeta they are designed for (Klipper's
``damping_ratio``, 0.1 by default), df = sqrt(1 - zeta^2), t_d = 1 / (f df), K = exp(-zeta pi / df):

- ``zv``: 1, K at 0, t_d / 2; ``zvd``: 1, 2K, K^2 at 0, t_d / 2, t_d (Singer and Seering);
- ``mzv`` (Klipper's default form, n = 3 impulses over t = 0.75 of a damped period): undamped, the
  amplitudes 1 - 1/sqrt 2, sqrt 2 - 1, 1 - 1/sqrt 2 at 0, 3/8, 3/4 of the period vanish the response at
  f and at 5/3 f; damped, impulse i is scaled by exp(-0.75 zeta pi / df)^i;
- ``ei``: Singhose's extra-insensitive shaper for a 5 % tolerance (vtol = 1/20), three impulses at
  0, t2 t_d, t_d whose amplitudes and t2 are quadratic / cubic fits in zeta (the coefficients below);
- ``2hump_ei``, ``3hump_ei``: the two- and three-hump EI shapers of Singhose, Porter, Tuttle and
  Singer ("Vibration reduction using multi-hump input shapers", ASME J. Dyn. Sys. 1997), each impulse's
  amplitude and time (in periods 1/f, not damped periods) a cubic in zeta, with the coefficients below.

Each has the lowest frequency Klipper scans it from (its projected max_accel is about 1500 mm/s^2
there) and the largest damping ratio Klipper accepts for it (``max_damping_ratio``).

A spectrum file (``parse_log``): a resonances or calibration_data CSV whose first line (after any '#'
lines) begins ``freq,psd_x,psd_y,psd_z,psd_xyz`` is one data set judged on its psd_xyz column; other
``freq,...`` headers name data sets column by column up to ``shapers:``. Unless the header holds
``,shapers:`` (what Klipper itself writes beside fitted shapers, already normalised), the power is
normalised (``normalize_to_frequencies``): divided by f + 0.1 and, below 2 * 5 Hz, multiplied by
exp(1 - (10 / (f + 0.1))^2). An older calibration_data file, whose header lists the shapers
(``...,psd_xyz,zv(52.6),...``) without ``shapers:``, is normalised again: that is what Klipper does
with it today, and Klipper is the judge. A raw accelerometer recording (``calc_freq_response``): Welch's
PSD of each axis, a symmetric Kaiser window (beta 6) of 2^ceil(log2(fs / 2)) samples, half overlapping, each
segment's mean removed, fs = samples / duration; the axes summed, then normalised the same way.

The scan (``fit_shaper``): frequencies from the shaper's lowest in 0.2 Hz steps below 150 Hz, each
judged (``metrics``), from the highest down; the best is the least vibration (the highest frequency
among equals), and the one chosen, going up from the lowest, is any with vibration below 1.1 times the
best's plus 0.05 % and a lower score. The pick (``find_best_shaper``) goes over zv, mzv, ei, 2hump_ei,
3hump_ei (not zvd) in that order: a shaper replaces the pick if its score is 20 % lower, or 5 % lower
with 10 % less smoothing; then any frequency of that shaper's scan with less vibration and less
smoothing than the pick replaces it; at the end a zv pick gives way to the first other shaper with a
tenth less vibration.
"""

from __future__ import annotations

import io
import math
import os
from dataclasses import dataclass

import numpy as np

from shapefmu.identification import metrics
from shapefmu.identification.fourier import welch_psd
from shapefmu.identification.spectra import Spectrum

KLIPPER_COMMIT = "84104bbbd7625d28b4eaaad83f4562972460ecd9"  # where the definitions were read
MIN_FREQ = 5.0  # Hz: the normalisation tapers the spectrum below twice this
MAX_SHAPER_FREQ = 150.0  # Hz: the top of the scan
FREQ_STEP = 0.2  # Hz
DEFAULT_DAMPING_RATIO = 0.1
WINDOW_SECONDS = 0.5  # a Welch segment holds the power of two at or above fs * 0.5 samples
AUTOTUNE = ("zv", "mzv", "ei", "2hump_ei", "3hump_ei")
_EI_VTOL = 1 / 20
# (time, amplitude) coefficients of the multi-hump EI shapers: row i is impulse i, c0 + c1 z + c2 z^2 + c3 z^3
_TWO_HUMP = ([[0.0, 0.0, 0.0, 0.0], [0.49890, 0.16270, -0.54262, 6.16180], [0.99748, 0.18382, -1.58270, 8.17120],
              [1.49920, -0.09297, -0.28338, 1.85710]],
             [[0.16054, 0.76699, 2.26560, -1.22750], [0.33911, 0.45081, -2.58080, 1.73650],
              [0.34089, -0.61533, -0.68765, 0.42261], [0.15997, -0.60246, 1.00280, -0.93145]])
_THREE_HUMP = ([[0.0, 0.0, 0.0, 0.0], [0.49974, 0.23834, 0.44559, 12.4720], [0.99849, 0.29808, -2.36460, 23.3990],
                [1.49870, 0.10306, -2.01390, 17.0320], [1.99960, -0.28231, 0.61536, 5.40450]],
               [[0.11275, 0.76632, 3.29160, -1.44380], [0.23698, 0.61164, -2.57850, 4.85220],
                [0.30008, -0.19062, -2.14560, 0.13744], [0.23775, -0.73297, 0.46885, -2.08650],
                [0.11244, -0.45439, 0.96382, -1.46000]])


def _zv(f, zeta):
    df = math.sqrt(1 - zeta * zeta)
    k, t_d = math.exp(-zeta * math.pi / df), 1 / (f * df)
    return [0.0, 0.5 * t_d], [1.0, k]


def _zvd(f, zeta):
    df = math.sqrt(1 - zeta * zeta)
    k, t_d = math.exp(-zeta * math.pi / df), 1 / (f * df)
    return [0.0, 0.5 * t_d, t_d], [1.0, 2 * k, k * k]


def _mzv(f, zeta):
    df = math.sqrt(1 - zeta * zeta)
    k, t_d = math.exp(-0.75 * zeta * math.pi / df), 1 / (f * df)
    side = 1 - 1 / math.sqrt(2)
    return [0.0, 0.375 * t_d, 0.75 * t_d], [side, (math.sqrt(2) - 1) * k, side * k * k]


def _ei(f, zeta):
    df = math.sqrt(1 - zeta * zeta)
    t_d, v = 1 / (f * df), _EI_VTOL
    a1 = (0.24968 + 0.24961 * v) + ((0.80008 + 1.23328 * v) + (0.49599 + 3.17316 * v) * zeta) * zeta
    a3 = (0.25149 + 0.21474 * v) + ((-0.83249 + 1.41498 * v) + (0.85181 - 4.90094 * v) * zeta) * zeta
    t2 = 0.4999 + (((0.46159 + 8.57843 * v) * v) + (((4.26169 - 108.644 * v) * v)
                                                    + ((1.75601 + 336.989 * v) * v) * zeta) * zeta) * zeta
    return [0.0, t2 * t_d, t_d], [a1, 1 - a1 - a3, a3]


def _hump(coefficients):
    times, amplitudes = (np.asarray(c) for c in coefficients)

    def design(f, zeta):
        powers = zeta ** np.arange(4)
        return list(times @ powers / f), list(amplitudes @ powers)

    return design


@dataclass(frozen=True)
class ShaperType:
    """One of Klipper's shapers: its ``name`` as Klipper spells it, the lowest frequency Klipper scans
    it from (Hz), the largest damping ratio Klipper accepts for it, and its design."""

    name: str
    min_freq: float
    max_damping_ratio: float
    _design: object

    def impulses(self, freq: float, damping_ratio: float = DEFAULT_DAMPING_RATIO) -> tuple[np.ndarray, np.ndarray]:
        """(times s, amplitudes), not normalised, of this shaper at ``freq`` Hz for ``damping_ratio``.

        >>> [round(float(t), 6) for t in SHAPERS["zv"].impulses(50.0, 0.0)[0]]
        [0.0, 0.01]
        """
        if not (math.isfinite(freq) and freq > 0):
            raise ValueError(f"the {self.name} shaper's frequency must be > 0 Hz, got {freq!r}")
        if not (0 <= damping_ratio <= self.max_damping_ratio):
            raise ValueError(f"the {self.name} shaper's damping_ratio must be in [0, {self.max_damping_ratio}], "
                             f"got {damping_ratio!r}")
        times, amplitudes = self._design(float(freq), float(damping_ratio))
        return np.asarray(times, dtype=float), np.asarray(amplitudes, dtype=float)


SHAPERS = {s.name: s for s in (
    ShaperType("zv", 21.0, 0.99, _zv), ShaperType("mzv", 23.0, 0.99, _mzv), ShaperType("zvd", 29.0, 0.99, _zvd),
    ShaperType("ei", 29.0, 0.4, _ei), ShaperType("2hump_ei", 39.0, 0.3, _hump(_TWO_HUMP)),
    ShaperType("3hump_ei", 48.0, 0.2, _hump(_THREE_HUMP)))}


def normalize_psd(freq, psd) -> np.ndarray:
    """Klipper's normalised power (module docstring): P / (f + 0.1), tapered below 10 Hz.

    >>> [round(float(p), 6) for p in normalize_psd([0.0, 9.9, 20.0], [1.0, 1.0, 1.0])]
    [0.0, 0.1, 0.049751]
    """
    freq, psd = np.asarray(freq, dtype=float), np.asarray(psd, dtype=float)
    out = psd / (freq + 0.1)
    low = freq < 2 * MIN_FREQ
    out[low] *= np.exp(1 - (2 * MIN_FREQ / (freq[low] + 0.1)) ** 2)
    return out


def read_spectrum_file(path) -> dict[str, Spectrum]:
    """The data sets of a Klipper resonances or calibration_data file as Klipper judges them (module
    docstring): for a ``psd_xyz`` file, ``xyz`` (what Klipper scores) and ``x``, ``y``, ``z``; otherwise
    one per named data set. Each is normalised unless the header holds ``,shapers:``.

    >>> import pathlib, tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = pathlib.Path(folder) / "resonances_x.csv"
    ...     _ = path.write_text("freq,psd_x,psd_y,psd_z,psd_xyz\\n10.0,1,0,0,1\\n20.0,2,0,0,2\\n")
    ...     sets = read_spectrum_file(path)
    >>> sorted(sets), [round(float(p), 6) for p in sets["xyz"].psd]  # 1 / 10.1 and 2 / 20.1
    (['x', 'xyz', 'y', 'z'], [0.09901, 0.099502])
    """
    from shapefmu.identification.recordings import read_bytes

    name = os.fspath(path)
    lines = read_bytes(path).decode("utf-8", "replace").lstrip("\ufeff").splitlines()
    first = next((i for i, line in enumerate(lines) if not line.startswith("#")), len(lines))
    header = lines[first] if first < len(lines) else ""
    if not header.startswith("freq,"):
        raise ValueError(f"{name}: line {first + 1}: expected a Klipper spectrum header 'freq,psd_x,psd_y,psd_z,psd_xyz' "
                         f"or 'freq,<data set>,...', got {header[:60]!r}")
    columns = [c.strip() for c in header.split(",")]
    try:  # Klipper's own reading: missing fields count as 0
        values = np.genfromtxt(io.StringIO("\n".join(lines[first + 1:])), delimiter=",", comments="#",
                               filling_values=0.0, ndmin=2, invalid_raise=True)
    except ValueError as error:
        raise ValueError(f"{name}: expected rows of numbers after line {first + 1} ({str(error).splitlines()[-1]})") from None
    if values.size == 0 or values.shape[0] < 2:
        raise ValueError(f"{name}: expected at least two rows of spectrum after line {first + 1}")
    bad = np.flatnonzero(~np.all(np.isfinite(values), axis=1))
    if bad.size:
        raise ValueError(f"{name}: line {first + 2 + int(bad[0])}: expected finite numbers")
    freq = values[:, 0]
    steps = np.flatnonzero(np.diff(freq) <= 0)
    if steps.size or freq[0] < 0:
        raise ValueError(f"{name}: line {first + 3 + int(steps[0]) if steps.size else first + 2}: expected increasing "
                         f"frequencies >= 0 in the freq column")
    normalised = ",shapers:" not in header
    if header.startswith("freq,psd_x,psd_y,psd_z,psd_xyz"):
        sets = {"xyz": 4, "x": 1, "y": 2, "z": 3}
    else:
        ends = columns.index("shapers:") if "shapers:" in columns else len(columns)
        sets = {column: i for i, column in enumerate(columns[1:ends], start=1)}
    note = ("normalised as Klipper does (P / (f + 0.1), tapered below 10 Hz)" if normalised
            else "already normalised (the header holds ',shapers:')")
    spectra = {}
    for key, i in sets.items():
        if i >= values.shape[1]:
            raise ValueError(f"{name}: the header names {len(columns)} columns, the rows hold {values.shape[1]}")
        psd = values[:, i]
        if np.any(psd < 0):
            raise ValueError(f"{name}: line {first + 2 + int(np.flatnonzero(psd < 0)[0])}: expected a power >= 0")
        psd = normalize_psd(freq, psd) if normalised else psd.copy()
        spectra[key] = Spectrum(name, key, freq.copy(), psd, f"Klipper's reading of {columns[i]}, {note}")
    return spectra


def recording_psd(recording, axis="xyz") -> Spectrum:
    """Klipper's normalised spectrum of a recording's samples (module docstring): ``xyz`` sums every
    recorded axis, as Klipper does; a single axis or direction takes those samples alone.

    >>> from shapefmu.identification.recordings import Recording
    >>> t = np.arange(4 * 3200) / 3200
    >>> spectrum = recording_psd(Recording("sine", "table", 3200.0, {"x": np.sin(2 * np.pi * 40 * t)}, "mm/s^2"))
    >>> bin_width = spectrum.freq[1] - spectrum.freq[0]  # 3200 Hz over 2048 samples
    >>> round(float(bin_width), 3), bool(abs(spectrum.freq[np.argmax(spectrum.psd)] - 40) < bin_width / 2)
    (1.563, True)
    """
    from shapefmu.identification.spectra import axis_samples

    signals = list(recording.channels.values()) if axis == "xyz" else [axis_samples(recording, axis)]
    n = len(signals[0])
    rate = recording.fs * n / (n - 1)  # Klipper's rate: samples over the time from the first to the last
    segment = 1 << int(rate * WINDOW_SECONDS - 1).bit_length()
    if n <= segment:
        raise ValueError(f"{recording.source}: {n} samples are too few for Klipper's spectrum, which needs more than "
                         f"{segment} at {rate:.0f} Hz")
    total = None
    for samples in signals:
        # the symmetric Kaiser window (numpy's): scipy's ("kaiser", 6.0) would be the periodic one
        found = welch_psd(samples, rate, np.kaiser(segment, 6.0), segment // 2, detrend=True)
        total = found.psd if total is None else total + found.psd
    name = axis if isinstance(axis, str) else "direction"
    return Spectrum(recording.source, name, found.freq, normalize_psd(found.freq, total),
                    f"Klipper's spectrum: Welch, Kaiser window (beta 6) of {segment} samples, half overlapping, "
                    f"normalised (P / (f + 0.1), tapered below 10 Hz)")


def judged_spectra(recording, source) -> list[Spectrum]:
    """The spectra Klipper judges shapers on, whatever axis the test moved: of a recording's samples,
    every recorded axis summed (``recording_psd``); of a spectrum file (``recording`` None), its psd_xyz,
    or each of its data sets (the worst of them counts).

    >>> from shapefmu.identification.recordings import Recording
    >>> t = np.arange(4 * 3200) / 3200
    >>> moved = {"x": np.sin(2 * np.pi * 40 * t), "y": np.zeros(t.size), "z": np.zeros(t.size)}
    >>> [s.axis for s in judged_spectra(Recording("sine", "table", 3200.0, moved, "mm/s^2"), "sine")]
    ['xyz']
    """
    if recording is not None:
        return [recording_psd(recording, "xyz")]
    sets = read_spectrum_file(source)
    return [sets["xyz"]] if "xyz" in sets else list(sets.values())


@dataclass(frozen=True)
class Fitted:
    """One frequency of Klipper's scan of a shaper and its figures (``metrics``)."""

    name: str
    freq: float
    vibration: float
    smoothing: float
    max_accel: float
    score: float


def scan_frequencies(name: str) -> np.ndarray:
    """The frequencies Klipper tries for shaper ``name``: from its lowest in 0.2 Hz steps below 150 Hz
    (numpy's arange, as Klipper builds them, to the last bit).

    >>> scan_frequencies("zv")[:3].tolist(), scan_frequencies("zv").size  # (150 - 21) / 0.2
    ([21.0, 21.2, 21.4], 645)
    """
    return np.arange(SHAPERS[name].min_freq, MAX_SHAPER_FREQ, FREQ_STEP)


def fit(judge, name: str, freqs=None, damping_ratio: float = DEFAULT_DAMPING_RATIO) -> tuple[Fitted, list[Fitted]]:
    """Klipper's scan of shaper ``name`` over ``freqs`` (default ``scan_frequencies``) judged by
    ``judge`` (a ``judge.Judge``): (the frequency Klipper chooses, every frequency from the highest).

    >>> from shapefmu.identification.judge import Judge
    >>> freq = np.arange(1.0, 101.0)
    >>> chosen, scanned = fit(Judge([(freq, np.exp(-((freq - 40) / 3) ** 2))]), "zv")  # a peak at 40 Hz
    >>> round(chosen.freq), len(scanned)  # ZV's zero on the peak
    (40, 645)
    """
    freqs = scan_frequencies(name) if freqs is None else np.asarray(freqs, dtype=float)
    shaper = SHAPERS[name]
    designs = [shaper.impulses(f, damping_ratio) for f in freqs[::-1]]
    times, amplitudes = np.array([d[0] for d in designs]), np.array([d[1] for d in designs])
    scores = judge.measures(times, amplitudes, max_freq=max(metrics.MAX_FREQ, float(freqs.max())))
    results = [Fitted(name, float(f), *(float(x) for x in row)) for f, row in zip(freqs[::-1], zip(*scores))]
    best = None
    for r in results:  # from the highest frequency down: the first of the least vibration
        if best is None or best.vibration > r.vibration:
            best = r
    chosen = best
    for r in results[::-1]:  # from the lowest up: a lower score at nearly the best vibration
        if r.vibration < best.vibration * 1.1 + 0.0005 and r.score < chosen.score:
            chosen = r
    return chosen, results


def pick(judge, damping_ratio: float = DEFAULT_DAMPING_RATIO) -> tuple[Fitted, tuple[Fitted, ...]]:
    """Klipper's recommendation on ``judge``'s spectra (module docstring): (the pick, the shaper
    chosen for each of zv, mzv, ei, 2hump_ei, 3hump_ei).

    >>> from shapefmu.identification.judge import Judge
    >>> freq = np.arange(1.0, 101.0)
    >>> best, chosen = pick(Judge([(freq, np.exp(-((freq - 40) / 3) ** 2))]))  # a peak at 40 Hz
    >>> [c.name for c in chosen], best.name in AUTOTUNE
    (['zv', 'mzv', 'ei', '2hump_ei', '3hump_ei'], True)
    """
    best, chosen = None, []
    for name in AUTOTUNE:
        shaper, results = fit(judge, name, damping_ratio=damping_ratio)
        if (best is None or shaper.score * 1.2 < best.score
                or (shaper.score * 1.05 < best.score and shaper.smoothing * 1.1 < best.smoothing)):
            best = shaper
        for r in results[::-1]:
            if r.vibration < best.vibration and r.smoothing < best.smoothing:
                best = shaper = r
        chosen.append(shaper)
    if best.name == "zv":
        best = next((s for s in chosen if s.name != "zv" and s.vibration * 1.1 < best.vibration), best)
    return best, tuple(chosen)


def config_lines(name: str, freq: float, axes=("x",), damping_ratio: float = DEFAULT_DAMPING_RATIO) -> str:
    """The ``[input_shaper]`` section that runs shaper ``name`` at ``freq`` Hz on ``axes``.

    >>> print(config_lines("mzv", 46.6, ("x",)))
    [input_shaper]
    shaper_type_x: mzv
    shaper_freq_x: 46.6
    """
    lines = ["[input_shaper]"]
    for axis in axes:
        lines += [f"shaper_type_{axis}: {name}", f"shaper_freq_{axis}: {freq:.{_decimals(freq)}f}"]
        if damping_ratio != DEFAULT_DAMPING_RATIO:
            lines.append(f"damping_ratio_{axis}: {damping_ratio:g}")
    return "\n".join(lines)


def _decimals(freq: float) -> int:
    """Decimals that write ``freq`` back exactly to 0.01 Hz (1 for Klipper's own 0.2 Hz grid)."""
    return 1 if abs(round(freq, 1) - freq) < 1e-9 else 2
