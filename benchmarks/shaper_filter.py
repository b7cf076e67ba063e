"""Streaming shaper filter: microseconds per sample, against a naive filter, in the same run.

The peer is the filter as one would first write it: keep every past sample in a Python list and
loop over the whole dense kernel (zeros included) at each step. Both produce the same output.

    .venv/bin/python benchmarks/shaper_filter.py
"""

import math
import time

from shapefmu.runtime.shaper_filter import StreamingShaper, grid_impulses
from shapefmu.shapers import convolve_modes, zv, zv_dn

H = 1e-4
STEPS = 20_000


class NaiveFilter:
    def __init__(self, delays, weights):
        self.kernel = [0.0] * (max(delays) + 1)
        for d, w in zip(delays, weights):
            self.kernel[d] = w
        self.history = []

    def step(self, u):
        self.history.append(u)
        y = 0.0
        for k, w in enumerate(self.kernel):
            if k < len(self.history):
                y += w * self.history[-1 - k]
        return y


def _microseconds_per_step(filt, inputs):
    start = time.perf_counter()
    for u in inputs:
        filt.step(u)
    return 1e6 * (time.perf_counter() - start) / len(inputs)


def main():
    omega = 2 * math.pi * 50
    cases = [
        zv(omega, 0.02),  # 2 impulses
        zv_dn(omega, 0.02, 3),  # 5 impulses
        convolve_modes([(2 * math.pi * f, 0.02) for f in (50, 80, 130, 210)]),  # 16 impulses
    ]
    inputs = [math.sin(0.01 * k) for k in range(STEPS)]
    print(f"{'impulses':>8} {'taps':>6} {'streaming us/sample':>20} {'naive us/sample':>16} {'naive/streaming':>16}")
    for shaper in cases:
        delays, weights = grid_impulses(shaper.times, shaper.amplitudes, H)
        streaming = _microseconds_per_step(StreamingShaper(delays, weights), inputs)
        naive = _microseconds_per_step(NaiveFilter(delays, weights), inputs)
        print(f"{len(shaper):>8} {len(delays):>6} {streaming:>20.3f} {naive:>16.3f} {naive / streaming:>16.1f}")


if __name__ == "__main__":
    main()
