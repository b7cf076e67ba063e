"""The rigid core of the motion planner: time-optimal, synchronised, equal to Ruckig's durations.

Reference: Ruckig (pip ``ruckig``, Berscheid & Kroeger, RSS 2021) on the same random problems. The
10,000-problem sweep runs the C twin of the core (equal to the Python kernel: test_motion_native),
the Python kernel itself is compared with Ruckig on the first 1,000 of them.
"""

import math
import random

import pytest

from shapefmu.fmi.native import jerk_planner as native
from shapefmu.runtime.jerk_profiles import Limits, Phases, Problem, block
from shapefmu.runtime.jerk_sync import candidate_durations, rigid_blocks, straight_line, synchronise
from support.motion_cases import assert_ends_in, assert_within, random_problem, ruckig_trajectory


def test_rigid_durations_equal_ruckigs_on_10000_random_problems():
    rng = random.Random(36)
    compared = 0
    for case in range(10_000):
        states, targets, limits = random_problem(rng)
        peer = ruckig_trajectory(states, targets, limits)
        assert peer is not None, (states, targets)
        durations = [native.rigid_duration(states, targets, limits)]
        if case < 1_000:
            _, blocks = rigid_blocks(states, targets, limits)
            durations.append(candidate_durations(blocks)[0][0])
        for ours in durations:
            assert math.isclose(ours, peer.duration, rel_tol=1e-9), (states, targets, ours, peer.duration)
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
            assert_ends_in(phases, target, T)
            assert_within(phases, lim)


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
