"""The master with every FMI 2.0 type, and FMUs that ask to end the simulation.

The FMU is tests/fmus_c/typed_stair.c (built by c_fmus.py): its outputs are closed forms of its
typed inputs and parameters, and it asks to end the simulation at ``stop_at`` as the FMI Reference
FMU Stair does, in Co-Simulation and in Model Exchange. fmpy.simulate_fmu is the second host.
"""

from __future__ import annotations

import numpy as np
import pytest
from support.c_fmus import build_typed_stair

from shapefmu.cosim import Master, Termination, save_results, simulate
from shapefmu.fmi.ssp import System, read_ssp, write_ssv

RECORD = ["a.counter", "a.n_out", "a.e_out", "a.b_out", "a.s_out", "a.x_out", "a.level",
          "b.counter", "b.n_out", "b.e_out", "b.b_out", "b.s_out", "b.x_out"]


@pytest.fixture(scope="module")
def stair(tmp_path_factory):
    return build_typed_stair(tmp_path_factory.mktemp("typed_stair"))


def test_the_typed_stair_fmu_passes_fmpy_validation(stair):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(stair)) == []


def counter(t, increment=1, period=1.0, sign=1):
    return sign * increment * np.floor(np.asarray(t) / period + 1e-9).astype(int)


def pair(stair, a=None, b=None, ssv=None) -> System:
    """a feeds b with every type: counter -> n_in, e_out -> e_in, b_out -> b_in, s_out -> s_in, x_out -> x_in."""
    return (System("typed").add("a", stair, a, ssv=ssv).add("b", stair, b)
            .connect("a.counter", "b.n_in").connect("a.e_out", "b.e_in").connect("a.b_out", "b.b_in")
            .connect("a.s_out", "b.s_in").connect("a.x_out", "b.x_in"))


def check_closed_form(result, increment, sign, negate, label, x_in, period=1.0, label_b="stair"):
    t = result["time"]
    c = counter(t, increment, period, sign)
    np.testing.assert_array_equal(result["a.counter"], c)
    np.testing.assert_array_equal(result["a.n_out"], c)  # n_in = 0
    np.testing.assert_array_equal(result["a.e_out"], 2)  # e_in = up (1) -> down (2)
    assert result["a.b_out"].tolist() == [negate] * len(t)
    assert result["a.s_out"].tolist() == [f"{label}:"] * len(t)
    np.testing.assert_allclose(result["a.level"], x_in * t, rtol=0, atol=1e-12)
    # b sees a's outputs of the same instant: a steps first (Gauss-Seidel), and a's echoed outputs
    # (e_out, b_out, s_out, x_out feed through) are passed on as read before a's step, when they
    # are functions of a's constant inputs; counter does not feed through and is read after it.
    np.testing.assert_array_equal(result["b.counter"], counter(t))
    np.testing.assert_array_equal(result["b.n_out"][1:], 2 * c[1:] + counter(t[1:]))
    np.testing.assert_array_equal(result["b.e_out"], 1)  # e_in = down -> up
    assert result["b.b_out"].tolist() == [negate] * len(t)  # b's negate is false
    assert result["b.s_out"].tolist()[1:] == [f"{label_b}:{label}:"] * (len(t) - 1)


def test_every_type_is_bound_connected_and_recorded_with_its_type(stair, tmp_path):
    ssv = write_ssv(tmp_path / "a.ssv", {"increment": 3, "negate": True, "label": "from-ssv"})
    system = pair(stair, {"mode": "down", "x_in": 0.5, "period": 0.25}, ssv=ssv)
    for path in (system.write_ssd(tmp_path / "typed.ssd"), system.write_ssp(tmp_path / "typed.ssp")):
        result = simulate(read_ssp(path), 2.0, 0.125, record=RECORD)
        assert result.dtype["a.counter"] == np.int32 and result.dtype["a.b_out"] == np.bool_
        assert result.dtype["a.s_out"].kind == "O" and result.dtype["a.x_out"] == np.float64
        check_closed_form(result, increment=3, sign=-1, negate=True, label="from-ssv", x_in=0.5, period=0.25)


