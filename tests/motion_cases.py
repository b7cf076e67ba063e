"""Random jerk-limited problems for the motion tests, and Ruckig (the peer) on the same problems.

A problem is per axis (state, target, Limits): limits drawn with asymmetric velocity and
acceleration ranges; the state and the target drawn inside them and safe (the acceleration can be
brought to zero without leaving the velocity range, so that neither we nor Ruckig has to brake
first); a third of the targets at rest.
"""

import random

import pytest

from shapefmu.motion.peers import ruckig_move
from shapefmu.runtime.jerk_profiles import Limits

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
