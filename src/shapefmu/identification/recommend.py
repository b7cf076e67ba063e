"""The shaper for a machine, from its measured spectra: every family the design layer has, each at
its best frequencies for the data, ranked on Klipper's own metrics (``metrics``).

Candidates:

- single-frequency impulse shapers (zv, mzv, zvd, zvdd, ei, ei2, ei3, zv_dn with n = 1, um_zv),
  designed once at 1 Hz and scaled (an impulse shaper designed for (f, zeta) is the 1 Hz design with
  its times divided by f), scanned over a log grid of 0.5 % steps from 0.5 times the lowest mode to
  2 times the highest;
- window shape filters of paper 000 (rectangle, hanning, blackman, hamming, three-hanning) sampled
  at ``ts``, designed at each frequency of a 1 % grid;
- multi-mode shapers for every pair of identified modes: the same single-mode kind at both modes,
  convolved (paper 002), each frequency on a 3 % grid from 0.5 to 2.5 times its mode and then in
  0.5 % steps around the best pair (the convolution's residual is the product of the two, at every
  frequency and damping), and the simultaneous design (paper 002, eq. 20) at the pair, scaled
  together in 0.5 % steps.

A design is judged, worst case over every given spectrum (probe points, loads, axes), by its
remaining vibration R, its smoothing at ``accel``, its largest acceleration for ``max_smoothing``,
its duration and its residual at the identified modes (the worst V over the damping range at each
mode: what a move of the machine keeps, the number a co-simulation checks).

The pick. Klipper's six (zv, mzv, zvd, ei, ei2, ei3) at single frequencies are the baseline: among
their best frequencies, the largest acceleration whose vibration is at most ``max_vibration`` (or the
least vibration if none reaches it). The pick is then the candidate of any family with the largest
acceleration among those with no more vibration than that baseline, so it never loses to it on
either count; the table shows both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from itertools import combinations

import numpy as np

from shapefmu.identification import metrics
from shapefmu.identification.modes import Mode
from shapefmu.identification.spectra import Spectrum

KLIPPER_SIX = ("zv", "mzv", "zvd", "ei", "ei2", "ei3")
SINGLE_KINDS = (*KLIPPER_SIX, "zvdd", "zv_dn", "um_zv")
WINDOW_KINDS = ("rectangle", "hanning", "blackman", "hamming", "three-hanning")
PAIR_KINDS = ("zv", "mzv", "zvd", "ei", "ei2", "ei3")
MAX_SPECTRA = 64
MAX_BINS = 200_000
DEFAULT_MAX_VIBRATION = 0.05
DEFAULT_TS = 1e-3
VTOL = 0.05


@dataclass(frozen=True)
class Candidate:
    """One design and its scores. ``kind`` names a Shaper FMU kind (impulse shapers; ``simultaneous``)
    or a ShapeFilter kind (``family == "window"``); ``frequencies`` (Hz) and ``zetas`` are the modes it
    is designed for; ``ts`` the sampling period of a window filter."""

    kind: str
    family: str
    frequencies: tuple[float, ...]
    zetas: tuple[float, ...]
    vibration: float
    at_modes: float
    smoothing: float
    max_accel: float
    duration: float
    times: tuple[float, ...] = field(repr=False)
    amplitudes: tuple[float, ...] = field(repr=False)
    ts: float | None = None

    @property
    def label(self) -> str:
        if self.family == "pair":
            return f"{self.kind} x2"
        return self.kind

    def row(self) -> dict:
        return {"shaper": self.label, "family": self.family, "frequencies_hz": list(self.frequencies),
                "zetas": list(self.zetas), "vibration": self.vibration, "residual_at_modes": self.at_modes,
                "smoothing_mm": self.smoothing, "max_accel": self.max_accel, "duration_s": self.duration,
                **({"ts": self.ts} if self.ts is not None else {})}


@dataclass(frozen=True)
class Recommendation:
    """The ranked ``candidates`` (the best frequency of every family, largest acceleration first
    among those within the vibration bound), the ``pick`` and the Klipper-six ``baseline``, and the
    settings they were judged with."""

    candidates: tuple[Candidate, ...]
    pick: Candidate
    baseline: Candidate
    modes: tuple[Mode, ...]
    dampings: tuple[float, ...]
    accel: float
    scv: float
    max_smoothing: float
    max_vibration: float
    bound: float
    designs_scored: int

    def to_json(self) -> dict:
        return {"pick": self.pick.row(), "baseline_klipper_six": self.baseline.row(),
                "candidates": [c.row() for c in self.candidates],
                "modes": [{"frequency_hz": m.frequency, "zeta": m.zeta, "frequency_sd": m.frequency_sd,
                           "zeta_sd": m.zeta_sd, "method": m.method} for m in self.modes],
                "settings": {"dampings": list(self.dampings), "accel": self.accel, "scv": self.scv,
                             "max_smoothing": self.max_smoothing, "max_vibration": self.max_vibration,
                             "vibration_bound": self.bound}}


def _unit_design(kind: str, zeta: float):
    """(times, amplitudes) of ``kind`` designed for 1 Hz."""
    from shapefmu.shapers.catalog import design

    shaper = design(kind, [(2 * math.pi, zeta)], vtol=VTOL, n=1)
    return np.asarray(shaper.times), np.asarray(shaper.amplitudes)


class _RatioTable:
    """V(r, zeta) of a design at frequency ratios r = f / f_design: an impulse shaper designed for f_d
    is its 1 Hz design with times / f_d, so its residual at f depends on f / f_d alone. Tabulated on a
    log grid of 0.075 % steps and interpolated: a scan over thousands of designs costs one table."""

    GRID = np.linspace(math.log(1 / 20), math.log(20), 8_001)

    def __init__(self, times, amplitudes, dampings):
        self.values = metrics.residual(times, amplitudes, np.exp(self.GRID), dampings)  # (grid, zeta)

    def __call__(self, ratio) -> np.ndarray:
        """V at ``ratio`` (any shape) -> (..., zeta)."""
        x = np.log(np.asarray(ratio, dtype=float))
        return np.stack([np.interp(x, self.GRID, self.values[:, k]) for k in range(self.values.shape[1])], axis=-1)


class _SampledCurve:
    """V of one sampled filter on a log grid of 1 % steps over 1..2000 Hz, interpolated: a window
    filter of tens of taps varies over tens of hertz, and the spectra hold about a thousand bins."""

    GRID = np.linspace(0.0, math.log(2000.0), int(math.log(2000.0) / 0.01) + 1)

    def __init__(self, taps, ts, dampings):
        self.values = metrics.residual_sampled(taps, ts, np.exp(self.GRID), dampings)  # (grid, zeta)

    def __call__(self, freq) -> np.ndarray:
        x = np.log(np.maximum(np.asarray(freq, dtype=float), 1.0))
        columns = [np.interp(x, self.GRID, self.values[:, k]) for k in range(self.values.shape[1])]
        return np.stack(columns, axis=-1)[None]


class _Judge:
    """The metrics of designs against every spectrum (worst case) and at the identified modes."""

    def __init__(self, spectra, dampings, modes, accel, scv, max_smoothing):
        self.meters = [metrics.VibrationMeter(s.freq, s.psd, dampings, max_gain=3.0) for s in spectra]
        self.dampings = dampings
        self.mode_freqs = np.array([m.frequency for m in modes]) if modes else np.zeros(0)
        self.accel, self.scv, self.max_smoothing = accel, scv, max_smoothing

    def remaining(self, v_of) -> np.ndarray:
        """Worst R over the spectra; ``v_of(freq)`` gives V (..., len(freq), zeta) of the batch."""
        worst = None
        for meter in self.meters:
            r = meter.remaining(v_of(meter.freq))
            worst = r if worst is None else np.maximum(worst, r)
        return worst

    def judge(self, kind, family, frequencies, zetas, times, amplitudes, v_of):
        """Candidates for a batch (rows of ``times``), ``frequencies`` a list of tuples; ``v_of(freq)``
        gives the batch's V (a ratio table or a sampled curve)."""
        ts = float(times[0][1] - times[0][0]) if family == "window" else None
        vib = self.remaining(v_of)
        at = (v_of(self.mode_freqs).max(axis=(-1, -2)) if self.mode_freqs.size
              else np.zeros(len(frequencies)))
        smooth = metrics.smoothing(times, amplitudes, self.accel, self.scv)
        accel = metrics.max_accel(times, amplitudes, self.max_smoothing, self.scv)
        return [Candidate(kind, family, tuple(float(f) for f in frequencies[i]), tuple(zetas), float(vib[i]),
                          float(at[i]), float(smooth[i]), float(accel[i]), float(times[i][-1]),
                          tuple(map(float, times[i])), tuple(map(float, amplitudes[i])),
                          ts if family == "window" else None)
                for i in range(len(frequencies))]


