"""Sampled shapers: FIR taps at a fixed sampling period, analysed exactly like impulse shapers."""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from shapefmu.runtime.checks import check_positive


@dataclass(frozen=True, eq=False)
class SampledShaper:
    """FIR taps ``taps[k]`` applied at ``k * ts`` seconds: impulses on a uniform grid.

    Any sampled command can be wrapped the same way to analyse its residual vibration
    (``SampledShaper(u, ts)``); shapers designed by this package have taps summing to 1.

    Examples
    --------
    >>> s = SampledShaper([0.5, 0.5], 0.1)  # a ZV of a 5 Hz mode, sampled at 10 Hz
    >>> s.times.tolist(), s.gain, s.duration
    ([0.0, 0.1], 1.0, 0.1)
    >>> s.convolve(s).taps.tolist()  # its ZVD
    [0.25, 0.5, 0.25]
    """

    taps: np.ndarray
    ts: float

    def __post_init__(self):
        taps = np.array(self.taps, dtype=float).ravel()
        if taps.size == 0 or not np.all(np.isfinite(taps)):
            raise ValueError(f"taps must be a non-empty sequence of finite numbers, got {self.taps!r:.80}")
        taps.setflags(write=False)
        object.__setattr__(self, "taps", taps)
        object.__setattr__(self, "ts", check_positive(self.ts, "ts"))

    @property
    def times(self) -> np.ndarray:
        return np.arange(self.taps.size) * self.ts

    @property
    def amplitudes(self) -> np.ndarray:
        return self.taps

    @property
    def duration(self) -> float:
        return (self.taps.size - 1) * self.ts

    @property
    def gain(self) -> float:
        return float(np.sum(self.taps))

    def __len__(self) -> int:
        return int(self.taps.size)

    def __eq__(self, other) -> bool:
        return (
            isinstance(other, SampledShaper)
            and self.ts == other.ts
            and np.array_equal(self.taps, other.taps)
        )

    __hash__ = None

    def convolve(self, other: SampledShaper) -> SampledShaper:
        """Discrete convolution; both shapers must share the sampling period."""
        if not np.isclose(self.ts, other.ts, rtol=1e-12, atol=0.0):
            raise ValueError(f"sampling periods must match to convolve, got {self.ts!r} and {other.ts!r}")
        return SampledShaper(np.convolve(self.taps, other.taps), self.ts)

    def apply(self, u) -> np.ndarray:
        """Shape a command sampled at ``ts``: y[k] = sum_j taps[j] u[k - j], u resting at u[0] before."""
        u = np.asarray(u, dtype=float)
        if u.ndim != 1 or u.size == 0:
            raise ValueError(f"u must be a non-empty 1-D sequence, got shape {u.shape}")
        padded = np.concatenate([np.full(self.taps.size - 1, u[0]), u])
        return np.convolve(padded, self.taps, mode="valid")

    def to_json(self) -> str:
        return json.dumps({"kind": "sampled", "ts": self.ts, "taps": self.taps.tolist()})

    @classmethod
    def from_json(cls, text: str) -> SampledShaper:
        data = json.loads(text)
        if data.get("kind") != "sampled":
            raise ValueError(f"JSON kind must be 'sampled', got {data.get('kind')!r}")
        return cls(np.asarray(data["taps"], dtype=float), data["ts"])
