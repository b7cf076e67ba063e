"""Shaped bang-bang rest-to-rest moves of a rigid body, standard library only.

The rigid-body time-optimal move over ``distance`` with |acceleration| <= ``acceleration`` is the
bang-bang of paper 002, eq. (2) (for b/s^2 with b = 1): +a on [0, T/2), -a on [T/2, T),
T = 2 sqrt(d / a). With a speed limit v below the bang-bang's peak sqrt(d a) it becomes
bang-coast-bang: +a for v/a, coast at v, -a for v/a, T = d/v + v/a. Convolving either with an
impulse shaper (times t_i, amplitudes A_i summing to 1) gives the shaped move of paper 002, eq. (4)
and (21): piecewise constant again, with breaks at every break + t_i, covering the same distance
and keeping |a| within the limit for non-negative amplitudes. This is
``shapefmu.optimal.Command.shaped`` without numpy.
"""

import math

from .checks import check_finite, check_positive
from .motion import PiecewiseAcceleration

# Breaks closer than this fraction of the move are one break: sums of delays coincide in exact
# arithmetic (t_a + t_b == t_b + t_a) but not always in floating point (as Command.shaped).
_MERGE = 1e-12


def bang_bang(distance, acceleration, speed=None):
    """(breaks, levels) of the rigid-body time-optimal move, bang-coast-bang if ``speed`` limits it."""
    distance = check_positive(distance, "distance")
    acceleration = check_positive(acceleration, "acceleration")
    if speed is not None:
        speed = check_positive(speed, "speed")
    if speed is None or speed * speed >= distance * acceleration:
        half = math.sqrt(distance / acceleration)
        return [0.0, half, 2.0 * half], [acceleration, -acceleration]
    ramp = speed / acceleration
    coast = distance / speed - ramp
    return [0.0, ramp, ramp + coast, 2.0 * ramp + coast], [acceleration, 0.0, -acceleration]


def shape(breaks, levels, times, amplitudes):
    """The piecewise-constant signal sum_i A_i u(t - t_i), exactly, as (breaks, levels)."""
    if len(times) != len(amplitudes) or not times:
        raise ValueError(
            f"times and amplitudes must be non-empty and of equal length, got {len(times)} and {len(amplitudes)}"
        )
    times = [check_finite(t, "impulse time") for t in times]
    amplitudes = [check_finite(a, "impulse amplitude") for a in amplitudes]
    if min(times) < 0.0:
        raise ValueError(f"impulse times must be >= 0, got {min(times)!r}")
    candidates = sorted({b + t for b in breaks for t in times})
    tolerance = _MERGE * max(candidates[-1] - candidates[0], 1e-300)
    merged = [candidates[0]]
    for b in candidates[1:]:
        if b - merged[-1] > tolerance:
            merged.append(b)

    def level(t):
        # u(t), 0 before the first and after the last break, right-continuous.
        if t < breaks[0] or t >= breaks[-1]:
            return 0.0
        k = max(j for j in range(len(levels)) if breaks[j] <= t)
        return levels[k]

    shaped = [
        math.fsum(a * level(0.5 * (lo + hi) - t) for t, a in zip(times, amplitudes))
        for lo, hi in zip(merged, merged[1:])
    ]
    return merged, shaped


def shaped_bang_bang(distance, acceleration, times=(0.0,), amplitudes=(1.0,), speed=None):
    """The rigid-body bang-bang (or bang-coast-bang) convolved with the impulses, as a move."""
    breaks, levels = bang_bang(distance, acceleration, speed)
    return PiecewiseAcceleration(*shape(breaks, levels, times, amplitudes))
