"""From a recording to a ranked recommendation: time of identify + recommend on a 60 s, 3.2 kHz,
three-axis Klipper recording of a two-mode machine (target: at most 4 s on the 2-core CI machine,
about what Klipper's calibrate_shaper.py takes for its six shapers), and the ratio to a
straightforward loop that scores the same candidates one design and one frequency at a time with
``shapefmu.analysis.residual_vibration`` (the same metric, no tables, no batching).

    python benchmarks/recommend.py
"""

import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from shapefmu.analysis import residual_vibration
from shapefmu.identification import identify, recommend
from shapefmu.identification import synthetic as syn
from shapefmu.identification.metrics import THRESHOLD_SHARE


def straightforward(spectrum, candidates, dampings) -> list[float]:
    """Klipper's remaining vibration of every candidate, one design, damping and bin set at a time."""
    threshold = spectrum.psd.max() * THRESHOLD_SHARE
    total = np.maximum(spectrum.psd - threshold, 0).sum()
    omega = 2 * math.pi * spectrum.freq
    scores = []
    for c in candidates:
        shaper = (np.asarray(c.times), np.asarray(c.amplitudes))
        worst = np.max([residual_vibration(shaper, omega, z) for z in dampings], axis=0)
        scores.append(float(np.maximum(spectrum.psd * worst - threshold, 0).sum() / total))
    return scores


def main() -> int:
    machine = [syn.SyntheticMode(25.0, 0.05, 0.6), syn.SyntheticMode(62.0, 0.08, 0.4)]
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "resonances_x.csv"
        t, xyz = syn.record(machine, fs=3200.0, f_min=5.0, f_max=125.0, hz_per_sec=2.0)
        syn.write_klipper_raw(path, t, xyz)
        size = path.stat().st_size
        start = time.perf_counter()
        found = identify(path, axis="xyz")
        advice = recommend([found.spectrum], found.modes.modes)
        ours = time.perf_counter() - start
    print(f"recording: {len(t)} rows x 3 axes, {t[-1] - t[0]:.1f} s at 3.2 kHz, {size / 1e6:.1f} MB")
    print(f"modes: {', '.join(f'{m.frequency:.2f} Hz / {m.zeta:.3f}' for m in found.modes.modes)}")
    print(f"pick: {advice.pick.label} {advice.pick.max_accel:.0f} mm/s^2 at {100 * advice.pick.vibration:.2f} %; "
          f"best of Klipper's six: {advice.baseline.label} {advice.baseline.max_accel:.0f} mm/s^2 at "
          f"{100 * advice.baseline.vibration:.2f} %")
    print(f"identify + recommend over every family: {ours:.2f} s (target <= 4 s)")
    # the same scores for the table's candidates, the straightforward way, timed per candidate and
    # scaled to the number of designs the recommendation scored
    sample = list(advice.candidates)
    start = time.perf_counter()
    plain = straightforward(found.spectrum, sample, advice.dampings)
    per_design = (time.perf_counter() - start) / len(sample)
    designs = advice.designs_scored
    loop = per_design * designs
    worst = max(abs(a - c.vibration) for a, c in zip(plain, sample))
    print(f"straightforward loop: {1000 * per_design:.2f} ms per design x {designs} designs = {loop:.1f} s; "
          f"ratio loop/ours {loop / ours:.1f} (largest score difference {worst:.1e})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
