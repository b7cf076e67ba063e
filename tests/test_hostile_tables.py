"""ReferencePlayer tables from users: numbers only, every derived number finite, bounded work (issue 34,
items 6, 8's table, 9's reference, 12).

``"time": "012", "value": "345"`` built rows 0, 1, 2 -> 3, 4, 5 (a string is a list of characters),
boolean times and ``"u_final": "0"`` were accepted; ``"time": 5`` / ``null`` / ``"switch_times": 5``
were TypeError tracebacks; times of +-1e308 made the running integral inf, which the native
FMU's C cannot hold (gcc: "'inf' undeclared"); a 15 MB table (under the 16 MB limit) kept gcc busy
for more than ten minutes. Now: every number a JSON number, refused with the key named; every derived
number a finite double with room for differences, refused with the bound named; the native twin's
table bounded in distinct times by what gcc compiles in seconds, its text written as string literals.
Each refusal is one line of ``shapefmu build reference`` (exit 2, no traceback).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hostile_support import guarded


# (table, words of the one-line refusal)
MIS_TYPED = {
    "strings as lists": ({"kind": "signal_table", "time": "012", "value": "345"},
                         'time must be a list of numbers, got "012" (a string)'),
    "a boolean time": ({"kind": "signal_table", "time": [True, 2.0], "value": [1.0, 2.0]},
                       "time[0] must be a number, got true (a boolean)"),
    "a string u_final": ({"kind": "time_optimal", "switch_times": [0.5], "levels": [1.0, -1.0], "T": 1.0, "u_final": "0"},
                         'u_final must be a number, got "0" (a string)'),
    "a null value": ({"kind": "signal_table", "time": [0.0, 1.0], "value": [1.0, None]},
                     "value[1] must be a number, got null (a null)"),
    "a string before": ({"kind": "signal_table", "time": [0.0], "value": [1.0], "before": "1"},
                        'before must be a number, got "1" (a string)'),
    '"time": 5': ({"kind": "signal_table", "time": 5, "value": [1.0]}, "time must be a list of numbers, got 5"),
    '"time": null': ({"kind": "signal_table", "time": None, "value": [1.0]}, "time must be a list of numbers, got null"),
    '"switch_times": 5': ({"kind": "time_optimal", "switch_times": 5, "levels": [1.0], "T": 1.0, "u_final": 0.0},
                          "switch_times must be a list of numbers, got 5"),
}
OVERFLOWING = {
    "times of +-1e308": ({"kind": "signal_table", "time": [-1e308, 1e308], "value": [1.0, 2.0]},
                         "its span must stay below 8.99e+307 s"),
    "an integral of 1e310": ({"kind": "signal_table", "time": [0.0, 1e300], "value": [1e10, 2.0]},
                             "running integral reaches inf between times 0.0 and 1e+300"),
    "an integral past half the largest double": ({"kind": "signal_table", "time": [0.0, 1e154, 2e154],
                                                  "value": [1e154, -1e154, 0.0]},
                                                 "running integral reaches 1e+308 between times 0.0 and 1e+154"),
}


def _build(tmp_path, table, *native):
    path = tmp_path / "t.json"
    path.write_text(json.dumps(table))
    return guarded(["build", "reference", path, "-o", tmp_path / "t.fmu", *native], seconds=600)


@pytest.mark.parametrize("native", [[], ["--native"]], ids=["pythonfmu", "native"])
@pytest.mark.parametrize("case", [*MIS_TYPED, *OVERFLOWING])
def test_a_table_of_other_than_numbers_or_overflowing_is_one_line_naming_the_key(tmp_path, case, native):
    table, words = {**MIS_TYPED, **OVERFLOWING}[case]
    code, out, err = _build(tmp_path, table, *native)
    assert code == 2 and len(err.strip().splitlines()) == 1 and words in err and "t.json" in err, err
    assert not (tmp_path / "t.fmu").exists()


def _played(path, steps):
    """(y, y_mean) after each step (t, h) of ``steps``, fmpy driving the FMU."""
    from support.fmpy_slaves import instantiated, variable_references

    vr = variable_references(path)
    slave = instantiated(path)
    slave.setupExperiment(startTime=steps[0][0])
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    rows = []
    for t, h in steps:
        slave.doStep(t, h)
        rows.append(slave.getReal([vr["y"], vr["y_mean"]]))
    slave.terminate()
    slave.freeInstance()
    return np.array(rows)


EDGE = {"kind": "signal_table", "interpolation": "linear", "time": [-1e153, 0.0, 1e153], "value": [4e154, -4e154, 4e154]}


@pytest.mark.parametrize("native", [[], ["--native"]], ids=["pythonfmu", "native"])
def test_a_table_near_the_bound_is_played_finite_even_by_steps_far_past_it(tmp_path, native):
    """The integral of EDGE reaches 4e307 (under half the largest double); a host stepping to 1e300 and
    back from -1e300 gets its means, weighted by the parts of the step inside and outside the table."""
    code, out, err = _build(tmp_path, EDGE, *native)
    assert code == 0, err
    steps = [(-1e300, 1e300), (0.0, 1e152), (1e152, 1e300 - 1e152), (1e300, 1e299)]
    rows = _played(tmp_path / "t.fmu", steps)
    assert np.all(np.isfinite(rows))
    # closed forms of the piecewise-linear signal: the mean of a line is its midpoint's value
    assert rows[1, 1] == pytest.approx(-4e154 + 0.5 * 0.1 * 8e154, rel=1e-12)  # over [0, 1e152]
    assert rows[3].tolist() == [4e154, 4e154]  # past the last row: its value
    assert rows[0, 1] == pytest.approx(-4e154 * 1e-147 / 2, rel=1e-9, abs=4e154 * 1e-140)  # mostly before: before = 0


def _rows(rows, indent=None):
    """A signal table of ``rows`` rows 0.5 s apart holding i mod 7, and its JSON text."""
    table = {"kind": "signal_table", "time": [0.5 * i for i in range(rows)], "value": [float(i % 7) for i in range(rows)]}
    return table, json.dumps(table, indent=indent)


def test_a_table_beyond_the_native_bound_of_distinct_times_is_refused_at_once(tmp_path):
    """4e5 rows: refused before any C is written, the limit named (gcc needed minutes for it)."""
    code, out, err = _build(tmp_path, _rows(400_000)[0], "--native")
    assert code == 2 and "400,000 distinct times, more than the 100,000" in err and "MAX_TABLE_TIMES" in err, err


@pytest.mark.parametrize("native", [[], ["--native"]], ids=["pythonfmu", "native"])
def test_the_issue_s_15_mb_table_is_refused_at_once_for_what_a_model_description_holds(tmp_path, native):
    """A table is the start value of the table parameter in modelDescription.xml, which fmpy (libxml2)
    reads up to 10 MB of: a 15 MB one made an FMU no such host opens (and gcc never finished)."""
    text = _rows(100_000, indent=35)[1]
    assert 14e6 < len(text) < 16e6
    path = tmp_path / "t.json"
    path.write_text(text)
    code, out, err = guarded(["build", "reference", path, "-o", tmp_path / "t.fmu", *native], seconds=600)
    assert code == 2 and "more than the 10,000,000" in err and len(err.strip().splitlines()) == 1, err


def test_a_table_at_the_bounds_builds_natively_and_plays_its_rows(tmp_path):
    """10^5 distinct times in 8.6 MB of JSON text (9.4 MB as XML): its C compiles, fmpy reads the FMU, it plays its rows."""
    table, text = _rows(100_000, indent=18)
    assert 8e6 < len(text) < 10e6
    path = tmp_path / "t.json"
    path.write_text(text)
    code, out, err = guarded(["build", "reference", path, "-o", tmp_path / "t.fmu", "--native"], seconds=3000)
    assert code == 0, err
    for k in (1, 777, 99_999):  # y at a row's time, reached by a step from a quarter second before: its value
        assert _played(tmp_path / "t.fmu", [(0.5 * k - 0.25, 0.25)])[0, 0] == table["value"][k]
