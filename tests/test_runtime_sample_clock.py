"""runtime/sample_clock.py: samples at t0 + k Ts whatever the steps, counted from them, per the spec in its docstring."""

import pytest

from shapefmu.fmi.python import state_codec
from shapefmu.runtime.limits import MAX_SAMPLES_PER_STEP, SAMPLE_TOLERANCE
from shapefmu.runtime.sample_clock import SampleClock

TS, T0 = 1e-3, 0.25
DELTA = SAMPLE_TOLERANCE * TS


def _steps(clock, steps, inputs):
    """Run the steps (t, h) with their inputs: the values committed, and the current one after each step."""
    committed, current = [], []
    for (t, h), u in zip(steps, inputs):
        current.append(clock.advance(t, h, u, committed.append))
    return committed, current


@pytest.mark.parametrize(
    ("offset", "index", "on_grid"),
    [(-1.5 * DELTA, 2, False), (-0.5 * DELTA, 3, True), (0.0, 3, True), (0.5 * DELTA, 3, True), (1.5 * DELTA, 3, False),
     (0.5 * TS, 3, False), (TS - 1.5 * DELTA, 3, False), (TS - 0.5 * DELTA, 4, True)],
)
def test_a_sample_instant_counts_as_reached_within_the_tolerance(offset, index, on_grid):
    clock = SampleClock(TS)
    clock.advance(T0, 3 * TS + offset, 0.0, lambda v: None)
    assert clock.k == index
    assert (clock.since == 0.0) is on_grid


def test_whole_sample_steps_commit_each_sample_once_with_the_input_set_before_the_step():
    clock = SampleClock(TS)
    t, steps = T0, []
    for m in (1, 3, 1, 2):
        steps.append((t, m * TS))
        t += m * TS
    committed, current = _steps(clock, steps, [10.0, 20.0, 30.0, 40.0])
    assert committed == [10.0, 20.0, 20.0, 20.0, 30.0, 40.0, 40.0]
    assert current == [10.0, 20.0, 30.0, 40.0]  # open samples: the value just used, fed through
    assert (clock.k, clock.latched) == (7, False)


def test_between_samples_the_input_is_latched_and_a_new_one_waits_for_the_next_sample():
    clock = SampleClock(TS)
    committed = []
    # 0 -> 1.5 Ts with u = 1: sample 0 committed with 1; sample 1 (at Ts) reached and latched with 1.
    assert clock.advance(0.0, 1.5 * TS, 1.0, committed.append) == 1.0
    assert (committed, clock.k, clock.latched, clock.v) == ([1.0], 1, True, 1.0)
    assert clock.current(5.0) == 1.0  # an input set between samples does not change the sample's
    # 1.5 Ts -> 1.7 Ts with u = 5: still inside sample 1, nothing committed, still latched with 1.
    assert clock.advance(1.5 * TS, 0.2 * TS, 5.0, committed.append) == 1.0
    # 1.7 Ts -> 3 Ts with u = 5: sample 1 with its latched 1, sample 2 with 5; sample 3 open.
    assert clock.advance(1.7 * TS, 1.3 * TS, 5.0, committed.append) == 5.0
    assert (committed, clock.k, clock.latched) == ([1.0, 1.0, 5.0], 3, False)


def test_a_step_of_1e_16_s_on_a_sample_instant_keeps_the_sample_open():
    clock = SampleClock(TS)
    committed = []
    assert clock.advance(2.0, 1e-16, 7.0, committed.append) == 7.0
    assert (committed, clock.k, clock.latched) == ([], 0, False)
    assert clock.current(8.0) == 8.0  # still on sample 0's instant: the input set there is its input


def test_a_host_drifting_as_t_plus_h_takes_one_sample_per_step_for_1e5_steps():
    clock = SampleClock(TS)
    t, counts = 0.0, set()
    for _ in range(100_000):
        committed = []
        clock.advance(t, TS, 0.0, committed.append)
        t += TS  # drifts from k Ts by about 1e-7 Ts after 1e5 steps
        counts.add(len(committed))
        assert not clock.latched
    assert counts == {1} and clock.k == 100_000


@pytest.mark.parametrize("h", [1e300, float("inf"), (MAX_SAMPLES_PER_STEP + 1) * TS])
def test_a_step_over_more_samples_than_the_bound_is_refused_and_changes_nothing(h):
    clock = SampleClock(TS)
    clock.advance(0.0, 0.5 * TS, 3.0, lambda v: None)
    before = dict(vars(clock))
    committed = []
    with pytest.raises(ValueError, match=f"samples of Ts = 0.001 s; at most {MAX_SAMPLES_PER_STEP} per step"):
        clock.advance(0.5 * TS, h, 4.0, committed.append)
    assert committed == [] and vars(clock) == before


def test_the_clock_state_survives_the_fmu_state_codec_exactly():
    clock = SampleClock(TS)
    clock.advance(0.1, 2.5 * TS, (1.0, -2.0, 0.1), lambda v: None)
    allowed = {"SampleClock": SampleClock}
    raw = state_codec.to_bytes(state_codec.encode(clock, allowed))
    restored = state_codec.decode(state_codec.from_bytes(raw), allowed)
    assert vars(restored) == vars(clock) and restored.v == (1.0, -2.0, 0.1)
