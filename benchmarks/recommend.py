"""From a raw recording to a recommendation: the time of identify + recommend (the default fmu target,
with its designed train) on a 130 s, 3.2 kHz, three-axis Klipper raw recording of a three-mode machine,
against the floor measured beside it in the same run: reading the same file and one Welch spectrum of
its three axes (what any recommender must at least do). Klipper's own calibrate_shaper.py on the same
file is measured by hand beside it (README, "Real recordings").

    python benchmarks/recommend.py
"""

import sys
import tempfile
import time
from pathlib import Path

from scipy.signal import welch

from shapefmu.identification import identify, klipper
from shapefmu.identification import synthetic as syn
from shapefmu.identification.recommend import recommend, usable_modes
from shapefmu.identification.recordings import read_recording

MACHINE = [syn.SyntheticMode(38.0, 0.06, 0.5), syn.SyntheticMode(61.0, 0.08, 0.3), syn.SyntheticMode(95.0, 0.05, 0.2)]


def floor(path) -> float:
    """Seconds to read the recording and take one Welch spectrum of each axis."""
    start = time.perf_counter()
    recording = read_recording(path)
    for samples in recording.channels.values():
        welch(samples, recording.fs, nperseg=2048)
    return time.perf_counter() - start


def main() -> int:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "resonances_x.csv"
        t, xyz = syn.record(MACHINE, f_min=5.0, f_max=135.0, hz_per_sec=1.0, seed=5)
        syn.write_klipper_raw(path, t, xyz)
        print(f"recording: {len(t)} rows x 3 axes, {t[-1] - t[0]:.1f} s at 3.2 kHz, {path.stat().st_size / 1e6:.1f} MB")
        least = floor(path)
        start = time.perf_counter()
        found = identify(path, axis="xyz")
        spectra = klipper.judged_spectra(found.recording, path)
        modes, _ = usable_modes(found.modes.modes)
        identified = time.perf_counter()
        advice = recommend(spectra, modes)
        ours = time.perf_counter() - start
        again = floor(path)
    print(f"modes: {', '.join(f'{m.frequency:.2f} Hz / {m.zeta:.3f}' for m in found.modes.modes)}")
    k, pick = advice.klipper_pick, advice.pick
    print(f"Klipper's pick: {k.kind} at {k.frequencies[0]:.1f} Hz, {100 * k.vibration:.2f} %, {k.max_accel:.0f} mm/s^2; "
          f"pick: {pick.label}, {100 * pick.vibration:.2f} %, {pick.max_accel:.0f} mm/s^2 ({advice.verdict})")
    print(f"identify {identified - start:.2f} s + recommend {ours - (identified - start):.2f} s = {ours:.2f} s; "
          f"floor (read + one Welch spectrum): {least:.2f} s before, {again:.2f} s after; "
          f"ratio ours / floor {ours / min(least, again):.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
