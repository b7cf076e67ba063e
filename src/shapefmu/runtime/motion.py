"""Rest-to-rest moves with piecewise-constant acceleration, evaluated exactly at any time.

Every profile family a ProfileGenerator FMU plays has piecewise-constant acceleration: the
twin-pulse family is a sum of boxcars (paper 003), a shaped bang-bang is a bang-bang convolved with
impulses (paper 002, eq. 4 and 21), and the sampled families (time-frequency, paper 004; window
velocity profiles, paper 000) hold their acceleration between samples. So one representation serves
them all: ``levels[k]`` on ``[breaks[k], breaks[k+1])``, rest before ``breaks[0]`` and after
``breaks[-1]``. Velocity and position at every break are accumulated once; between breaks they are
the exact polynomials v_k + a_k s and p_k + v_k s + a_k s^2 / 2, so an FMU's output at a
communication point does not depend on its step size.

``sample(ts)`` gives the design layer's ``MotionProfile`` arrays (``shapefmu.shapers.profile``):
exact v, p at t = k ts and the mean acceleration over each sample period, 0 in the last entry.
"""

import bisect
import math

from .checks import check_finite, check_positive, check_size

_SNAP = 1e-12


class PiecewiseAcceleration:
    """Acceleration ``levels[k]`` on ``[breaks[k], breaks[k+1])``, 0 elsewhere, starting from rest."""

    def __init__(self, breaks, levels):
        breaks = [check_finite(b, "breaks") for b in breaks]
        levels = [check_finite(a, "levels") for a in levels]
        if len(breaks) != len(levels) + 1 or not levels:
            raise ValueError(
                f"a move needs len(breaks) == len(levels) + 1 >= 2, got {len(breaks)} and {len(levels)}"
            )
        if any(b < a for a, b in zip(breaks, breaks[1:])):
            raise ValueError(f"breaks must be non-decreasing, got {breaks}")
        self.breaks = breaks
        self.levels = levels
        velocity, position = [0.0], [0.0]
        for k, a in enumerate(levels):
            s = breaks[k + 1] - breaks[k]
            v, p = velocity[-1], position[-1]
            velocity.append(v + a * s)
            position.append(p + v * s + 0.5 * a * s * s)
        self._velocity = velocity
        self._position = position
        # Times within rounding of a break are at the break (see ``state``).
        self._tolerance = _SNAP * max(abs(breaks[0]), abs(breaks[-1]), breaks[-1] - breaks[0])

    @property
    def duration(self):
        """Time from the first break to the last, s."""
        return self.breaks[-1] - self.breaks[0]

    @property
    def distance(self):
        """Position reached at the end of the move."""
        return self._position[-1]

    @property
    def final_velocity(self):
        """Velocity after the last break: 0 for a rest-to-rest move, up to rounding."""
        return self._velocity[-1]

    def state(self, t):
        """(position, velocity, acceleration) at time ``t``; the acceleration is right-continuous."""
        breaks = self.breaks
        # A communication point meant to fall on a break (k*h accumulated as t + h) may land one
        # rounding error before it: it still gets the new level, as in runtime.reference_player.
        k = bisect.bisect_right(breaks, t + self._tolerance) - 1
        if k < 0:
            return 0.0, 0.0, 0.0
        if k >= len(self.levels):
            s = t - breaks[-1]
            return self._position[-1] + self._velocity[-1] * s, self._velocity[-1], 0.0
        s = t - breaks[k]
        a = self.levels[k]
        v = self._velocity[k]
        return self._position[k] + v * s + 0.5 * a * s * s, v + a * s, a

    def sample(self, ts, count=None):
        """Lists (t, acceleration, velocity, position) on t = k ts, k = 0..count - 1.

        ``count`` defaults to ceil(end / ts) + 2 samples (the twin-pulse grid of the design layer).
        The acceleration entry k is the mean over [t_k, t_{k+1}) and the last entry is 0.
        """
        ts = check_positive(ts, "ts")
        if count is None:
            check_size(self.breaks[-1] / ts + 2, "MAX_SAMPLED_LENGTH", f"a move of {self.breaks[-1]!r} s sampled at "
                       f"ts = {ts!r} s has", "samples", "use a longer ts")
            count = math.ceil(self.breaks[-1] / ts) + 2
        t = [k * ts for k in range(count)]
        states = [self.state(x) for x in t]
        velocity = [v for _, v, _ in states]
        position = [p for p, _, _ in states]
        acceleration = [(b - a) / ts for a, b in zip(velocity, velocity[1:])] + [0.0]
        return t, acceleration, velocity, position


def held_acceleration(acceleration, ts):
    """The move whose acceleration holds ``acceleration[k]`` on [k ts, (k + 1) ts) (zero-order hold)."""
    ts = check_positive(ts, "ts")
    levels = [check_finite(a, "acceleration") for a in acceleration]
    if not levels:
        raise ValueError("acceleration must be a non-empty sequence of finite numbers")
    return PiecewiseAcceleration([k * ts for k in range(len(levels) + 1)], levels)


def velocity_profile(taps, ts, distance):
    """A shape filter f[k] (taps summing to 1) used as the velocity v[k] = distance f[k] / ts (paper 000).

    As ``shapefmu.shapers.profile.velocity_profile``: the acceleration is the held difference
    (v[k+1] - v[k]) / ts, so v passes through the samples and the move covers distance * sum(f).
    The first and last taps must be 0, or the velocity would jump.
    """
    ts = check_positive(ts, "ts")
    distance = check_positive(distance, "distance")
    taps = [check_finite(f, "taps") for f in taps]
    scale = max((abs(f) for f in taps), default=0.0)
    if len(taps) < 3 or abs(taps[0]) > 1e-12 * scale or abs(taps[-1]) > 1e-12 * scale:
        raise ValueError(
            "a shape filter is a velocity profile only if its first and last taps are 0 "
            "(the Hanning and Blackman filters qualify, the rectangle does not)"
        )
    v = [distance * f / ts for f in taps]
    return held_acceleration([(b - a) / ts for a, b in zip(v, v[1:])], ts)
