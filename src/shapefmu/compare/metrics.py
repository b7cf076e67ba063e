"""One rule for every candidate's recorded run: move time, residual vibration and peak command."""

from __future__ import annotations

import dataclasses
import math

import numpy as np


@dataclasses.dataclass(frozen=True)
class MoveMetrics:
    """``move_time``: from the move's start until the position stays within ``tolerance`` |X| of
    the target and the command within ``tolerance`` U of its final value (for an open-loop command
    that is its end, at the grid); ``residual``: the largest |y_j - y_j,final| of the position and
    the deflections over one period of the slowest mode after the move time, divided by |X| (the
    definition of ``optimal.residual_after_move``, on the recorded samples); ``peak``: max |u|."""

    move_time: float
    residual: float
    peak: float


def move_metrics(t, u, position, deflections, distance: float, u_max: float, window: float,
                 tolerance: float = 1e-3, u_final: float = 0.0) -> MoveMetrics:
    """The metrics of :class:`MoveMetrics` from samples at ``t`` (the move starts at t[0])."""
    t, u, position = (np.asarray(a, dtype=float) for a in (t, u, position))
    deflections = np.atleast_2d(np.asarray(deflections, dtype=float))
    outside = (np.abs(position - distance) > tolerance * abs(distance)) | (np.abs(u - u_final) > tolerance * u_max)
    late = np.flatnonzero(outside)
    if late.size and late[-1] + 1 >= t.size:
        return MoveMetrics(math.inf, math.nan, float(np.max(np.abs(u))))
    first = late[-1] + 1 if late.size else 0
    span = (t >= t[first] - 1e-12 * window) & (t <= t[first] + window * (1 + 1e-9))
    errors = [np.abs(position[span] - distance)] + [np.abs(row[span]) for row in deflections]
    residual = max(float(np.max(e)) for e in errors) / abs(distance)
    return MoveMetrics(float(t[first] - t[0]), residual, float(np.max(np.abs(u))))