def test_run_parameters_are_typed_by_the_model_description(stair):
    # what `--set` hands over: text, typed by each variable's declared type
    text = {"a.increment": "2", "a.mode": "down", "a.negate": "true", "a.label": "set", "a.x_in": "1.5"}
    result = simulate(pair(stair), 3.0, 0.5, record=RECORD, parameters=text)
    check_closed_form(result, increment=2, sign=-1, negate=True, label="set", x_in=1.5)


@pytest.mark.parametrize("parameters, message", [
    ({"a.increment": "2.5"}, r"parameter a.increment must be an integer in \[-2147483648, 2147483647\] \(Integer\), got '2.5'"),
    ({"a.mode": "sideways"}, r"parameter a.mode must be one of up, down or its number \(Enumeration\), got 'sideways'"),
    ({"a.negate": "maybe"}, r"parameter a.negate must be true, false, 1 or 0 \(Boolean\), got 'maybe'"),
    ({"a.period": "fast"}, r"parameter a.period must be a number \(Real\), got 'fast'"),
])
def test_a_run_parameter_of_the_wrong_type_is_refused_naming_it(stair, parameters, message):
    with Master(pair(stair), 0.5) as master, pytest.raises(ValueError, match=message):
        master.run(1.0, parameters=parameters)


@pytest.mark.parametrize("start, end, message", [
    ("a.counter", "b.x_in", "type mismatch, Integer a.counter -> Real b.x_in"),
    ("a.b_out", "b.n_in", "type mismatch, Boolean a.b_out -> Integer b.n_in"),
    ("a.counter", "b.e_in", "type mismatch, Integer a.counter -> Enumeration Direction b.e_in"),
    ("a.s_out", "b.b_in", "type mismatch, String a.s_out -> Boolean b.b_in"),
])
def test_a_type_mismatch_is_refused_naming_both_ends(stair, start, end, message):
    system = System().add("a", stair).add("b", stair)
    with pytest.raises(ValueError, match=message):
        system.connect(start, end)


def test_a_typed_ssd_round_trips_its_enumeration_types_and_values(stair, tmp_path):
    ssd = pair(stair, {"mode": "down", "negate": True}).write_ssd(tmp_path / "typed.ssd")
    text = ssd.read_text()
    assert '<ssc:Enumeration name="Direction" />' in text and '<ssv:Enumeration value="down" />' in text
    assert '<ssc:Item name="down" value="2" />' in text
    again = read_ssp(ssd)
    assert again.parameter_values("a") == {"mode": 2, "negate": True}
    assert again.components["a"].connectors["e_in"].declared_type == "Direction"


def test_numeric_connections_run_in_the_compiled_loop_bit_for_bit(stair):
    system = (System().add("a", stair, {"increment": 4}).add("b", stair)
              .connect("a.counter", "b.n_in").connect("a.e_out", "b.e_in").connect("a.b_out", "b.b_in")
              .connect("a.x_out", "b.x_in"))
    record = [r for r in RECORD if "s_out" not in r]
    results = {}
    for native in (True, False):
        with Master(system, 0.1, native=native, record=record) as master:
            assert master.loop_kind == ("C" if native else "Python")
            results[native] = master.run(2.35, parameters={"a.x_in": 0.75})
    assert results[True].tobytes() == results[False].tobytes()
    np.testing.assert_array_equal(results[True]["b.n_out"][1:], 2 * counter(results[True]["time"][1:], 4)
                                  + counter(results[True]["time"][1:]))


def test_a_string_connection_runs_the_python_loop_and_says_why(stair):
    with Master(pair(stair), 0.5) as master:
        assert master.loop_kind == "Python"
        assert master.loop_reason == "connection a.s_out -> b.s_in joins String variables, which the compiled loop does not move"


@pytest.mark.parametrize("native", [True, False], ids=["C", "Python"])
def test_a_cosimulation_fmu_ending_the_simulation_ends_the_run_normally(stair, native):
    from fmpy import simulate_fmu

    h, stop_at = 0.2, 9.0
    with Master(pair(stair, {"stop_at": stop_at, "increment": 3, "x_in": 2.0}), h, native=native,
                record=["a.counter", "a.level", "b.counter"]) as master:
        result = master.run(12.0)
    assert master.termination == Termination("a", stop_at, "fmi2DoStep returned fmi2Discard and fmi2Terminated is true")
    assert result["time"][-1] == stop_at and len(result) == 46  # t = 0, 0.2, ..., 9.0
    want = simulate_fmu(str(stair), stop_time=12.0, output_interval=h, output=["counter", "level"],
                        start_values={"stop_at": stop_at, "increment": 3, "x_in": 2.0})
    np.testing.assert_allclose(result["time"], want["time"], rtol=0, atol=1e-12)  # fmpy also ends at 9.0
    np.testing.assert_array_equal(result["a.counter"], want["counter"])
    np.testing.assert_allclose(result["a.level"], want["level"], rtol=0, atol=1e-12)
    assert result["a.counter"][-1] == 27 and result["b.counter"][-1] == 9  # b finished the macro step too


