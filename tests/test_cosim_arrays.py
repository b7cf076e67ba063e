"""FMI 3.0 array variables in the master: connected element by element, set whole or by element,
recorded a column per element -- against fmpy on the same FMU and the closed form of ArrayGain3
(tests/fmus_c/array_gain3.c: y = k .* u, total = s + sum(y), x += h y, m2 = 2 m), in both step loops.

ArrayGain3's getters and setters fail unless nValues is the number of elements over the value
references, so every run here also checks that the master passes it."""

from __future__ import annotations

import csv
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from support.c_fmus import build_array_gain3

import shapefmu
from shapefmu.cli import main
from shapefmu.cosim import Master
from shapefmu.fmi.ssp import System, read_ssp, write_ssv

H, STOP = 0.25, 1.0  # exact in binary: the closed forms hold to the last bit
TIMES = np.arange(0.0, STOP + H / 2, H)
KA, UA = np.array([2.0, 3.0, 4.0]), np.array([1.0, -2.0, 0.5])
KB = np.array([-1.0, 10.0, 0.25])

loops = pytest.mark.parametrize("native", [True, False], ids=["C", "Python"])


@pytest.fixture(scope="module")
def fmu(tmp_path_factory):
    return build_array_gain3(tmp_path_factory.mktemp("arrays"))


def column(result, name: str, n: int) -> np.ndarray:
    """The columns name[1] ... name[n] of a result, as an array of shape (rows, n)."""
    return np.column_stack([result[f"{name}[{i}]"] for i in range(1, n + 1)])


def run(system: System, native: bool, algorithm: str = "gauss-seidel", parameters=None, record=None):
    with Master(system, H, native=native, algorithm=algorithm, record=record) as master:
        assert master.loop_kind == ("C" if native else "Python")
        return master.run(STOP, parameters=parameters), list(master.record)


@loops
def test_one_array_fmu_records_what_fmpy_records(fmu, native):
    from fmpy import simulate_fmu

    start = {"k": KA, "u": UA, "s": 0.5, "m": [3, -4]}
    ours, record = run(System("one").add("g", fmu), native, parameters={f"g.{n}": v for n, v in start.items()})
    theirs = simulate_fmu(str(fmu), stop_time=STOP, step_size=H, output_interval=H,
                          start_values={n: list(v) if n != "s" else v for n, v in start.items()})
    assert record == ["g.y[1]", "g.y[2]", "g.y[3]", "g.total", "g.x[1]", "g.x[2]", "g.x[3]", "g.m2[1]", "g.m2[2]"]
    np.testing.assert_array_equal(ours["time"], theirs["time"])
    for name, n in (("y", 3), ("x", 3), ("m2", 2)):
        np.testing.assert_array_equal(column(ours, f"g.{name}", n), theirs[name], err_msg=name)
    np.testing.assert_array_equal(ours["g.total"], theirs["total"])
    np.testing.assert_array_equal(column(ours, "g.x", 3), np.outer(TIMES, KA * UA))  # x = t k u
    assert ours.dtype["g.m2[1]"] == np.int32 and list(ours[-1][["g.m2[1]", "g.m2[2]"]]) == [6, -8]


@loops
@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_an_array_output_feeds_an_array_input_element_by_element(fmu, native, algorithm):
    # a.x (no feed-through) -> b.u: b integrates kb * a.x, which is t ka ua.
    system = (System("pair").add("a", fmu, {"k": KA, "u": UA}).add("b", fmu, {"k": KB})
              .connect("a.x", "b.u"))
    result, _ = run(system, native, algorithm)
    n = np.arange(len(TIMES))
    seen = n if algorithm == "gauss-seidel" else np.maximum(n - 1, 0)  # Gauss-Seidel: a's new x; Jacobi: the last
    np.testing.assert_array_equal(column(result, "b.y", 3), np.outer(seen * H, KB * KA * UA))
    # b.x(t_N) = sum over its steps of h kb u: ka ua h^2 N(N+1)/2 (Gauss-Seidel) or N(N-1)/2 (Jacobi)
    steps = n * (n + 1) / 2 if algorithm == "gauss-seidel" else n * (n - 1) / 2
    np.testing.assert_array_equal(column(result, "b.x", 3), np.outer(steps * H * H, KB * KA * UA))


@loops
def test_an_element_feeds_a_scalar_and_a_scalar_feeds_an_element(fmu, native):
    system = (System("mixed").add("a", fmu, {"k": KA, "u": UA}).add("b", fmu, {"k": KB})
              .connect("a.y[2]", "b.s").connect("a.total", "b.u[3]"))
    result, _ = run(system, native, parameters={"b.u[1]": 5.0})
    a_total = np.sum(KA * UA)
    u_b = np.array([5.0, 2.0, a_total])  # u[2] unconnected and unset: its start value 2
    np.testing.assert_array_equal(column(result, "b.y", 3)[-1], KB * u_b)
    assert result["b.total"][-1] == KA[1] * UA[1] + np.sum(KB * u_b)


@loops
def test_integer_arrays_travel_in_their_own_family(fmu, native):
    system = System("ints").add("a", fmu, {"m": [3, -4]}).add("b", fmu).connect("a.m2", "b.m")
    result, _ = run(system, native, record=["b.m2", "a.m2[2]"])
    assert result.dtype.names == ("time", "b.m2[1]", "b.m2[2]", "a.m2[2]")
    assert [tuple(row) for row in result[["b.m2[1]", "b.m2[2]", "a.m2[2]"]]] == [(12, -16, -8)] * len(TIMES)


