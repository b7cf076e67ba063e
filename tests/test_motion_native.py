"""The C twin of the planner (fmi/native/c/jerk_*.c) plans what the Python kernel plans, and
on 10,000 random starts and mid-move re-plans its moves end exactly in the target within the limits.

References: the Python kernel (runtime.jerk_planner) for the twin; Ruckig for the rigid durations;
the limits and the end state checked on the exact polynomials of every phase. The twin is reentrant
(two threads plan at once, each in its workspace) and clean under valgrind memcheck.
"""

import math
import random
import subprocess
from concurrent.futures import ThreadPoolExecutor

import pytest

from shapefmu.fmi.native import jerk_planner as native
from shapefmu.runtime import jerk_planner, jerk_vibration
from shapefmu.runtime.jerk_profiles import Limits
from support import HOSTS_C
from support.motion_cases import (EXAMPLE_LIMITS, assert_ends_in, assert_within, example_plan, random_problem,
                                  random_targets, ruckig_trajectory)
from support.valgrind import assert_clean_under_memcheck, requires_valgrind


def _same(python, c):
    """``python``: the kernel's PlannedMove or the design layer's Trajectory (phases as tuples)."""
    assert c.duration == pytest.approx(python.duration, rel=1e-12, abs=0.0)
    assert c.method == python.method
    for p, q in zip(python.phases, c.phases):
        durations, jerks = (p[1], p[2]) if isinstance(p, tuple) else (p.durations, p.jerks)
        assert len(durations) == len(q.durations)
        assert q.durations == pytest.approx(list(durations), rel=1e-12, abs=1e-12 * python.duration)
        assert q.jerks == pytest.approx(list(jerks), rel=1e-12, abs=0.0)


@pytest.mark.parametrize("delta", [0.0, 0.05])
def test_the_twin_plans_the_40_hz_example_as_python_does(delta):
    modes = [[jerk_vibration.Mode(2 * math.pi * 40.0, 0.05, delta, 0.01)]]
    _same(example_plan(delta), native.plan([(0.0, 0.0, 0.0)], [(0.01, 0.0, 0.0)], [EXAMPLE_LIMITS], modes))


def test_the_twin_plans_random_moves_with_modes_as_python_does():
    rng = random.Random(11)
    compared = 0
    while compared < 3:
        states, targets, limits = random_problem(rng, rest_target=True)
        modes = [[jerk_vibration.Mode(2 * math.pi * rng.uniform(2.0, 8.0), 0.05, 0.0, 0.01)] for _ in states]
        try:
            python = jerk_planner.plan_move(states, targets, limits, modes)
        except ValueError as error:
            with pytest.raises(ValueError) as twin:
                native.plan(states, targets, limits, modes)
            assert str(twin.value) == str(error)
            continue
        _same(python, native.plan(states, targets, limits, modes))
        compared += 1


def test_the_twin_plans_random_rigid_moves_as_python_does():
    rng = random.Random(5)
    for _ in range(200):
        states, targets, limits = random_problem(rng)
        none = [[] for _ in states]
        _same(jerk_planner.plan_move(states, targets, limits, none), native.plan(states, targets, limits, none))


def test_10000_random_starts_and_mid_move_replans_end_in_the_target_within_the_limits():
    # Random states within the limits, random targets; then a re-plan from the state at a random
    # instant of that move to a new random target. The durations are Ruckig's.
    rng = random.Random(10_000)
    for case in range(5_000):
        states, targets, limits = random_problem(rng)
        none = [[] for _ in states]
        move = native.plan(states, targets, limits, none)
        if case % 50 == 0:
            assert math.isclose(move.duration, ruckig_trajectory(states, targets, limits).duration, rel_tol=1e-9)
        _check(move, targets, limits)
        switch = rng.uniform(0.0, move.duration)
        now = [phases.state(switch)[:3] for phases in move.phases]
        new_targets = random_targets(rng, limits)
        replanned = native.plan(now, new_targets, limits, none)
        for phases, state in zip(replanned.phases, now):
            assert all(abs(x - y) <= 1e-9 for x, y in zip(phases.state(0.0), state)), (phases.state(0.0), state)
        _check(replanned, new_targets, limits)


def _check(move, targets, limits):
    for phases, target, lim in zip(move.phases, targets, limits):
        assert_ends_in(phases, target, move.duration)
        assert_within(phases, lim)


