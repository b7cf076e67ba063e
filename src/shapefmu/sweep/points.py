"""Parameter points of a sweep: grids, ranges and seeded random samples."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from shapefmu.runtime.checks import check_size
from shapefmu.sweep.store import FIXED_COLUMNS


@dataclass(frozen=True, eq=False)
class Points:
    """Parameter points of a sweep: ``values[i, j]`` is parameter ``names[j]`` of run ``i``."""

    names: tuple[str, ...]
    values: np.ndarray

    def __post_init__(self):
        values = np.array(self.values, dtype=float, ndmin=2)
        names = tuple(self.names)
        if values.ndim != 2 or values.shape[1] != len(names) or not names:
            raise ValueError(f"values must have shape (n, {len(names)}) for parameters {names}, got {values.shape}")
        if len(set(names)) != len(names) or set(names) & set(FIXED_COLUMNS):
            raise ValueError(f"parameter names must be distinct and not one of {FIXED_COLUMNS}, got {names}")
        if not np.all(np.isfinite(values)):
            raise ValueError("parameter values must be finite")
        _check_distinct(names, values)
        values.setflags(write=False)
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "values", values)

    def __len__(self) -> int:
        return self.values.shape[0]

    def parameters(self, i: int) -> dict[str, float]:
        return dict(zip(self.names, map(float, self.values[i])))


def _check_distinct(names, values: np.ndarray) -> None:
    """A sweep has one row per point and resumes by the point's values: a point given twice would
    be run twice and written twice on every rerun, so it is refused."""
    if len(values) < 2:
        return
    _, first, counts = np.unique(values, axis=0, return_index=True, return_counts=True)
    if np.any(counts > 1):
        repeated = values[first[np.argmax(counts > 1)]]
        raise ValueError(f"parameter points must be distinct, but {dict(zip(names, map(float, repeated)))} appears "
                         f"{int(counts.max())} times; list each value of a grid axis once")


def _check_point_count(count, what) -> None:
    check_size(count, "MAX_SWEEP_POINTS", f"{what} has", "points", "sweep a coarser grid or fewer samples")


def parse_vary(text: str) -> tuple[str, np.ndarray]:
    """``"name=start:stop:n"`` (n points from start to stop, ends included) or ``"name=v1,v2,..."``."""
    name, sep, spec = text.partition("=")
    name = name.strip()
    if not sep or not name or not spec.strip():
        raise ValueError(f"--vary must be NAME=START:STOP:N or NAME=V1,V2,..., got {text!r}")
    if ":" in spec:
        try:
            start, stop, count = spec.split(":")
            start, stop, n = float(start), float(stop), int(count)
        except ValueError:
            raise ValueError(f"--vary must be NAME=START:STOP:N or NAME=V1,V2,..., got {text!r}") from None
        if n < 1:
            raise ValueError(f"the number of points of {name} must be >= 1, got {n} in {text!r}")
        _check_point_count(n, f"--vary {text!r}")
        values = np.linspace(start, stop, n)
    else:
        try:
            values = np.array([float(v) for v in spec.split(",")])
        except ValueError:
            raise ValueError(f"--vary must be NAME=START:STOP:N or NAME=V1,V2,..., got {text!r}") from None
    if not np.all(np.isfinite(values)):
        raise ValueError(f"values of {name} must be finite, got {text!r}")
    return name, values


def grid(*specs) -> Points:
    """The Cartesian product of the specs (the first varies slowest); a spec is a ``parse_vary``
    string or a ``(name, values)`` pair."""
    if not specs:
        raise ValueError("a grid needs at least one spec such as 'plant.wn=3.36:3.66:10'")
    axes = [parse_vary(s) if isinstance(s, str) else (str(s[0]), np.asarray(s[1], dtype=float).ravel()) for s in specs]
    names = tuple(name for name, _ in axes)
    _check_point_count(math.prod(len(values) for _, values in axes), f"the grid of {', '.join(names)}")
    mesh = np.meshgrid(*(values for _, values in axes), indexing="ij")
    return Points(names, np.stack([m.ravel() for m in mesh], axis=1))


def parse_range(text: str) -> tuple[str, float, float]:
    """``"name=low:high"`` -> (name, low, high) with low < high."""
    name, sep, spec = text.partition("=")
    try:
        low, high = (float(v) for v in spec.split(":"))
    except ValueError:
        raise ValueError(f"a sampling range must be NAME=LOW:HIGH, got {text!r}") from None
    if not sep or not name.strip() or not (math.isfinite(low) and math.isfinite(high) and low < high):
        raise ValueError(f"a sampling range must be NAME=LOW:HIGH with finite LOW < HIGH, got {text!r}")
    return name.strip(), low, high


def random_samples(n: int, ranges, seed: int = 0) -> Points:
    """``n`` points drawn uniformly from ``ranges`` ({name: (low, high)} or ``"name=low:high"``
    strings) with ``numpy.random.default_rng(seed)``: the same seed gives the same points."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n must be an integer >= 1, got {n!r}")
    _check_point_count(int(n), "the random sample")
    items = [parse_range(r) for r in ranges] if not isinstance(ranges, Mapping) else [
        (str(k), float(v[0]), float(v[1])) for k, v in ranges.items()]
    if not items:
        raise ValueError("random_samples needs at least one range")
    for name, low, high in items:
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise ValueError(f"range of {name} must be finite with low < high, got ({low}, {high})")
    rng = np.random.default_rng(seed)
    low = np.array([lo for _, lo, _ in items])
    high = np.array([hi for _, _, hi in items])
    return Points(tuple(name for name, _, _ in items), low + (high - low) * rng.random((n, len(items))))


def _points(points) -> Points:
    if isinstance(points, Points):
        return points
    if isinstance(points, str):
        return grid(points)
    if isinstance(points, Mapping):
        return grid(*points.items())
    if isinstance(points, Sequence) and points:
        return grid(*points)
    raise ValueError("points must be a Points (grid(...) or random_samples(...)), a spec string such as "
                     f"'plant.wn=3.36:3.66:10', a list of them or a {{name: values}} mapping, got {points!r}")
