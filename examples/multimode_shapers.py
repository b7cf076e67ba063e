"""Paper 002 (La-orpacharapan & Pao): convolution and simultaneous shapers for the disk drive.

Prints the impulses of both shapers beside the paper's values and plots their sensitivity around
both modes (2.0 and 3.0 kHz, zeta = 0.01) to results/multimode_sensitivity.png.

    .venv/bin/python examples/multimode_shapers.py
"""

import math
from pathlib import Path

import numpy as np

from shapefmu.analysis import residual_vibration, sensitivity
from shapefmu.plots import plot_sensitivity
from shapefmu.shapers import convolve_modes, simultaneous

MODES = [(2 * math.pi * 2000.0, 0.01), (2 * math.pi * 3000.0, 0.01)]
PAPER = {
    "convolution": ([0, 1.6668e-4, 2.5001e-4, 4.1669e-4], [0.2579, 0.2499, 0.2499, 0.2422]),
    "simultaneous": ([0, 2.0135e-4, 4.0461e-4], [0.2848, 0.4471, 0.2681]),
}


def main():
    shapers = {"convolution": convolve_modes(MODES), "simultaneous": simultaneous(MODES)}
    for name, shaper in shapers.items():
        paper_times, paper_amplitudes = PAPER[name]
        print(f"\n{name} shaper: {'t [s]':>12} {'paper t':>12} {'amplitude':>10} {'paper':>8}")
        for t, pt, a, pa in zip(shaper.times, paper_times, shaper.amplitudes, paper_amplitudes):
            print(f"{'':20}{t:12.5e} {pt:12.5e} {a:10.4f} {pa:8.4f}")
        residuals = ", ".join(f"{100 * residual_vibration(shaper, w, z):.1e} %" for w, z in MODES)
        print(f"  duration {shaper.duration:.5e} s, residual at the two modes: {residuals}")
    saved = shapers["convolution"].duration - shapers["simultaneous"].duration
    print(f"\nsimultaneous is shorter by {saved:.4e} s ({100 * saved / shapers['convolution'].duration:.1f} %)")

    q = np.linspace(0.0, 2.0, 1601)
    curves = [
        (f"{name}, {w / (2 * math.pi * 1000):g} kHz mode", sensitivity(shaper, w, z, q))
        for name, shaper in shapers.items()
        for w, z in MODES
    ]
    path = plot_sensitivity(curves, Path("results") / "multimode_sensitivity.png")
    print(f"sensitivity plot: {path}")


if __name__ == "__main__":
    main()
