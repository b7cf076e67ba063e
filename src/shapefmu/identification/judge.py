"""Designs judged by Klipper's measures (``metrics``) on one or more measured spectra, worst case over
them, and the record of a judged design (``Candidate``) that every family and firmware target shares.

Beside Klipper's measures stands one of ours, named as ours: ``at_modes``, the worst V at the identified
modes, each at its own damping and Klipper's test dampings (what a move keeps of each mode, the number a
co-simulation of the machine checks), which Klipper's measure can hide since it discounts what lies
under max / 20.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from shapefmu.identification import metrics


@dataclass(frozen=True)
class Candidate:
    """A judged design: ``kind`` as its firmware spells it (or a design-layer kind for ``fmu``),
    ``family`` (klipper, rrf, marlin, train, single, pair, multi, window), the ``frequencies`` (Hz) and
    ``zetas`` it was designed for, Klipper's ``vibration`` (share), ``smoothing`` (mm), ``max_accel``
    (mm/s^2) and ``score``, our ``at_modes``, its ``duration`` (s), its impulses (``ts`` set for a
    sampled filter, whose impulses are its taps), the firmware ``line`` that runs it, the start values
    of the Shaper or ShapeFilter FMU that runs it (``fmu``, None when no FMU kind holds it) and whether it
    passes the guards of ``recommend`` (``guarded``)."""

    kind: str
    family: str
    frequencies: tuple[float, ...]
    zetas: tuple[float, ...]
    vibration: float
    smoothing: float
    max_accel: float
    score: float
    at_modes: float
    duration: float
    times: tuple[float, ...] = field(repr=False)
    amplitudes: tuple[float, ...] = field(repr=False)
    ts: float | None = None
    line: str | None = None
    fmu: tuple[tuple[str, object], ...] | None = None
    guarded: bool = True

    @property
    def label(self) -> str:
        """The kind, marked ``x2`` for a pair of single-mode designs convolved.

        >>> zv = Candidate("zv", "klipper", (40.0,), (0.0,), 0.12, 0.1, 6000.0, 1e-3, 0.0, 0.0125,
        ...                (0.0, 0.0125), (0.5, 0.5))
        >>> zv.label, dataclasses.replace(zv, family="pair").label
        ('zv', 'zv x2')
        """
        return f"{self.kind} x2" if self.family == "pair" else self.kind

    def same(self, other: Candidate) -> bool:
        """The same impulses (or taps) as ``other``.

        >>> zv = Candidate("zv", "klipper", (40.0,), (0.0,), 0.12, 0.1, 6000.0, 1e-3, 0.0, 0.0125,
        ...                (0.0, 0.0125), (0.5, 0.5))
        >>> zv.same(dataclasses.replace(zv, kind="renamed")), zv.same(dataclasses.replace(zv, amplitudes=(0.6, 0.4)))
        (True, False)
        """
        return self.times == other.times and self.amplitudes == other.amplitudes

    def dominates(self, other: Candidate) -> bool:
        """No more vibration and no less max_accel than ``other`` (Klipper's measures).

        >>> zv = Candidate("zv", "klipper", (40.0,), (0.0,), 0.12, 0.1, 6000.0, 1e-3, 0.0, 0.0125,
        ...                (0.0, 0.0125), (0.5, 0.5))
        >>> zv.dominates(dataclasses.replace(zv, vibration=0.2)), zv.dominates(dataclasses.replace(zv, max_accel=1e9))
        (True, False)
        """
        return self.vibration <= other.vibration and self.max_accel >= other.max_accel

    def row(self) -> dict:
        """The JSON row: measures, impulses (or taps and ts) and the firmware line.

        >>> zv = Candidate("zv", "klipper", (40.0,), (0.0,), 0.12, 0.1, 6000.0, 1e-3, 0.0, 0.0125,
        ...                (0.0, 0.0125), (0.5, 0.5))
        >>> zv.row()["impulse_times_s"], zv.row()["impulse_amplitudes"], zv.row()["firmware_line"]
        ([0.0, 0.0125], [0.5, 0.5], None)
        """
        shape = ({"taps": list(self.amplitudes), "ts": self.ts} if self.ts is not None
                 else {"impulse_times_s": list(self.times), "impulse_amplitudes": list(self.amplitudes)})
        return {"shaper": self.label, "family": self.family, "frequencies_hz": list(self.frequencies),
                "zetas": list(self.zetas), "vibration": self.vibration, "smoothing_mm": self.smoothing,
                "max_accel": self.max_accel, "score": self.score, "ours_residual_at_modes": self.at_modes,
                "duration_s": self.duration, **shape, "firmware_line": self.line,
                "passes_guards": self.guarded}  # the CLI adds the FMU that runs it (fmi is a layer above)


class Judge:
    """Klipper's measures of batches of impulse sets on ``spectra`` (worst case over them), at the
    settings Klipper takes: test ``dampings``, ``scv`` (mm/s), ``accel`` (mm/s^2, where smoothing and
    the score are taken) and ``max_smoothing`` (mm, the bound of max_accel); ``max_freq`` is where the
    spectra are cut (Klipper's 200 Hz, or its --max_freq). ``modes`` ((Hz, zeta) pairs) are where
    ``at_modes`` is taken.

    >>> judge = Judge([(np.linspace(1, 100, 100), np.exp(-((np.linspace(1, 100, 100) - 40) / 3) ** 2))])
    >>> vibration, smoothing, accel, score = judge.measures([[0.0, 0.0125]], [[1.0, 1.0]])  # ZV at 40 Hz
    >>> round(float(vibration[0]), 4), round(float(accel[0]))  # undamped ZV: 12 % left at damping 0.15
    (0.1247, 6144)
    """

    CHUNK = 2_000_000

    def __init__(self, spectra, *, dampings=metrics.KLIPPER_DAMPINGS, scv: float = metrics.DEFAULT_SCV,
                 accel: float = metrics.DEFAULT_ACCEL, max_smoothing: float = metrics.DEFAULT_MAX_SMOOTHING,
                 max_freq: float = metrics.MAX_FREQ, modes=()):
        self.spectra = [(np.asarray(s.freq if hasattr(s, "freq") else s[0], dtype=float),
                         np.asarray(s.psd if hasattr(s, "psd") else s[1], dtype=float)) for s in spectra]
        self.dampings = tuple(float(z) for z in dampings)
        self.scv, self.accel, self.max_smoothing, self.max_freq = scv, accel, max_smoothing, max_freq
        self.modes = tuple((float(f), float(z)) for f, z in modes)
        self._meters: dict[tuple[float, float], list[metrics.VibrationMeter]] = {}

    def meters(self, max_freq: float | None = None, max_gain: float = 1.0) -> list[metrics.VibrationMeter]:
        """One ``VibrationMeter`` per spectrum, cut at ``max_freq`` (default the judge's).

        >>> freq = np.arange(1.0, 101.0)
        >>> judge = Judge([(freq, np.exp(-((freq - 40) / 3) ** 2))])  # a peak at 40 Hz
        >>> len(judge.meters()), judge.meters() is judge.meters()  # one spectrum; kept for the next batch
        (1, True)
        """
        key = (self.max_freq if max_freq is None else max_freq, max_gain)
        if key not in self._meters:
            self._meters[key] = [metrics.VibrationMeter(f, p, self.dampings, key[0], max_gain) for f, p in self.spectra]
        return self._meters[key]

    def vibration(self, times, amplitudes, max_freq: float | None = None) -> np.ndarray:
        """Klipper's remaining vibration of each design of the batch, worst over the spectra (in chunks
        of ``CHUNK`` values of V, so a scan of thousands of designs stays within memory).

        >>> freq = np.arange(1.0, 101.0)
        >>> judge = Judge([(freq, np.exp(-((freq - 40) / 3) ** 2))])  # a peak at 40 Hz
        >>> [round(float(v), 4) for v in judge.vibration([[0.0, 0.0125], [0.0, 0.0]], [[1.0, 1.0], [1.0, 0.0]])]
        [0.1247, 1.0]
        """
        times, amplitudes = np.atleast_2d(times), np.atleast_2d(amplitudes)
        gain = float(np.max(np.abs(amplitudes).sum(-1) / np.abs(amplitudes.sum(-1))))
        worst = np.zeros(times.shape[0])
        for meter in self.meters(max_freq, max(1.0, gain)):
            rows = max(1, self.CHUNK // max(1, meter.freq.size * len(self.dampings) * times.shape[1]))
            for i in range(0, times.shape[0], rows):
                v = metrics.residual(times[i:i + rows], amplitudes[i:i + rows], meter.freq, meter.dampings)
                worst[i:i + rows] = np.maximum(worst[i:i + rows], meter.remaining(v))
        return worst

    def measures(self, times, amplitudes, max_freq: float | None = None):
        """(vibration, smoothing, max_accel, score) arrays of a batch (rows of ``times``).

        >>> freq = np.arange(1.0, 101.0)
        >>> judge = Judge([(freq, np.exp(-((freq - 40) / 3) ** 2))])  # a peak at 40 Hz
        >>> [x.shape for x in judge.measures([[0.0, 0.0125]] * 3, [[1.0, 1.0]] * 3)]
        [(3,), (3,), (3,), (3,)]
        """
        vibration = self.vibration(times, amplitudes, max_freq)
        smooth = metrics.smoothing(times, amplitudes, self.accel, self.scv)
        return vibration, smooth, metrics.max_accel(times, amplitudes, self.max_smoothing, self.scv), \
            metrics.score(smooth, vibration)

    def at_modes(self, times, amplitudes) -> np.ndarray:
        """Ours: the worst V at the identified modes, each at its damping and the test dampings.

        >>> at_40 = Judge([(np.arange(1.0, 101.0), np.ones(100))], dampings=(0.0,), modes=[(40.0, 0.0)])
        >>> float(abs(at_40.at_modes([0.0, 0.0125], [0.5, 0.5])[0])) < 1e-12  # ZV's zero: cos(pi) = -1
        True
        """
        worst = np.zeros(np.atleast_2d(times).shape[0])
        for f, zeta in self.modes:
            v = metrics.residual(np.atleast_2d(times), np.atleast_2d(amplitudes), [f], (*self.dampings, zeta))
            worst = np.maximum(worst, v.max(axis=(-1, -2)))
        return worst

    def candidate(self, kind: str, family: str, frequencies, zetas, times, amplitudes, *, ts=None, line=None,
                  fmu=None, guarded=True, max_freq: float | None = None) -> Candidate:
        """One design judged exactly. With ``ts``, ``amplitudes`` are taps at k ts (``times`` ignored).

        >>> freq = np.arange(1.0, 101.0)
        >>> judge = Judge([(freq, np.exp(-((freq - 40) / 3) ** 2))])  # a peak at 40 Hz
        >>> zv = judge.candidate("zv", "klipper", (40.0,), (0.0,), [0.0, 0.0125], [0.5, 0.5])
        >>> zv.label, round(zv.vibration, 4), zv.duration
        ('zv', 0.1247, 0.0125)
        >>> window = judge.candidate("rectangle", "window", (40.0,), (0.0,), None, [0.25] * 4, ts=0.00625)
        >>> [round(t, 6) for t in window.times]
        [0.0, 0.00625, 0.0125, 0.01875]
        """
        amplitudes = np.asarray(amplitudes, dtype=float)
        times = np.arange(amplitudes.size) * ts if ts is not None else np.asarray(times, dtype=float)
        vibration, smooth, accel, score = (float(x[0]) for x in self.measures(times[None], amplitudes[None], max_freq))
        return Candidate(kind, family, tuple(float(f) for f in frequencies), tuple(float(z) for z in zetas), vibration,
                         smooth, accel, score, float(self.at_modes(times, amplitudes)[0]), float(times[-1] - times[0]),
                         tuple(map(float, times)), tuple(map(float, amplitudes)), ts, line,
                         tuple(fmu.items()) if fmu else None, guarded)
