"""What the motion tests share: random jerk-limited problems, Ruckig (the peer) on them, the exact
limit check, the mode's response integrated independently, and the 40 Hz example planned once.

A problem is per axis (state, target, Limits): limits drawn with asymmetric velocity and
acceleration ranges; the state and the target drawn inside them and safe (the acceleration can be
brought to zero without leaving the velocity range, so that neither we nor Ruckig has to brake
first); a third of the targets at rest.

The 40 Hz example of issue 36 (10 mm, v 0.3 m/s, a 5 m/s^2, j 2000 m/s^3, zeta 0.05, vtol 1 %) is
planned by the Python kernel once per band per session (``example_plan``): the vibration, optimum
and twin tests check the same move, each against its own reference.
"""

import functools
import math
import random

import numpy as np
import pytest
from scipy.linalg import expm

from shapefmu.motion import AxisLimits, plan
from shapefmu.motion.peers import ruckig_move
from shapefmu.runtime.jerk_profiles import Limits

EXAMPLE_LIMITS = Limits(0.3, 5.0, 2000.0)

pytest.importorskip("ruckig")


def _safe(rng, lim):
    while True:
        v = rng.uniform(lim.v_min, lim.v_max)
        a = rng.uniform(lim.a_min, lim.a_max)
        reach = a * abs(a) / (2.0 * lim.j_max)
        if lim.v_min <= v + reach <= lim.v_max and lim.v_min <= v - reach <= lim.v_max:
            return v, a


def random_problem(rng: random.Random, axes=None, rest_target=None):
    """([state], [target], [Limits]) of 1-3 axes (or ``axes``)."""
    count = axes or rng.randint(1, 3)
    states, targets, limits = [], [], []
    for _ in range(count):
        lim = Limits(rng.uniform(0.5, 2.0), rng.uniform(0.5, 3.0), rng.uniform(1.0, 10.0),
                     -rng.uniform(0.5, 2.0), -rng.uniform(0.5, 3.0))
        v0, a0 = _safe(rng, lim)
        vf, af = _safe(rng, lim)
        if rest_target or (rest_target is None and rng.random() < 1 / 3):
            vf = af = 0.0
        states.append((rng.uniform(-1.0, 1.0), v0, a0))
        targets.append((rng.uniform(-2.0, 2.0), vf, af))
        limits.append(lim)
    return states, targets, limits


def random_targets(rng: random.Random, limits):
    """A new target per axis for a re-plan, as an FMU's inputs give it: a position and a velocity
    (acceleration 0) that ``limits`` allow."""
    return [(rng.uniform(-2.0, 2.0), rng.uniform(lim.v_min, lim.v_max), 0.0) for lim in limits]


def ruckig_trajectory(states, targets, limits):
    """Ruckig's trajectory for the problem, or None where Ruckig reports an error."""
    return ruckig_move(states, targets, limits)[0]


@functools.cache
def example_plan(band):
    """The planner's (Python kernel's) ``Trajectory`` of the 40 Hz example with a band +- ``band``."""
    return plan([0.0], [0.01], [AxisLimits(0.3, 5.0, 2000.0)], [(40.0, 0.05)], band=band, vtol=0.01)


@functools.cache
def example_ruckig():
    """Ruckig's trajectory of the 40 Hz example (the rigid move, 91.98 ms in the issue)."""
    return ruckig_trajectory([(0.0, 0.0, 0.0)], [(0.01, 0.0, 0.0)], [EXAMPLE_LIMITS])


def assert_within(phases, lim, rel=1e-9):
    """Limits on the exact polynomials: a at the phase ends, v at the ends and at a = 0, |j|."""
    v, a = phases.v[0], phases.a[0]
    for d, j in zip(phases.durations, phases.jerks):
        assert abs(j) <= lim.j_max * (1 + rel), (j, lim)
        a1 = a + j * d
        assert lim.a_min * (1 + rel) <= a1 <= lim.a_max * (1 + rel), (a1, lim)
        if j != 0.0 and a * a1 < 0.0:
            s = -a / j
            turn = v + a * s + j * s * s / 2
            assert lim.v_min * (1 + rel) <= turn <= lim.v_max * (1 + rel), (turn, lim)
        v = v + a * d + j * d * d / 2
        a = a1
        assert lim.v_min * (1 + rel) <= v <= lim.v_max * (1 + rel), (v, lim)


def assert_ends_in(phases, target, duration, rel=1e-9):
    """The phases last ``duration`` (1e-12) and end in ``target`` (p, v, a) to ``rel`` (abs and rel)."""
    assert math.isclose(phases.duration, duration, rel_tol=1e-12), (phases.duration, duration)
    for got, want in zip(phases.end(), target):
        assert abs(got - want) <= rel * max(1.0, abs(want)), (phases.end(), target)


def mode_amplitude(start, durations, jerks, hz, zeta, a_final):
    """Amplitude of y'' + 2 zeta w y' + w^2 y = -a after the phases, by matrix exponentials: the
    five states p, v, a, y, y' and the jerk held over a phase, from the mode at its quasi-static
    deflection -a0 / w^2 (independent of the planner's jerk-step sums)."""
    w = 2 * math.pi * hz
    A = np.zeros((6, 6))  # p, v, a, y, y', jerk (held constant over a phase)
    A[0, 1] = A[1, 2] = A[3, 4] = 1.0
    A[2, 5] = 1.0
    A[4, 3], A[4, 4], A[4, 2] = -w * w, -2 * zeta * w, -1.0
    x = np.array([start[0], start[1], start[2], -start[2] / w**2, 0.0, 0.0])
    for d, j in zip(durations, jerks):
        x[5] = j
        x = expm(A * d) @ x
    e, de = x[3] + a_final / w**2, x[4]
    wd = w * math.sqrt(1 - zeta**2)
    return math.hypot(e, (de + zeta * w * e) / wd)


def ruckig_phases(trajectory, axis):
    """(durations, jerks) of one axis of Ruckig's trajectory."""
    profile = trajectory.profiles[0][axis]
    return list(profile.t), list(profile.j)


def band(hz, delta, count=41):
    """``count`` frequencies spread over hz (1 +- delta)."""
    return [hz] if delta == 0 else list(np.linspace(hz * (1 - delta), hz * (1 + delta), count))