def test_random_moves_with_modes_never_break_a_limit_or_a_bound():
    # Moving starts, 1-3 axes, a mode per axis, bands 0-10 %: every move returned holds its limits
    # and every mode's bound over its band (the residual here by the jerk-step sum at 41 points of
    # the band; test_motion_vibration checks it by integrating the mode); a start from which no
    # move is found gets a one-line message naming the bound (how often: benchmarks/motion.py).
    rng = random.Random(36)
    refused = 0
    for _ in range(60):
        states, targets, limits = random_problem(rng, rest_target=True)
        delta = rng.choice([0.0, 0.05, 0.1])
        modes = [[jerk_vibration.Mode(2 * math.pi * rng.uniform(2.0, 8.0), 0.05, delta, 0.01)] for _ in states]
        try:
            move = native.plan(states, targets, limits, modes)
        except ValueError as error:
            assert "vibration bounds" in str(error) and "\n" not in str(error)
            refused += 1
            continue
        _check(move, targets, limits)
        assert move.duration <= move.ceiling_duration
        for phases, axis_modes, references in zip(move.phases, modes, move.references):
            for mode, reference in zip(axis_modes, references):
                band = [mode.omega * (1 - delta + 2 * delta * k / 40) for k in range(41)]
                worst = max(jerk_vibration.amplitude(phases.durations, phases.jerks, move.duration, w, mode.zeta)
                            for w in band)
                assert worst <= mode.vtol * reference * (1 + 1e-6)
    assert refused < 60


def test_a_start_that_must_break_a_limit_is_refused_with_its_numbers():
    lim = Limits(1.0, 2.0, 4.0)
    with pytest.raises(ValueError, match=r"axis 0: initial velocity 0\.9 with acceleration 2 reaches 1\.4"):
        native.plan([(0.0, 0.9, 2.0)], [(1.0, 0.0, 0.0)], [lim], [[]])


def test_two_threads_plan_at_once_each_in_its_own_workspace():
    # The twin keeps nothing between calls (jerk_planner.h: every buffer in the caller's workspace):
    # moves planned by two threads at the same time (ctypes releases the GIL in the call) equal the
    # same moves planned one after the other.
    rng = random.Random(21)
    problems = []
    while len(problems) < 4:
        states, targets, limits = random_problem(rng, axes=3, rest_target=True)
        modes = [[jerk_vibration.Mode(2 * math.pi * rng.uniform(2.0, 8.0), 0.05, 0.05, 0.01)] for _ in states]
        problems.append((states, targets, limits, modes, native.ceiling_shapers(states, targets, limits, modes)))

    def planned(problem):  # in the calling thread's own workspace
        try:
            move = native.plan(*problem[:4], shapers=problem[4])
        except ValueError as error:
            return str(error)
        return move.duration, [(p.durations, p.jerks) for p in move.phases]

    alone = [planned(problem) for problem in problems]
    with ThreadPoolExecutor(max_workers=2) as pool:
        together = list(pool.map(planned, problems))
    assert together == alone


@pytest.mark.foreign
@requires_valgrind
def test_the_twin_touches_no_invalid_memory_and_leaks_nothing(tmp_path):
    # tests/hosts_c/valgrind_jerk_planner.c with the twin's sources (-g) under memcheck; the moves it
    # plans against the Python kernel (the 40 Hz example, its band and its re-plan) and Ruckig.
    program = tmp_path / "valgrind_jerk_planner"
    subprocess.run(["gcc", "-g", "-O1", "-std=c99", "-Wall", "-Wextra", "-Werror", "-I", str(native.SOURCES[0].parent),
                    str(HOSTS_C / "valgrind_jerk_planner.c"), *map(str, native.SOURCES), "-o", str(program), "-lm"],
                   check=True)
    printed = assert_clean_under_memcheck([program]).stdout.split()
    assert printed[0] == "ok"
    example, band, replanned, moving, rigid = map(float, printed[1:])
    assert example == pytest.approx(example_plan(0.0).duration, rel=1e-12)
    assert band == pytest.approx(example_plan(0.05).duration, rel=1e-12)
    assert replanned == pytest.approx(example_plan(0.0).replan(0.03, [0.025]).duration, rel=1e-12)
    states, targets = [(0.1, 0.4, -0.5), (-0.2, -0.3, 0.2)], [(0.6, 0.0, 0.0), (0.3, 0.0, 0.0)]
    limits = [Limits(1.0, 2.0, 8.0, -0.8, -1.5), Limits(0.7, 1.0, 3.0, -1.2, -2.5)]
    assert rigid == pytest.approx(ruckig_trajectory(states, targets, limits).duration, rel=1e-9)
    modes = [[jerk_vibration.Mode(2 * math.pi * 5.0, 0.05, 0.0, 0.01)], []]
    assert moving == pytest.approx(native.plan(states, targets, limits, modes, shapers=[[], []]).duration, rel=1e-12)
