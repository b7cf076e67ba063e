"""What a sampled FMU must output at arbitrary communication points, computed without its clock.

The spec (runtime/sample_clock.py): samples at s_k = t0 + k Ts; sample k takes the input set at the
last communication point t_i <= s_k + delta (delta = SAMPLE_TOLERANCE Ts); at a communication
point tau the current sample is K(tau), the newest s_k <= tau + delta, and tau is on the grid when
it lies within delta of s_K. Here the grid is an array and both searches are numpy's binary search,
not the FMU's floor-and-guard arithmetic; the filtering is the design layer's.

    SampledRun(t, inputs, ts, t0=0.0): t the communication points (increasing), inputs[i] the
        input values set at t[i] (one row per point, one column per input)
    .samples        the input values of every sample 0..K(t[-1])
    .current        per communication point: the input values of its current sample as the FMU
                    sees them there (the ones just set if on the grid, else the sample's)
    .fir(taps, u0)  y at every communication point of a u -> y filter with these taps, the command
                    resting at u0 before t0 (the design layer's SampledShaper.apply)
"""

from __future__ import annotations

import numpy as np

from shapefmu.runtime.limits import SAMPLE_TOLERANCE
from shapefmu.shapers import SampledShaper


class SampledRun:
    def __init__(self, t, inputs, ts, t0=0.0):
        t = np.asarray(t, dtype=float)
        inputs = np.asarray(inputs, dtype=float).reshape(t.size, -1)
        delta = SAMPLE_TOLERANCE * ts
        grid = t0 + ts * np.arange(int((t[-1] - t0) / ts) + 3)
        self.ts = ts
        self.index = np.searchsorted(grid, t + delta, side="right") - 1  # K(t_i)
        self.on_grid = np.abs(t - grid[self.index]) <= delta
        count = self.index[-1] + 1
        last_point = np.searchsorted(t, grid[:count] + delta, side="right") - 1  # the last t_i <= s_k + delta
        self.samples = inputs[last_point]
        self.current = np.where(self.on_grid[:, None], inputs, self.samples[self.index])

    def fir(self, taps, u0=0.0):
        """y at every communication point: the taps over the samples, u0 before t0, held between."""
        taps = np.asarray(taps, dtype=float)
        u = self.samples[:, 0]
        y = SampledShaper(taps, self.ts).apply(np.concatenate([[u0], u]))[1:]
        # On the grid the current sample's input is the one just set (feed-through of taps[0]).
        return y[self.index] + taps[0] * (self.current[:, 0] - u[self.index])
