"""Streaming shaper filter: microseconds per sample, against two peers, in the same run.

Peers, both producing the same output:
- naive: the filter as one would first write it: keep every past sample in a Python list and loop
  over the whole dense kernel (zeros included) at each step;
- loop: a circular buffer of the last samples and a Python loop over the non-zero taps, wrapping
  by negative indexing (StreamingShaper before it took the dense span of many-tap filters in one
  ``sum(map(mul, ...))``).

The cases run from sparse impulse shapers (a few taps spread over hundreds of samples) to the
ShapeFilter FMU's 400-tap Hanning filter; the last column is the largest relative difference of
StreamingShaper's output from the loop's (0: the same floats).

    .venv/bin/python benchmarks/shaper_filter.py
"""

import math
import time

from shapefmu.runtime.shaper_filter import StreamingShaper, grid_impulses
from shapefmu.runtime.window_filters import hanning_filter
from shapefmu.shapers import convolve_modes, zv, zv_dn

H = 1e-4
STEPS = 20_000
REPEATS = 3  # best of, so that a burst of load from other processes does not decide a ratio


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


class LoopFilter:
    def __init__(self, delays, weights):
        self.pairs = tuple(zip(delays, weights))
        self.length = max(delays) + 1
        self.buffer = [0.0] * self.length
        self.pos = 0

    def step(self, u):
        buffer, pos = self.buffer, self.pos
        buffer[pos] = u
        y = 0.0
        for d, w in self.pairs:
            y += w * buffer[pos - d]
        pos += 1
        self.pos = 0 if pos == self.length else pos
        return y


def _microseconds_per_step(make_filter, inputs):
    best = math.inf
    for _ in range(REPEATS):
        filt = make_filter()
        start = time.perf_counter()
        for u in inputs:
            filt.step(u)
        best = min(best, time.perf_counter() - start)
    return 1e6 * best / len(inputs)


def _largest_relative_difference(a, b, inputs):
    return max(abs(x - y) / abs(y) if y else abs(x) for x, y in zip(map(a.step, inputs), map(b.step, inputs)))


def main():
    omega = 2 * math.pi * 50
    hanning_taps, _ = hanning_filter(2 * math.pi * 100.0, 0.0, H, 2)
    cases = [
        ("ZV", zv(omega, 0.02)),  # 2 impulses
        ("ZVDDD", zv_dn(omega, 0.02, 3)),  # 5 impulses
        ("ZV x 4 modes", convolve_modes([(2 * math.pi * f, 0.02) for f in (50, 80, 130, 210)])),  # 16 impulses
    ]
    designs = [(name, *grid_impulses(shaper.times, shaper.amplitudes, H)) for name, shaper in cases]
    nonzero = [k for k, w in enumerate(hanning_taps) if w != 0.0]
    designs.append(("Hanning n=2, 100 Hz", nonzero, [hanning_taps[k] for k in nonzero]))
    # Input: a slow sine plus steps, so that no output is zero.
    inputs = [math.sin(0.01 * k) + (1.0 if (k // 700) % 2 else 0.0) for k in range(STEPS)]
    print(f"{'filter':<20} {'taps':>5} {'span':>5} {'streaming us':>13} {'loop us':>8} {'naive us':>9} "
          f"{'loop/streaming':>15} {'naive/streaming':>16} {'max rel diff':>13}")
    for name, delays, weights in designs:
        streaming = _microseconds_per_step(lambda: StreamingShaper(delays, weights), inputs)
        loop = _microseconds_per_step(lambda: LoopFilter(delays, weights), inputs)
        naive = _microseconds_per_step(lambda: NaiveFilter(delays, weights), inputs)
        difference = _largest_relative_difference(StreamingShaper(delays, weights), LoopFilter(delays, weights), inputs)
        print(f"{name:<20} {len(delays):>5} {max(delays) + 1:>5} {streaming:>13.3f} {loop:>8.3f} {naive:>9.3f} "
              f"{loop / streaming:>15.2f} {naive / streaming:>16.1f} {difference:>13.1e}")


if __name__ == "__main__":
    main()
