"""The signal-table player (runtime.reference_player) against the time-optimal solution it plays."""

import json
import math

import numpy as np
import pytest
from scipy.integrate import quad

from shapefmu.optimal import time_optimal
from shapefmu.plants import rigid_flexible
from shapefmu.runtime.reference_player import SignalTable, from_csv, from_dict, load

# Paper 002's disk drive with its 2 kHz mode: a five-level bang-bang (rigid body + one mode).
B2, U = 2.7e3, 11.0


@pytest.fixture(scope="module")
def solution():
    return time_optimal(rigid_flexible(B2, [(2 * math.pi * 2.0e3, 0.0, -B2)]), 1e-3, U)


@pytest.fixture(scope="module", params=["json", "csv"])
def table(request, solution, tmp_path_factory):
    path = tmp_path_factory.mktemp("tables") / f"solution.{request.param}"
    path.write_text(solution.to_json() if request.param == "json" else solution.to_csv())
    return load(path)


def _probe_times(solution):
    switches = np.array([0.0, *solution.switch_times, solution.T])
    inside = np.linspace(-0.1 * solution.T, 1.1 * solution.T, 301) + 1.234e-3 * solution.T
    # Just outside the rounding tolerance before each switch the old level still holds.
    return np.sort(np.concatenate([inside, switches, switches - 1e-9 * solution.T]))


def test_player_equals_the_solutions_command_at_every_instant_and_switch(solution, table):
    t = _probe_times(solution)
    np.testing.assert_array_equal([table.value(x) for x in t], solution.command(t))


def test_a_step_that_straddles_a_switch_ends_on_the_new_level(solution, table):
    switch = solution.switch_times[0]
    h = 0.37 * switch
    start = switch - 0.5 * h
    assert table.value(start + h) == solution.levels[1]
    assert table.value(start) == solution.levels[0]


def test_accumulated_communication_points_land_on_the_switch(solution, table):
    # A master that steps t += h onto a switch arrives one rounding error off it: the new level
    # still takes effect at that communication point, not one step later.
    switch = solution.switch_times[0]
    steps = 37
    h = switch / steps
    t = 0.0
    for _ in range(steps):
        t += h
    assert t != switch  # the rounding this guards against really happens here
    assert table.value(t) == solution.levels[1]
    assert table.value(np.nextafter(switch, 0.0)) == solution.levels[1]


def test_step_average_is_the_exact_mean_over_the_step(solution, table):
    command = solution.command
    points = [0.0, *solution.switch_times, solution.T]
    rng = np.random.default_rng(3)
    for start, h in zip(rng.uniform(-0.1, 1.0, 20) * solution.T, rng.uniform(0.01, 0.5, 20) * solution.T):
        exact, _ = quad(lambda x: float(command(x)), start, start + h, points=points, epsabs=1e-14, limit=200)
        assert table.average(start, start + h) == pytest.approx(exact / h, rel=1e-10, abs=1e-12 * U)


def test_zero_length_average_is_the_value(solution, table):
    switch = solution.switch_times[1]
    assert table.average(switch, switch) == solution.levels[2]


def test_next_switch_is_the_next_row_time(solution, table):
    assert table.next_switch(0.0) == solution.switch_times[0]
    assert table.next_switch(solution.switch_times[0]) == solution.switch_times[1]
    assert table.next_switch(solution.T) == math.inf


def test_linear_table_jumps_where_a_time_repeats():
    table = SignalTable([0.0, 1.0, 1.0, 3.0], [0.0, 2.0, -1.0, 1.0], "linear")
    assert table.value(0.5) == 1.0
    assert table.value(1.0 - 1e-6) == pytest.approx(2.0 - 2e-6, rel=1e-12)
    assert table.value(1.0) == -1.0
    assert table.value(2.0) == 0.0
    assert table.value(5.0) == 1.0
    exact, _ = quad(table.value, 0.5, 2.0, points=[1.0])
    assert table.average(0.5, 2.0) == pytest.approx(exact / 1.5, rel=1e-12)


def test_signal_table_json_round_trips():
    table = SignalTable([0.0, 1.0, 1.0, 3.0], [0.0, 2.0, -1.0, 1.0], "linear", before=0.5)
    again = from_dict(json.loads(json.dumps(table.to_dict())))
    t = np.linspace(-1.0, 4.0, 51)
    assert [again.value(x) for x in t] == [table.value(x) for x in t]


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: SignalTable([0.0, 1.0], [1.0]), "equal length"),
        (lambda: SignalTable([1.0, 0.0], [1.0, 2.0]), r"times must be non-decreasing, got times\[1\] = 0.0"),
        (lambda: SignalTable([0.0, float("nan")], [1.0, 2.0]), r"times\[1\] must be a finite real number"),
        (lambda: SignalTable([0.0], [1.0], "cubic"), "interpolation must be one of hold, linear"),
        (lambda: from_dict({"kind": "spline"}), "kind must be 'time_optimal' or 'signal_table'"),
        (lambda: from_dict({"kind": "time_optimal", "T": 1.0}), "needs the field 'switch_times'"),
        (lambda: from_csv("time,u\n0,1\n1\n"), "CSV line 3 must have 2 columns"),
        (lambda: from_csv("time,u\n0,x\n"), "CSV line 2 must hold two numbers"),
        (lambda: SignalTable([0.0], [1.0]).average(1.0, 0.5), "t_end must be >= t_start"),
    ],
)
def test_bad_tables_are_refused_with_the_reason(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_load_refuses_an_unknown_extension(tmp_path):
    path = tmp_path / "solution.txt"
    path.write_text("time,u\n0,1\n")
    with pytest.raises(ValueError, match="path must end in .json or .csv"):
        load(path)
