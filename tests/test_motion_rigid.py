"""The rigid core of the motion planner: time-optimal, synchronised, equal to Ruckig's durations.

Reference: Ruckig (pip ``ruckig``, Berscheid & Kroeger, RSS 2021) on the same random problems.
"""

import math
import random

import pytest

from motion_cases import random_problem, ruckig_trajectory
from shapefmu.runtime.jerk_profiles import Limits, Phases, Problem, block
from shapefmu.runtime.jerk_sync import candidate_durations, rigid_blocks, straight_line, synchronise


def test_rigid_durations_equal_ruckigs_on_10000_random_problems():
    rng = random.Random(36)
    compared = 0
    for _ in range(10_000):
        states, targets, limits = random_problem(rng)
        peer = ruckig_trajectory(states, targets, limits)
        _, blocks = rigid_blocks(states, targets, limits)
        ours = candidate_durations(blocks)[0][0]
        assert peer is not None, (states, targets)
        assert ours == pytest.approx(peer.duration, rel=1e-9, abs=0.0), (states, targets)
        compared += 1
    assert compared == 10_000


def test_the_axes_end_together_in_their_targets_within_their_limits():
    # Ruckig's duration again, and every axis's profile (the second step) checked exactly: the
    # end state by integrating the phases, the limits at the phase ends and where a crosses zero.
    rng = random.Random(7)
    for _ in range(300):
        states, targets, limits = random_problem(rng)
        T, moves = synchronise(states, targets, limits)
        assert T == pytest.approx(ruckig_trajectory(states, targets, limits).duration, rel=1e-9)
        for phases, target, lim in zip(moves, targets, limits):
            assert phases.duration == pytest.approx(T, rel=1e-12)
            assert phases.end() == pytest.approx(target, rel=1e-9, abs=1e-9)
            _assert_within(phases, lim)


def _assert_within(phases, lim, rel=1e-9):
    """Limits on the exact polynomials: a at the phase ends, v at the ends and at a = 0, |j|."""
    t, p, v, a = 0.0, phases.p[0], phases.v[0], phases.a[0]
    for d, j in zip(phases.durations, phases.jerks):
        assert abs(j) <= lim.j_max * (1 + rel)
        a1 = a + j * d
        assert lim.a_min * (1 + rel) <= a1 <= lim.a_max * (1 + rel)
        if j != 0.0 and a * a1 < 0.0:
            s = -a / j
            assert lim.v_min * (1 + rel) <= v + a * s + j * s * s / 2 <= lim.v_max * (1 + rel)
        v = v + a * d + j * d * d / 2
        a = a1
        assert lim.v_min * (1 + rel) <= v <= lim.v_max * (1 + rel)


def test_a_moving_axis_that_must_turn_has_a_blocked_interval_like_ruckig():
    # An axis at 0.5 m/s that must pass 0.2 m further on at 0.5 m/s again can do it in 0.37 s,
    # but a slower arrival with that velocity needs a turn round: durations in a window are
    # impossible. A second axis whose t_min falls in that window pushes the synchronised move past
    # it, as Ruckig's does.
    lim = Limits(1.0, 1.0, 10.0)
    blocked = block(Problem(0.0, 0.5, 0.0, 0.2, 0.5, 0.0, lim))
    assert len(blocked.intervals) == 1
    left, right, _ = blocked.intervals[0]
    states = [(0.0, 0.5, 0.0), (0.0, 0.0, 0.0)]
    durations = []
    for distance in (0.05, 0.3, 0.5, 1.5):
        targets = [(0.2, 0.5, 0.0), (distance, 0.0, 0.0)]
        T, _ = synchronise(states, targets, [lim, lim])
        assert T == pytest.approx(ruckig_trajectory(states, targets, [lim, lim]).duration, rel=1e-9)
        assert not left < T < right
        durations.append(T)
    assert durations[1] == durations[2] == right  # both second axes' own t_min lie in the window


def test_a_straight_line_move_stays_on_the_line():
    lim = Limits(0.5, 2.0, 20.0)
    states = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 0.0)]
    targets = [(0.3, 0.0, 0.0), (0.4, 0.0, 0.0), (-0.15, 0.0, 0.0)]
    T, moves = straight_line(states, targets, [lim, Limits(0.3, 2.0, 20.0), lim])
    for k in range(101):
        s = [phases.state(k * T / 100)[0] for phases in moves]
        fraction = (s[0] - 0.0) / 0.3
        assert s[1] == pytest.approx(1.0 - 0.6 * fraction, abs=1e-12)
        assert s[2] == pytest.approx(-0.15 * fraction, abs=1e-12)
    # The slowest direction: y moves 0.6 at 0.3 m/s -> the path speed is limited by y alone.
    path = Problem(0.0, 0.0, 0.0, 0.6, 0.0, 0.0, Limits(0.3, 2.0, 20.0))
    assert T == pytest.approx(block(path).t_min, rel=1e-12)


def test_a_straight_line_needs_states_along_the_line():
    lim = Limits(0.5, 2.0, 20.0)
    with pytest.raises(ValueError, match="along the line"):
        straight_line([(0.0, 0.1, 0.0), (0.0, 0.0, 0.0)], [(0.3, 0.0, 0.0), (0.4, 0.0, 0.0)], [lim, lim])


def test_phases_state_is_the_exact_polynomial():
    # One phase of jerk 6 from (1, 2, 3): p = 1 + 2 t + 1.5 t^2 + t^3.
    phases = Phases(1.0, 2.0, 3.0, [2.0], [6.0])
    assert phases.state(0.5) == pytest.approx((1 + 1 + 0.375 + 0.125, 2 + 1.5 + 0.75, 6.0, 6.0))
    assert phases.state(3.0)[:3] == pytest.approx((46.5, 35.0, 15.0))  # the end state moving on
    assert math.isclose(phases.duration, 2.0)
