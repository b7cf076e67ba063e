"""The true optimum of a jerk-limited move with vibration bounds brackets the planner's move.

References: the optimum's own feasible move (a grid of jerks from a linear program) checked by the
independent matrix-exponential integration of the mode; its lower bound is a weak-duality
certificate valid for every jerk, not only grid ones; and the rigid time-optimal duration (Ruckig's)
is a second lower bound.
"""

import math

import pytest

from shapefmu.optimal import jerk_limited_optimum
from support.motion_cases import example_plan, example_ruckig, mode_amplitude


@pytest.mark.parametrize("delta", [0.0, 0.05])
def test_the_planner_is_within_5_percent_of_the_optimum_on_the_40_hz_example(delta):
    move = example_plan(delta)
    residual, = move.residuals
    bound = 0.01 * residual.rigid_amplitude
    optimum = jerk_limited_optimum([(0.0, 0.0, 0.0)], [0.01], [(0.3, 5.0, 2000.0, -0.3, -5.0)],
                                   [[(2 * math.pi * 40.0, 0.05, delta, bound)]], n_intervals=200)
    axis, = optimum.axes
    rigid = example_ruckig().duration
    assert optimum.certified
    assert optimum.lower < optimum.upper
    assert rigid <= optimum.upper
    assert max(optimum.lower, rigid) <= move.duration <= 1.05 * optimum.upper
    # The optimum's grid move itself: at rest at the target, within the bound at every frequency.
    h = optimum.upper / axis.n_intervals
    durations, jerks = [h] * axis.n_intervals, list(axis.jerk)
    frequencies = [40.0] if delta == 0 else [40.0 * (1 - delta + 2 * delta * k / 8) for k in range(9)]
    for hz in frequencies:
        assert mode_amplitude((0, 0, 0), durations, jerks, hz, 0.05, 0.0) <= bound * (1 + 1e-6)
    p = v = a = 0.0
    for j in jerks:
        p, v, a = p + v * h + a * h * h / 2 + j * h**3 / 6, v + a * h + j * h * h / 2, a + j * h
        assert abs(a) <= 5.0 * (1 + 1e-9) and abs(v) <= 0.3 + axis.velocity_slack
    # HiGHS meets equality rows to its feasibility tolerance, 1e-7 of each row's scale.
    assert (p, v, a) == pytest.approx((0.01, 0.0, 0.0), abs=1e-7)
    assert max(abs(j) for j in jerks) <= 2000.0 * (1 + 1e-9)
