"""Every design a firmware target can run, as batches for the judge (``recommend`` picks among them).

- ``klipper``: Klipper's six shapers at any frequency (0.1 Hz steps, as its config writes them) from
  each shaper's lowest up to the top of the judged band;
- ``rrf``: RepRapFirmware's built-in shapers over the same frequencies, and its custom shaper carrying
  Klipper's pick and the train designed for the spectrum (``trains``), at most 5 impulses;
- ``marlin``: the fixed-time planner's eight shapers and the planner's own ZV (``M593``);
- ``fmu``: what the design layer builds into a Shaper or ShapeFilter FMU (the single-mode kinds on a
  log grid of 1 % steps from half the lowest mode to twice the highest, two-mode convolutions on a 5 %
  grid around the two strongest modes, the window filters of paper 000 sampled at ``ts`` on a 4 %
  grid), Klipper's pick, and the designed train. The simultaneous design (paper 002, eq. 20) is left
  out: its solver takes about a second per pair of modes, more than the rest of a recommendation.

A design layer kind that cannot take the modes' damping (the EI family takes zeta <= 0.3) is left out
and named, with the reason, in ``left_out``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
import numpy as np

from shapefmu.identification import firmware, klipper

SINGLE_KINDS = ("zv", "mzv", "zvd", "zvdd", "ei", "ei2", "ei3", "um_zv")
PAIR_KINDS = ("zv", "mzv", "zvd", "ei")
WINDOW_KINDS = ("rectangle", "hanning", "blackman", "hamming", "three-hanning")
SCAN_STEP = 0.1  # Hz, the firmware scans (one decimal, as the lines print it)
MARLIN_LOWEST = 20.0  # Hz: FTM_MIN_SHAPE_FREQ
VTOL = 0.05


@dataclass(frozen=True)
class Batch:
    """Designs of one ``kind`` of one ``family``: row i has ``frequencies[i]`` and impulses ``times[i]``,
    ``amplitudes[i]`` (a window filter's taps at k ``ts[i]``, led by zero taps); ``line(i)`` is its
    firmware line and ``build(i)`` the Shaper / ShapeFilter start values (None when no FMU kind holds it)."""

    kind: str
    family: str
    frequencies: np.ndarray
    zetas: tuple[float, ...]
    times: np.ndarray
    amplitudes: np.ndarray
    line: object = None
    build: object = None
    ts: np.ndarray | None = None


def _stack(designs):
    times, amplitudes = zip(*designs)
    return np.array(times, dtype=float), np.array(amplitudes, dtype=float)


def _grid(low, high, step=SCAN_STEP):
    """Frequencies k * step (exactly as printed) in [low, high)."""
    return np.arange(math.ceil(low / step - 1e-9), math.ceil(high / step - 1e-9)) * step


def klipper_fmu(name: str, freq: float) -> dict | None:
    """The Shaper FMU start values of Klipper's ``name`` at ``freq``: the design layer's zv, mzv and zvd
    are Klipper's (the same amplitudes and times at damping 0.1); its EI fits are not."""
    if name not in ("zv", "mzv", "zvd"):
        return None
    return {"kind": name, "f[1]": float(freq), "zeta[1]": klipper.DEFAULT_DAMPING_RATIO}


def klipper_scan(top: float, axes) -> list[Batch]:
    """Klipper's six shapers from each one's lowest frequency to ``top`` Hz."""
    batches = []
    for name, shaper in klipper.SHAPERS.items():
        freqs = _grid(shaper.min_freq, top)
        times, amplitudes = _stack([shaper.impulses(f) for f in freqs])
        batches.append(Batch(name, "klipper", freqs[:, None], (klipper.DEFAULT_DAMPING_RATIO,), times, amplitudes,
                             lambda i, f=freqs, n=name: firmware.klipper_line(n, float(f[i]), axes),
                             lambda i, f=freqs, n=name: klipper_fmu(n, f[i])))
    return batches


def rrf_scan(top: float) -> list[Batch]:
    """RepRapFirmware's built-in shapers from 10 Hz to ``top``."""
    freqs = _grid(max(10.0, firmware.RRF_FREQ[0]), min(top, firmware.RRF_FREQ[1]))
    batches = []
    for kind in firmware.RRF_TYPES:
        times, amplitudes = _stack([firmware.rrf_train(kind, f) for f in freqs])
        batches.append(Batch(kind, "rrf", freqs[:, None], (firmware.DAMPING,), times, amplitudes,
                             lambda i, k=kind: firmware.rrf_line(k, float(freqs[i]))))
    return batches


def rrf_custom(name: str, times, amplitudes, frequencies=(), zetas=()) -> Batch:
    """One train as RepRapFirmware's custom shaper: what its printed line sets."""
    line, times, amplitudes = firmware.rrf_custom(times, amplitudes)
    return Batch(name, "rrf", np.array([frequencies], dtype=float).reshape(1, -1), tuple(zetas), times[None],
                 amplitudes[None], lambda i: line)


def marlin_scan(top: float, axes) -> list[Batch]:
    """Marlin's fixed-time shapers and its planner's ZV from 20 Hz to ``top``."""
    freqs = _grid(MARLIN_LOWEST, top)
    batches = []
    for mode in firmware.MARLIN_MODES:
        times, amplitudes = _stack([firmware.marlin_train(mode, f) for f in freqs])
        batches.append(Batch(mode, "marlin", freqs[:, None], (firmware.DAMPING,), times, amplitudes,
                             lambda i, m=mode: firmware.marlin_line(m, float(freqs[i]), axes)))
    times, amplitudes = _stack([klipper.SHAPERS["zv"].impulses(f, firmware.DAMPING) for f in freqs])
    batches.append(Batch("M593 ZV", "marlin", freqs[:, None], (firmware.DAMPING,), times, amplitudes,
                         lambda i: firmware.marlin_line("M593 ZV", float(freqs[i]), axes)))
    return batches


def _log_grid(low, high, step):
    return np.exp(np.arange(math.log(low), math.log(high) + step / 2, step))


def design_layer(modes, zeta: float, ts: float, left_out: list) -> list[Batch]:
    """The Shaper and ShapeFilter FMU designs (module docstring) for ``modes`` designed at ``zeta``;
    kinds that refuse it are named in ``left_out``."""
    from shapefmu.shapers.catalog import design

    low, high = 0.5 * min(m.frequency for m in modes), 2.0 * max(m.frequency for m in modes)
    batches = []
    grid = _log_grid(low, high, 0.01)
    for kind in SINGLE_KINDS:
        try:
            unit = design(kind, [(2 * math.pi, zeta)], vtol=VTOL)  # at 1 Hz: a design at f is it with times / f
        except ValueError as error:
            left_out.append(f"{kind}: {error}")
            continue
        times = np.asarray(unit.times)[None, :] / grid[:, None]
        amplitudes = np.broadcast_to(np.asarray(unit.amplitudes), times.shape)
        batches.append(Batch(kind, "single", grid[:, None], (zeta,), times, amplitudes, None,
                             lambda i, k=kind: {"kind": k, "f[1]": float(grid[i]), "zeta[1]": zeta, "vtol": VTOL}))
    if len(modes) >= 2:  # the two strongest modes (identified modes come strongest first)
        batches += _two_modes(modes[0], modes[1], zeta, left_out)
    return batches + _windows(low, high, zeta, ts, left_out)


def _two_modes(m1, m2, zeta, left_out) -> list[Batch]:
    """Two-mode designs for ``m1`` and ``m2``: each single-mode kind at both, convolved (the impulse sets'
    product: times add, amplitudes multiply; paper 002's convolution method), on a 5 % grid of each
    frequency from 0.75 to 1.33 times its mode."""
    from shapefmu.shapers.catalog import design

    batches = []
    ratios = _log_grid(0.75, 1.34, 0.05)
    f1, f2 = (np.repeat(m1.frequency * ratios, ratios.size), np.tile(m2.frequency * ratios, ratios.size))
    for kind in PAIR_KINDS:
        try:
            unit = design(kind, [(2 * math.pi, zeta)], vtol=VTOL)
        except ValueError as error:
            left_out.append(f"{kind} x2: {error}")
            continue
        t, a = np.asarray(unit.times), np.asarray(unit.amplitudes)
        times = (t[None, :, None] / f1[:, None, None] + t[None, None, :] / f2[:, None, None]).reshape(f1.size, -1)
        amplitudes = np.broadcast_to((a[:, None] * a[None, :]).ravel(), times.shape)
        order = np.argsort(times, axis=1)
        times, amplitudes = np.take_along_axis(times, order, 1), np.take_along_axis(amplitudes, order, 1)
        frequencies = np.column_stack([f1, f2])
        batches.append(Batch(kind, "pair", frequencies, (zeta, zeta), times, amplitudes, None,
                             lambda i, k=kind, fr=frequencies: {"kind": k, "n_modes": 2, "f[1]": float(fr[i, 0]),
                                                               "f[2]": float(fr[i, 1]), "zeta[1]": zeta,
                                                               "zeta[2]": zeta, "vtol": VTOL}))
    return batches


def _windows(low, high, zeta, ts, left_out) -> list[Batch]:
    """The window filters of paper 000, a batch per filter: each row its taps as impulses at k ts (ts
    adjusted per frequency so a period holds whole samples), shorter rows led by zero taps at 0 s."""
    from shapefmu.shapers import window

    makers = {"rectangle": window.rectangle_filter, "hanning": window.hanning_filter,
              "blackman": window.blackman_filter, "hamming": window.hamming_filter,
              "three-hanning": window.three_hanning_filter}
    batches = []
    for kind in WINDOW_KINDS:
        rows = []
        for f in _log_grid(low, high, 0.04):
            try:
                shaper = makers[kind](2 * math.pi * f, zeta, ts, 1, adjust_ts=True)
            except ValueError:
                continue  # too few samples per period at this frequency for this ts
            rows.append((f, np.asarray(shaper.taps, dtype=float), shaper.ts))
        if not rows:
            left_out.append(f"{kind} (window): no frequency from {low:.1f} to {high:.1f} Hz has whole samples of "
                            f"ts = {ts:g} s in its period")
            continue
        width = max(taps.size for _, taps, _ in rows)
        times, amplitudes = np.zeros((len(rows), width)), np.zeros((len(rows), width))
        for i, (_, taps, step) in enumerate(rows):
            times[i, width - taps.size:] = np.arange(taps.size) * step
            amplitudes[i, width - taps.size:] = taps
        freqs = np.array([f for f, _, _ in rows])
        batches.append(Batch(kind, "window", freqs[:, None], (zeta,), times, amplitudes, None,
                             lambda i, k=kind, fr=freqs: {"kind": k, "f": float(fr[i]), "zeta": zeta, "Ts": ts,
                                                          "adjust_Ts": True},
                             np.array([step for _, _, step in rows])))
    return batches
