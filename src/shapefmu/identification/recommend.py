"""The shaper for a machine, from its measured spectra, judged by Klipper's own measures (``metrics``)
and expressed in what the user's firmware runs (``firmware``): Klipper's pick beside ours.

1. Klipper's pick (``klipper.pick``): what Klipper's calibrate_shaper.py recommends on these spectra,
   the baseline every design is measured against.
2. The candidates the target can run (``families``): Klipper's six at any frequency (``klipper``),
   RepRapFirmware's shapers and its custom shaper (``rrf``), Marlin's (``marlin``), or anything a
   Shaper / ShapeFilter FMU builds (``fmu``); for ``rrf`` and ``fmu`` also a train of 5 impulses designed
   for the spectrum under Klipper's pick's budget (``trains``), and Klipper's pick itself where the
   target can run it (as RRF's custom shaper, or the impulses for ``fmu``).
3. The guards, on every candidate: (a) no impulse below 2 % of the total (Klipper measures the
   vibration left after the last impulse, so a negligible late impulse fakes a win); (b) on the spectra
   with their frequency axis scaled by 0.97 and 1.03 (the machine drifts), no more vibration than
   Klipper's pick leaves there plus 0.5 percentage points.
4. The pick, by Klipper's measures: among the guarded candidates, the lowest score among those that
   dominate Klipper's pick (no more vibration, no less max_accel); else the lowest score among those
   that score no worse than it; else the lowest score (and the verdict says it is worse). Klipper's pick,
   when the target can run it, dominates itself, so the pick is never worse on Klipper's score.

The table keeps, of each kind, the design this rule prefers; ``left_out`` names the kinds that could
not be designed for these modes and why.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from shapefmu.identification import families, firmware, klipper, metrics, trains
from shapefmu.identification.judge import Candidate, Judge
from shapefmu.identification.modes import Mode

MAX_SPECTRA = 64
MAX_BINS = 200_000
DEFAULT_TS = 1e-3
TRAIN_IMPULSES = 5  # RepRapFirmware's custom shaper holds at most 5
GUARD_SHARE = trains.MIN_SHARE
GUARD_DRIFT = 0.005  # (b): 0.5 percentage points
MODE_FREQ = (1.0, 1000.0)  # Hz: modes a recommendation is made for
SMOOTHING_RANGE = (0.05, 10.0)  # mm: Klipper refuses a max_smoothing below 0.05
ACCEL_RANGE = (1.0, 1e6)  # mm/s^2: where smoothing and the score are taken
TS_RANGE = (1e-5, 1e-2)  # s: the window filters' sampling period


@dataclass(frozen=True)
class Recommendation:
    """The ranked ``candidates`` (one per kind, by the pick rule), the ``pick``, ``klipper_pick``
    (Klipper's own recommendation on the same spectra), the ``verdict`` on the pick against it
    (dominates, better score, Klipper's pick, worse), the kinds ``left_out`` and the settings."""

    firmware: str
    candidates: tuple[Candidate, ...]
    pick: Candidate
    klipper_pick: Candidate
    verdict: str
    left_out: tuple[str, ...]
    modes: tuple[Mode, ...]
    dampings: tuple[float, ...]
    accel: float
    scv: float
    max_smoothing: float
    max_freq: float
    designs_scored: int

    def to_json(self) -> dict:
        """The recommendation as ``--json`` prints it (``recommend``'s example shows its keys), but the FMU
        that runs each design, which the command adds."""
        return {"firmware": self.firmware, "pick": self.pick.row(), "klipper_pick": self.klipper_pick.row(),
                "verdict": self.verdict, "candidates": [c.row() for c in self.candidates],
                "left_out": list(self.left_out),
                "modes": [{"frequency_hz": m.frequency, "zeta": m.zeta, "frequency_sd": m.frequency_sd,
                           "zeta_sd": m.zeta_sd, "method": m.method} for m in self.modes],
                "settings": {"dampings": list(self.dampings), "accel": self.accel, "scv": self.scv,
                             "max_smoothing": self.max_smoothing, "max_freq": self.max_freq,
                             "guards": {"min_impulse_share": GUARD_SHARE, "drifts": list(trains.DRIFTS),
                                        "drift_allowance": GUARD_DRIFT}}}


def _unusable(mode: Mode) -> str | None:
    """Why no recommendation can be made for ``mode``, or None."""
    if not (math.isfinite(mode.frequency) and MODE_FREQ[0] <= mode.frequency <= MODE_FREQ[1]):
        return f"mode frequency must be in [{MODE_FREQ[0]:g}, {MODE_FREQ[1]:g}] Hz, got {float(mode.frequency):g}"
    if not (math.isfinite(mode.zeta) and 0 <= mode.zeta < 1):
        return f"mode damping ratio must be in [0, 1), got {float(mode.zeta):g}"
    return None


def check_modes(modes) -> tuple[Mode, ...]:
    """``modes`` if a recommendation can be made for every one (each in ``MODE_FREQ`` Hz with a damping
    ratio in [0, 1)), else a one-line error naming the value.

    >>> check_modes([Mode(0.5, 0.05, 0.1, 0.01, 1.0, "spectrum fit")])
    Traceback (most recent call last):
    ValueError: mode frequency must be in [1, 1000] Hz, got 0.5
    """
    modes = tuple(modes)
    if not modes:
        raise ValueError("recommend needs at least one mode")
    for m in modes:
        if _unusable(m):
            raise ValueError(_unusable(m))
    return modes


def usable_modes(modes) -> tuple[tuple[Mode, ...], tuple[str, ...]]:
    """(the identified modes a recommendation can be made for, why each other one is set aside).

    >>> kept, why = usable_modes([Mode(40.0, 0.05, 0.1, 0.01, 1.0, "fit"), Mode(40.0, 1.5, 0.1, 0.01, 1.0, "fit")])
    >>> [m.zeta for m in kept], why
    ([0.05], ('the mode at 40.00 Hz is set aside: mode damping ratio must be in [0, 1), got 1.5',))
    """
    kept = tuple(m for m in modes if not _unusable(m))
    return kept, tuple(f"the mode at {float(m.frequency):.2f} Hz is set aside: {_unusable(m)}" for m in modes
                       if _unusable(m))


def _check(spectra, modes, firmware_name, accel, scv, max_smoothing, ts):
    if firmware_name not in firmware.FIRMWARES:
        raise ValueError(f"firmware must be one of {', '.join(firmware.FIRMWARES)}, got {firmware_name!r}")
    if not spectra:
        raise ValueError("recommend needs at least one spectrum")
    if len(spectra) > MAX_SPECTRA:
        raise ValueError(f"at most {MAX_SPECTRA} spectra can be judged together, got {len(spectra)}")
    bins = sum(s.freq.size for s in spectra)
    if bins > MAX_BINS:
        raise ValueError(f"the spectra hold {bins} bins, more than the {MAX_BINS} judged at once; use a coarser resolution")
    for s in spectra:
        if not (np.all(np.isfinite(s.psd)) and np.all(np.isfinite(s.freq))):
            raise ValueError(f"{s.source}: the spectrum holds a value that is not finite (an overflow in the recording?)")
    check_modes(modes)
    for value, name, (low, high), unit in ((accel, "accel (--accel)", ACCEL_RANGE, "mm/s^2"),
                                           (ts, "the window filters' ts (--filter-ts)", TS_RANGE, "s")):
        if not (math.isfinite(value) and low <= value <= high):
            raise ValueError(f"{name} must be in [{low:g}, {high:g}] {unit}, got {value!r}")
    if not (math.isfinite(max_smoothing) and SMOOTHING_RANGE[0] <= max_smoothing <= SMOOTHING_RANGE[1]):
        raise ValueError(f"max_smoothing (--max-smoothing) must be in [{SMOOTHING_RANGE[0]:g}, {SMOOTHING_RANGE[1]:g}] "
                         f"mm (Klipper refuses less than 0.05), got {max_smoothing!r}")
    if not (math.isfinite(scv) and 0 <= scv <= 1000):
        raise ValueError(f"scv (--scv) must be in [0, 1000] mm/s, got {scv!r}")


class _Rule:
    """The guards and the pick rule (module docstring) against Klipper's pick."""

    def __init__(self, judge, reference):
        self.reference = reference
        self.drifted = [Judge([(f * s, p) for f, p in judge.spectra], dampings=judge.dampings, scv=judge.scv,
                              accel=judge.accel, max_smoothing=judge.max_smoothing, max_freq=judge.max_freq)
                        for s in trains.DRIFTS]
        self.allowed = [float(j.vibration(np.array(reference.times)[None], np.array(reference.amplitudes)[None])[0])
                        + GUARD_DRIFT for j in self.drifted]

    @staticmethod
    def shares_kept(amplitudes) -> np.ndarray:
        """Guard (a) per row of ``amplitudes``: no impulse below 2 % of the total (the zero taps that lead
        a window filter's row are no impulses)."""
        amplitudes = np.asarray(amplitudes, dtype=float)
        smallest = np.where(amplitudes != 0, amplitudes, np.inf).min(axis=-1)
        return smallest >= GUARD_SHARE * amplitudes.sum(axis=-1)

    def drift_kept(self, times, amplitudes) -> np.ndarray:
        """Guard (b) per row of a batch."""
        kept = np.ones(np.shape(times)[0], dtype=bool)
        for judge, allowed in zip(self.drifted, self.allowed):
            kept &= judge.vibration(times, amplitudes) <= allowed
        return kept

    def tiers(self, vibration, accel, score) -> np.ndarray:
        """0: dominates Klipper's pick; 1: no worse a score; 2: worse (before the guards)."""
        ref = self.reference
        return np.where((vibration <= ref.vibration) & (accel >= ref.max_accel), 0, np.where(score <= ref.score, 1, 2))

    def best(self, times, amplitudes, measures) -> tuple[int, bool]:
        """(row, guarded) the rule prefers among designs that pass guard (a): in order of (tier, score),
        the first that passes guard (b) among the first 20, else the first, unguarded."""
        vibration, _, accel, score = measures
        order = np.lexsort((score, self.tiers(vibration, accel, score)))[:20]
        kept = np.flatnonzero(self.drift_kept(times[order], amplitudes[order]))
        return (int(order[kept[0]]), True) if kept.size else (int(order[0]), False)


def recommend(spectra, modes, *, firmware_name: str = "fmu", axes=("x",),
              dampings=metrics.KLIPPER_DAMPINGS, accel: float = metrics.DEFAULT_ACCEL,
              scv: float = metrics.DEFAULT_SCV, max_smoothing: float = metrics.DEFAULT_MAX_SMOOTHING,
              max_freq: float = metrics.MAX_FREQ, ts: float = DEFAULT_TS, progress=None) -> Recommendation:
    """Klipper's pick and the pick for ``firmware_name`` on ``spectra`` (``Spectrum`` objects judged as
    Klipper judges, e.g. ``klipper.read_spectrum_file``) for the identified ``modes``; module docstring.
    ``axes`` name the axes in the firmware lines; ``max_freq`` is Klipper's (200 Hz, or its --max_freq).

    >>> from shapefmu.identification.spectra import Spectrum
    >>> freq = np.arange(1.0, 101.0)
    >>> peak = Spectrum("example", "x", freq, np.exp(-((freq - 40) / 3) ** 2), "a peak at 40 Hz")
    >>> advice = recommend([peak], [Mode(40.0, 0.05, 0.1, 0.01, 1.0, "fit")], firmware_name="klipper")
    >>> advice.pick.same(advice.klipper_pick), advice.pick.line.splitlines()[1]  # its six: Klipper's pick
    (True, 'shaper_type_x: mzv')
    >>> sorted(advice.to_json())
    ['candidates', 'firmware', 'klipper_pick', 'left_out', 'modes', 'pick', 'settings', 'verdict']
    """
    spectra = list(spectra)
    modes = tuple(modes)
    _check(spectra, modes, firmware_name, accel, scv, max_smoothing, ts)
    say = progress or (lambda text: None)
    judge = Judge(spectra, dampings=dampings, scv=scv, accel=accel, max_smoothing=max_smoothing, max_freq=max_freq,
                  modes=[(m.frequency, m.zeta) for m in modes])
    say("Klipper's pick: its five shapers over its frequency scan")
    best, _ = klipper.pick(judge)
    ref_t, ref_a = klipper.SHAPERS[best.name].impulses(best.freq)
    reference = judge.candidate(best.name, "klipper", (best.freq,), (klipper.DEFAULT_DAMPING_RATIO,), ref_t, ref_a,
                                line=firmware.klipper_line(best.name, round(best.freq, 1), axes))
    rule = _Rule(judge, reference)
    top = max(max_freq, 2.0 * max(m.frequency for m in modes))
    left_out: list[str] = []
    batches = _batches(firmware_name, judge, reference, modes, top, axes, ts, left_out, say)
    chosen, scored = [], 0
    for batch in batches:
        kept = np.flatnonzero(rule.shares_kept(batch.amplitudes))
        if not kept.size:  # guard (a) holds for none: not worth judging
            left_out.append(f"{batch.kind} ({batch.family}): every design has an impulse below 2 % of the total")
            continue
        times, amplitudes = batch.times[kept], batch.amplitudes[kept]
        measures = judge.measures(times, amplitudes)
        scored += kept.size
        row, guarded = rule.best(times, amplitudes, measures)
        row = int(kept[row])
        impulses = batch.amplitudes[row] if batch.ts is None else np.trim_zeros(batch.amplitudes[row], "f")  # or taps
        chosen.append(judge.candidate(batch.kind, batch.family, batch.frequencies[row], batch.zetas, batch.times[row],
                                      impulses, ts=None if batch.ts is None else float(batch.ts[row]),
                                      line=batch.line(row) if batch.line else None,
                                      fmu=batch.build(row) if batch.build else None, guarded=guarded))
    if not chosen:
        raise ValueError(f"no {firmware_name} design passes guard (a): each has an impulse below 2 % of the total")
    first_of_kind = {}
    for c in sorted(chosen, key=lambda c: (not c.guarded, int(rule.tiers(c.vibration, c.max_accel, c.score)), c.score)):
        first_of_kind.setdefault((c.family, c.kind), c)
    ranked = tuple(first_of_kind.values())
    return Recommendation(firmware_name, ranked, ranked[0], reference, _verdict(ranked[0], reference),
                          tuple(dict.fromkeys(left_out)),
                          modes, judge.dampings, accel, scv, max_smoothing, max_freq, scored)


def _verdict(pick, reference) -> str:
    if pick.same(reference):
        return "Klipper's pick"
    if not pick.guarded:
        return "worse: no candidate passes the guards"
    if pick.dominates(reference):
        return "dominates Klipper's pick"
    return "better score than Klipper's pick" if pick.score <= reference.score else "worse score than Klipper's pick"


def _batches(target, judge, reference, modes, top, axes, ts, left_out, say) -> list[families.Batch]:
    """The candidates' batches for ``target`` (module docstring)."""
    train = None
    own = families.Batch(reference.kind, "klipper", np.array([reference.frequencies]), reference.zetas,
                         np.array([reference.times]), np.array([reference.amplitudes]), lambda i: reference.line,
                         lambda i: families.klipper_fmu(reference.kind, reference.frequencies[0]))
    if target == "klipper":
        say("Klipper's six shapers at every 0.1 Hz")
        return [*families.klipper_scan(top, axes), own]
    if target == "marlin":
        say("Marlin's shapers at every 0.1 Hz")
        return families.marlin_scan(top, axes)
    if target in ("rrf", "fmu"):
        say(f"a train of {TRAIN_IMPULSES} impulses designed for the spectrum")
        train = trains.design(judge, (reference.times, reference.amplitudes), TRAIN_IMPULSES)
        if train is None:
            left_out.append("train: no train of 5 impulses met Klipper's pick's budget on these spectra")
    if target == "rrf":
        batches = families.rrf_scan(top)
        batches.append(families.rrf_custom(f"custom ({reference.kind})", reference.times, reference.amplitudes,
                                           reference.frequencies, reference.zetas))
        if train is not None:
            batches.append(families.rrf_custom("custom (train)", *train))
        return batches
    zeta = float(min(np.median([m.zeta for m in modes]), 0.5))
    say("the design layer's shapers and filters")
    batches = families.design_layer(modes, zeta, ts, left_out)
    batches.append(own)
    if train is not None:
        batches.append(families.Batch("train", "train", np.zeros((1, 0)), (), train[0][None], train[1][None]))
    return batches


def remaining_curve(candidate: Candidate, freq, dampings) -> np.ndarray:
    """V(f) of a candidate, worst over ``dampings``: the share of each frequency's vibration it leaves.

    >>> from shapefmu.identification.judge import Judge
    >>> zv = Judge([(np.arange(1.0, 101.0), np.ones(100))]).candidate("zv", "single", (40.0,), (0.0,), [0.0, 0.0125],
    ...                                                              [0.5, 0.5])
    >>> [round(float(v), 6) for v in remaining_curve(zv, [20.0, 40.0], (0.0,))]  # |1 + e^(i pi / 2)| / 2, 0
    [0.707107, 0.0]
    """
    return metrics.residual(np.asarray(candidate.times)[None], np.asarray(candidate.amplitudes)[None],
                            freq, dampings).max(axis=-1)[0]