def test_ssp_binds_an_array_as_its_elements(fmu, tmp_path):
    system = System("bound").add("g", fmu, {"k": KA, "u[2]": 7.0})
    ssd = system.write_ssd(tmp_path / "bound.ssd")
    assert 'name="k[2]"' in ssd.read_text() and 'name="u[2]"' in ssd.read_text()
    again = read_ssp(ssd)
    assert again.parameter_values("g") == {"k[1]": 2.0, "k[2]": 3.0, "k[3]": 4.0, "u[2]": 7.0}
    result, _ = run(again, native=True, record=["g.y"])
    np.testing.assert_array_equal(column(result, "g.y", 3)[-1], KA * [1.0, 7.0, 3.0])  # u[1], u[3] at their starts


def test_an_ssd_may_declare_and_connect_single_elements(fmu, tmp_path):
    ssd = System("elements").add("a", fmu, {"k": KA, "u": UA}).add("b", fmu).connect("a.y[2]", "b.s").write_ssd(
        tmp_path / "elements.ssd")
    text = ssd.read_text()
    assert 'startConnector="y[2]"' in text
    # as SSP tools declare FMI 2.0 array elements: a connector per element used
    declared = '<ssd:Connector name="y" kind="output">'
    assert declared in text
    ssd.write_text(text.replace(declared, '<ssd:Connector name="y[2]" kind="output">', 1))
    result, _ = run(read_ssp(ssd), native=True, record=["b.total"])
    assert result["b.total"][-1] == KA[1] * UA[1] + 1.0 + 2.0 + 3.0  # s + sum(k u) with b's start values


def test_an_ssv_file_binds_single_elements(fmu, tmp_path):
    ssv = write_ssv(tmp_path / "k.ssv", {"k[2]": -3.0, "u[1]": 4.0})
    result, _ = run(System("file").add("g", fmu, ssv=ssv), native=True, record=["g.y"])
    np.testing.assert_array_equal(column(result, "g.y", 3)[-1], [1.0 * 4.0, -3.0 * 2.0, 1.0 * 3.0])


def test_a_run_parameter_sets_one_element_over_the_ssp_binding_of_the_array(fmu):
    system = System("over").add("g", fmu, {"k": KA})
    result, _ = run(system, native=True, parameters={"g.k[3]": -1.0}, record=["g.y"])
    np.testing.assert_array_equal(column(result, "g.y", 3)[-1], [2.0 * 1, 3.0 * 2, -1.0 * 3])


def test_simulate_sets_a_whole_array_and_one_element_from_the_command_line(fmu, tmp_path):
    ssd = System("cli").add("g", fmu).write_ssd(tmp_path / "cli.ssd")
    out = tmp_path / "result.csv"
    environment = {**os.environ, "PYTHONPATH": str(Path(shapefmu.__file__).parents[1])}
    done = subprocess.run([sys.executable, "-m", "shapefmu", "simulate", str(ssd), "--stop", "1", "--step", "0.25",
                           "--set", "g.k=[0,0.001,2]", "--set", "g.u[3]=5", "--out", str(out)],
                          capture_output=True, text=True, env=environment, timeout=120)
    assert done.returncode == 0, done.stderr
    rows = list(csv.DictReader(out.open()))
    assert list(rows[0]) == ["time", "g.y[1]", "g.y[2]", "g.y[3]", "g.total", "g.x[1]", "g.x[2]", "g.x[3]",
                             "g.m2[1]", "g.m2[2]"]
    assert [float(rows[-1][f"g.y[{i}]"]) for i in (1, 2, 3)] == [0.0, 0.002, 10.0]


@pytest.mark.parametrize("value, message", [
    ("[0,0.001]", "parameter g.k has 3 elements, got 2 values: '[0,0.001]'"),
    ("0.5", "is an array of 3 elements: give all as [v1, ..., v3] or one as name[i]"),
])
def test_simulate_refuses_an_array_value_of_the_wrong_size(fmu, tmp_path, capsys, value, message):
    ssd = System("cli").add("g", fmu).write_ssd(tmp_path / "cli.ssd")
    with pytest.raises(SystemExit) as exit_:
        main(["simulate", str(ssd), "--stop", "1", "--step", "0.25", "--set", f"g.k={value}"])
    error = capsys.readouterr().err
    assert exit_.value.code == 2 and message in error and len(error.strip().splitlines()) == 1


def test_run_parameters_refuse_an_array_value_of_the_wrong_size(fmu):
    with Master(System("one").add("g", fmu), H) as master, pytest.raises(ValueError) as error:
        master.run(STOP, parameters={"g.u": [1.0, 2.0]})
    assert str(error.value) == "parameter g.u has 3 elements, got 2 values: [1.0, 2.0]"


@pytest.mark.parametrize("start, end, message", [
    ("a.y", "b.s", "size mismatch, a.y has 3 element(s) and b.s 1"),
    ("a.total", "b.u", "size mismatch, a.total has 1 element(s) and b.u 3"),
    ("a.y[4]", "b.s", "a.y[4]: index 4 is beyond the 3 elements of a.y"),
])
def test_connections_of_different_sizes_are_refused_naming_both_ends(fmu, start, end, message):
    system = System("bad").add("a", fmu).add("b", fmu)
    with pytest.raises(ValueError) as error:
        system.connect(start, end)
    assert message in str(error.value) and "\n" not in str(error.value)


def test_an_element_is_connected_once_whether_alone_or_with_its_array(fmu):
    system = System("twice").add("a", fmu).add("b", fmu).connect("a.total", "b.u[2]")
    with pytest.raises(ValueError, match=r"input b\.u\[2\] is already connected from a\.total"):
        system.connect("a.y", "b.u")