def test_a_model_exchange_fmu_ending_the_simulation_ends_the_run_at_its_event(stair):
    # stop_at = 2.3 lies inside the macro step [2.25, 2.5]: the run ends at the event itself.
    with Master(System().add("a", stair, {"stop_at": 2.3, "period": 0.5, "x_in": -1.5}), 0.25,
                model_exchange=["a"], record=["a.counter", "a.level"]) as master:
        result = master.run(5.0)
    assert master.termination.component == "a" and "terminateSimulation" in master.termination.call
    assert result["time"][-1] == pytest.approx(2.3, abs=1e-12)
    np.testing.assert_allclose(result["time"][:-1], 0.25 * np.arange(10), atol=1e-12)
    np.testing.assert_array_equal(result["a.counter"], counter(result["time"], period=0.5))
    np.testing.assert_allclose(result["a.level"], -1.5 * result["time"], rtol=0, atol=1e-9)


@pytest.mark.parametrize("interface, call", [
    ([], "fmi2DoStep returned fmi2Discard and fmi2Terminated is true"),
    (["--model-exchange", "stair"], "fmi2NewDiscreteStates set terminateSimulation"),
], ids=["CoSimulation", "ModelExchange"])
def test_cli_simulate_ends_with_exit_0_and_says_who_ended_the_run(stair, tmp_path, capsys, interface, call):
    from shapefmu.cli import main

    ssd = System("stair").add("stair", stair).write_ssd(tmp_path / "stair.ssd")
    out = tmp_path / "r.csv"
    code = main(["simulate", str(ssd), "--stop", "12", "--step", "0.2", "--set", "stair.stop_at=9",
                 "--set", "stair.mode=down", "--set", "stair.negate=true", "--set", "stair.label=cli",
                 "--record", "stair.counter", "--record", "stair.b_out", "--record", "stair.s_out", "--out", str(out),
                 "--plot", str(tmp_path / "r.png"), *interface])
    captured = capsys.readouterr()
    assert code == 0
    assert f"component 'stair' ended the simulation at t = 9 s ({call}): a normal end" in captured.err
    assert "46 records to t = 9 s" in captured.out
    lines = out.read_text().splitlines()
    assert lines[0] == "time,stair.counter,stair.b_out,stair.s_out"
    assert lines[-1] == "9,-9,true,cli:"
    assert (tmp_path / "r.png").read_bytes()[:4] == b"\x89PNG"


def test_typed_results_save_as_csv_and_parquet_with_their_types(stair, tmp_path):
    import pyarrow.parquet as pq

    result = simulate(pair(stair, {"negate": True, "label": "p"}), 1.0, 0.5, record=RECORD)
    table = pq.read_table(save_results(result, tmp_path / "r.parquet"))
    assert str(table.schema.field("a.counter").type) == "int32" and str(table.schema.field("a.b_out").type) == "bool"
    assert table["a.s_out"].to_pylist() == ["p:"] * 3
    for name in result.dtype.names:
        assert table[name].to_pylist() == result[name].tolist()
    rows = save_results(result, tmp_path / "r.csv").read_text().splitlines()
    assert rows[1].split(",")[1:6] == ["0", "0", "2", "true", "p:"]


def test_an_fmi_error_still_stops_with_component_call_and_time(stair):
    from shapefmu.cosim import CosimError

    # period <= 0 is refused by fmi2ExitInitializationMode with fmi2Error
    with pytest.raises(CosimError, match=r"component 'a' \(TypedStair.fmu\): fmi2ExitInitializationMode returned "
                                         r".*error.* at t = 0 s; FMU log: .*period must be > 0"):
        simulate(System().add("a", stair, {"period": 0.0}), 1.0, 0.1)