def _grid(low, high, step):
    return np.exp(np.arange(math.log(low), math.log(high) + step / 2, step))


def _best(points, bound):
    """The largest acceleration with vibration <= bound (1e-12 slack), else the least vibration."""
    within = [p for p in points if p.vibration <= bound + 1e-12]
    if within:
        return max(within, key=lambda p: (p.max_accel, -p.vibration))
    return min(points, key=lambda p: (p.vibration, -p.max_accel))


def _pair_scan(judge, kind, m1, m2, r1, r2, dampings) -> list[Candidate]:
    """The convolution of ``kind`` at m1.frequency * r1 and m2.frequency * r2 (every pair)."""
    g1, g2 = m1.frequency * np.asarray(r1), m2.frequency * np.asarray(r2)
    ta, aa = _unit_design(kind, min(m1.zeta, 0.5))
    tb, ab = _unit_design(kind, min(m2.zeta, 0.5))
    table_a, table_b = _RatioTable(ta, aa, dampings), _RatioTable(tb, ab, dampings)

    def v_of(freq):
        # a convolution's residual is the product of its factors' at every frequency and damping
        va = table_a(freq[None, :] / g1[:, None])  # (g1, freq, zeta)
        vb = table_b(freq[None, :] / g2[:, None])
        return (va[:, None] * vb[None, :]).reshape(g1.size * g2.size, freq.size, len(dampings))

    times = ta[None, None, :, None] / g1[:, None, None, None] + tb[None, None, None, :] / g2[None, :, None, None]
    amps = np.broadcast_to(aa[:, None] * ab[None, :], times.shape)
    times, amps = times.reshape(g1.size * g2.size, -1), amps.reshape(g1.size * g2.size, -1)
    order = np.argsort(times, axis=1)
    times, amps = np.take_along_axis(times, order, 1), np.take_along_axis(amps, order, 1)
    pairs = [(a, b) for a in g1 for b in g2]
    return judge.judge(kind, "pair", pairs, (m1.zeta, m2.zeta), times, amps, v_of)


