"""How well ``identify`` reads raw Klipper resonance tests of machines it knows nothing about: the
second synthetic generator (``identification.synthetic_chain``: base-excited chains with
non-proportional damping, Klipper's own test pattern, an ADXL345 or LIS2DW as Klipper runs it), the
truth from each chain's eigenvalues.

Per run it prints, over the modes a person sees (a peak of the chain's exact f |H(f)|^2 above a
fifth of the highest; between a tenth and a fifth Klipper's coarse spectrum may show it or not):
the largest and 90th-percentile errors in frequency and damping, how often the damping's 90 %
interval holds the truth with its one-sided 95 % lower confidence bound (Clopper-Pearson), the
modes missed and the modes reported that the chain does not have (artefacts), and the time of
reading + spectra + modes per recording beside the time Klipper's ``calibrate_shaper.py`` takes on
the first one (with ``--klipper PATH_TO_KLIPPER``: the ratio, measured side by side).

    python benchmarks/modes_chain.py [--cases 200] [--first 1000] [--klipper /work/klipper]
"""

import argparse
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.signal import find_peaks
from scipy.stats import beta

from shapefmu.identification import identify
from shapefmu.identification import synthetic_chain as sc


def seen_modes(chain: sc.Chain, share: float = 0.2):
    """The chain's modes whose peak in f |H(f)|^2 reaches ``share`` of the highest."""
    a, b, c = chain.state_space()
    freq = np.linspace(5.0, 200.0, 8000)
    response = np.array([c @ np.linalg.solve(2j * math.pi * f * np.eye(a.shape[0]) - a, b) for f in freq])
    view = freq * np.abs(response) ** 2
    peaks, _ = find_peaks(view, height=share * view.max())
    modes = chain.modes()
    return [min(modes, key=lambda m: abs(m.frequency - freq[i])) for i in peaks]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", type=int, default=200)
    parser.add_argument("--first", type=int, default=1000, help="seed of the first chain")
    parser.add_argument("--klipper", type=Path, help="a Klipper checkout: time its calibrate_shaper.py on case 1")
    args = parser.parse_args()
    freq_errors, zeta_errors, inside, missed, artefacts, seconds, beyond = [], [], 0, 0, 0, [], []
    with tempfile.TemporaryDirectory() as folder:
        for n, seed in enumerate(range(args.first, args.first + args.cases)):
            chain = sc.Chain.random(seed)
            sensor = sc.LIS2DW if seed % 4 == 3 else sc.ADXL345
            path = Path(folder) / "raw.csv"
            sc.write_klipper_raw(path, *sc.record(chain, sensor=sensor, seed=seed))
            start = time.perf_counter()
            found = identify(path, axis="x").modes.modes
            seconds.append(time.perf_counter() - start)
            if n == 0 and args.klipper:
                start = time.perf_counter()
                subprocess.run([sys.executable, "scripts/calibrate_shaper.py", str(path)], cwd=args.klipper,
                               check=True, capture_output=True)
                klipper = time.perf_counter() - start
            truth = chain.modes()
            artefacts += sum(not any(abs(m.frequency / t.frequency - 1) < 0.05 for t in truth) for m in found)
            for true in seen_modes(chain):
                near = [m for m in found if abs(m.frequency / true.frequency - 1) < 0.05]
                if not near:
                    missed += 1
                    continue
                mode = min(near, key=lambda m: abs(m.frequency - true.frequency))
                freq_errors.append(abs(mode.frequency / true.frequency - 1))
                zeta_errors.append(abs(mode.zeta / true.zeta - 1))
                inside += mode.zeta_interval[0] <= true.zeta <= mode.zeta_interval[1]
                if freq_errors[-1] > 0.01 or zeta_errors[-1] > 0.15:
                    beyond.append(f"seed {seed}: {true.frequency:.2f} Hz / {true.zeta:.4f} read as {mode.describe().strip()}")
    count = len(zeta_errors)
    bound = beta.ppf(0.05, inside, count - inside + 1) if inside else 0.0
    print(f"{args.cases} raw recordings (seeds {args.first}-{args.first + args.cases - 1}), {count} modes seen, "
          f"{missed} missed, {artefacts} reported that the chains do not have")
    print(f"frequency error: largest {100 * max(freq_errors):.2f} %, 90th percentile "
          f"{100 * np.percentile(freq_errors, 90):.2f} % (target 1 %)")
    print(f"damping error: largest {100 * max(zeta_errors):.1f} %, 90th percentile "
          f"{100 * np.percentile(zeta_errors, 90):.1f} % (target 15 %)")
    print(f"beyond 1 % in frequency or 15 % in damping: {len(beyond)} of {count}")
    for line in beyond:
        print(f"  {line}")
    print(f"damping's 90 % interval holds the truth in {inside}/{count} = {100 * inside / count:.1f} % "
          f"(one-sided 95 % lower bound {100 * bound:.1f} %; target 85 %)")
    print(f"reading + spectra + modes: {np.median(seconds):.2f} s per recording (median)")
    if args.klipper:
        print(f"Klipper's calibrate_shaper.py on the first recording: {klipper:.2f} s "
              f"(ours / Klipper's: {seconds[0] / klipper:.2f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