def recommend(spectra, modes, *, dampings=None, accel: float = metrics.DEFAULT_ACCEL,
              scv: float = metrics.DEFAULT_SCV, max_smoothing: float = metrics.DEFAULT_MAX_SMOOTHING,
              max_vibration: float = DEFAULT_MAX_VIBRATION, ts: float = DEFAULT_TS, windows: bool = True,
              f_range: tuple[float, float] | None = None, progress=None) -> Recommendation:
    """Rank every family on ``spectra`` (one or more ``Spectrum``) for the identified ``modes`` (see the
    module docstring). ``dampings`` default to Klipper's (0.075, 0.1, 0.15) widened to hold every
    identified damping; designs use the median identified damping (0.1 without modes)."""
    spectra = [spectra] if isinstance(spectra, Spectrum) else list(spectra)
    if not spectra:
        raise ValueError("recommend needs at least one spectrum")
    if len(spectra) > MAX_SPECTRA:
        raise ValueError(f"at most {MAX_SPECTRA} spectra can be judged together, got {len(spectra)}")
    bins = sum(s.freq.size for s in spectra)
    if bins > MAX_BINS:
        raise ValueError(f"the spectra hold {bins} bins, more than the {MAX_BINS} judged at once; use a coarser resolution")
    modes = tuple(modes)
    for value, name in ((accel, "accel"), (max_smoothing, "max_smoothing"), (ts, "ts")):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a positive number, got {value!r}")
    if not (math.isfinite(scv) and scv >= 0):
        raise ValueError(f"scv must be a number >= 0 (mm/s), got {scv!r}")
    if not (math.isfinite(max_vibration) and 0 < max_vibration <= 1):
        raise ValueError(f"max_vibration must be a fraction in (0, 1], got {max_vibration!r}")
    zetas = [m.zeta for m in modes]
    if dampings is None:
        dampings = tuple(sorted({*metrics.KLIPPER_DAMPINGS, *(round(min(z, 0.5), 4) for z in zetas)}))
    dampings = tuple(float(z) for z in dampings)
    if not dampings or any(not (0 <= z < 1) for z in dampings):
        raise ValueError(f"dampings must be damping ratios in [0, 1), got {dampings!r}")
    design_zeta = float(min(np.median(zetas), 0.5)) if zetas else 0.1
    if f_range is None:
        if modes:
            f_range = (0.5 * min(m.frequency for m in modes), 2.0 * max(m.frequency for m in modes))
        else:
            f_range = (max(spectra[0].freq[0], 1.0), spectra[0].freq[-1])
    judge = _Judge(spectra, dampings, modes, accel, scv, max_smoothing)
    say = progress or (lambda text: None)
    scans: dict[tuple[str, str], list[Candidate]] = {}

    grid = _grid(*f_range, 0.005)
    for kind in SINGLE_KINDS:
        say(f"single-frequency {kind}: {grid.size} frequencies")
        t1, a1 = _unit_design(kind, design_zeta)
        table = _RatioTable(t1, a1, dampings)
        times = t1[None, :] / grid[:, None]
        amps = np.broadcast_to(a1, times.shape)
        scans[(kind, "single")] = judge.judge(kind, "single", [(f,) for f in grid], (design_zeta,), times, amps,
                                              lambda freq, table=table: table(freq[None, :] / grid[:, None]))

    six = [_best(scans[(k, "single")], max_vibration) for k in KLIPPER_SIX]
    baseline = _best(six, max_vibration)
    bound = baseline.vibration if baseline.vibration <= max_vibration else max_vibration

    if windows:
        from shapefmu.shapers import window

        coarse = _grid(*f_range, 0.02)
        for kind in WINDOW_KINDS:
            say(f"window filter {kind} at Ts = {ts:g} s: {coarse.size} frequencies")
            design = {"rectangle": window.rectangle_filter, "hanning": window.hanning_filter,
                      "blackman": window.blackman_filter, "hamming": window.hamming_filter,
                      "three-hanning": window.three_hanning_filter}[kind]
            points = []
            for f in coarse:
                try:
                    shaper = design(2 * math.pi * f, design_zeta, ts, 1, adjust_ts=True)
                except ValueError:
                    continue  # too few samples per period at this frequency for this Ts
                taps = np.asarray(shaper.taps)
                times = (np.arange(taps.size) * shaper.ts)[None, :]
                points += judge.judge(kind, "window", [(f,)], (design_zeta,), times, taps[None, :],
                                      _SampledCurve(taps, shaper.ts, dampings))
            if points:
                scans[(kind, "window")] = points

    for i, j in combinations(range(len(modes)), 2):
        m1, m2 = modes[i], modes[j]
        for kind in PAIR_KINDS:
            say(f"two-mode {kind} x2 at {m1.frequency:.1f} and {m2.frequency:.1f} Hz")
            # a 3 % grid over 0.5..2.5 of each mode, then 0.5 % steps around the best of it
            coarse = _pair_scan(judge, kind, m1, m2, _grid(0.5, 2.5, 0.03), _grid(0.5, 2.5, 0.03), dampings)
            near = _best(coarse, bound)
            fine = _grid(0.97, 1.03, 0.005)
            refined = _pair_scan(judge, kind, m1, m2, near.frequencies[0] / m1.frequency * fine,
                                 near.frequencies[1] / m2.frequency * fine, dampings)
            scans.setdefault((kind, "pair"), []).extend(coarse + refined)
        say(f"two-mode simultaneous at {m1.frequency:.1f} and {m2.frequency:.1f} Hz")
        from shapefmu.shapers.catalog import design as design_kind

        try:
            shaper = design_kind("simultaneous", [(m1.omega, min(m1.zeta, 0.5)), (m2.omega, min(m2.zeta, 0.5))])
        except ValueError:
            continue
        scale = _grid(0.6, 1.6, 0.005)
        # in units of mode 1: the design's times times f1 are those of a design with mode 1 at 1 Hz
        table = _RatioTable(np.asarray(shaper.times) * m1.frequency, np.asarray(shaper.amplitudes), dampings)
        times = np.asarray(shaper.times)[None, :] / scale[:, None]
        amps = np.broadcast_to(np.asarray(shaper.amplitudes), times.shape)
        scans.setdefault(("simultaneous", "multi"), []).extend(judge.judge(
            "simultaneous", "multi", [(m1.frequency * s, m2.frequency * s) for s in scale], (m1.zeta, m2.zeta),
            times, amps, lambda freq, table=table, f1=m1.frequency: table(freq[None, :] / (f1 * scale[:, None]))))

    best = [_best(points, bound) for points in scans.values()]
    within = sorted((c for c in best if c.vibration <= bound + 1e-12), key=lambda c: -c.max_accel)
    rest = sorted((c for c in best if c.vibration > bound + 1e-12), key=lambda c: c.vibration)
    ranked = tuple(within + rest)
    pick = ranked[0] if within else baseline
    scored = sum(len(points) for points in scans.values())
    return Recommendation(ranked, pick, baseline, modes, dampings, accel, scv, max_smoothing, max_vibration, bound,
                          scored)


def remaining_curve(candidate: Candidate, freq, dampings) -> np.ndarray:
    """V_max(f) of a candidate: the share of each frequency's vibration that it leaves (for plots)."""
    return metrics.residual(np.asarray(candidate.times)[None], np.asarray(candidate.amplitudes)[None],
                            freq, dampings).max(axis=-1)[0]
