"""The master against FMUs that behave as other tools' exports do, with fmpy as the second opinion.

The FMUs are TypedStair variants (tests/fmus_c, built by tests/support/c_fmus.py), each with one behaviour taken from
the standards' text and seen in a real export: a step with noSetFMUStatePriorToCurrentPoint = false kept
provisional (the OSP quarter-truck Wheel), every value reset in fmi2SetupExperiment (a 20-sim export),
discrete inputs of a Model Exchange FMU refused outside event mode (the FMI Reference FMUs), an FMI 3.0
FMU with FMU state and every integer type, a source whose ModelStructure omits ``dependencies``
(Reference FMU Stair, pythonfmu's Csvdemo), and a binary that cannot be loaded.
"""

from __future__ import annotations

import os

import fmpy
import numpy as np
import pytest
from support.c_fmus import build_typed_stair, build_typed_stair3

from shapefmu.cosim import AlgebraicLoopError, Master, simulate
from shapefmu.fmi.ssp import System, read_ssp

BUILD = {"2": build_typed_stair, "3": build_typed_stair3}


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("exporters")


@pytest.fixture(scope="module")
def fmus(folder):
    """One FMU per behaviour and FMI version: {(behaviour, version): path}."""
    built = {}
    for version, build in BUILD.items():
        built["plain", version] = build(folder, f"Plain{version}")
        built["provisional", version] = build(folder, f"Provisional{version}", quirks=("PROVISIONAL",))
        built["source", version] = build(folder, f"Source{version}", source=True, dependencies=False)
        built["declared source", version] = build(folder, f"DeclaredSource{version}", source=True)
    built["reset in setup", "2"] = build_typed_stair(folder, "ResetInSetup", quirks=("RESET_IN_SETUP",))
    return built


def first_row_per_time(result):
    """fmpy records an event's left and right limits at one time; keep the left (the master's row)."""
    _, first = np.unique(result["time"], return_index=True)
    return result[np.sort(first)]


def minimal_ssd(path, name: str, fmu, outputs: dict[str, str], bound: dict[str, tuple[str, object]]):
    """A one-component SSD as libcosim's demos write them: the connectors it needs (``outputs``: name ->
    Real | Integer) and bindings (``bound``: name -> (causality, value)); libcosim cannot read the
    ssd:Enumerations that System.write_ssd declares for TypedStair's Direction type."""
    def kind(value):
        return "Integer" if isinstance(value, int) else "Real"

    connectors = "".join(f'<ssd:Connector name="{n}" kind="output"><ssc:{t}/></ssd:Connector>' for n, t in outputs.items())
    connectors += "".join(f'<ssd:Connector name="{n}" kind="{c}"><ssc:{kind(v)}/></ssd:Connector>' for n, (c, v) in bound.items())
    parameters = "".join(f'<ssv:Parameter name="{n}"><ssv:{kind(v)} value="{v}"/></ssv:Parameter>' for n, (_, v) in bound.items())
    bindings = (f'<ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues><ssv:ParameterSet version="1.0" '
                f'name="parameters"><ssv:Parameters>{parameters}</ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues>'
                f'</ssd:ParameterBinding></ssd:ParameterBindings>') if bound else ""
    path.write_text(f"""<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
    xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" version="1.0" name="{name}">
  <ssd:System name="{name}"><ssd:Elements>
    <ssd:Component name="{name}" source="{os.path.relpath(fmu, path.parent)}">
      <ssd:Connectors>{connectors}</ssd:Connectors>{bindings}
    </ssd:Component>
  </ssd:Elements></ssd:System>
  <ssd:DefaultExperiment startTime="0.0"/>
</ssd:SystemStructureDescription>
""")
    return path


# ------------------------------------------------------------------------- 1: provisional steps


@pytest.mark.parametrize("version", ["2", "3"])
@pytest.mark.parametrize("native", [True, False], ids=["C", "Python"])
def test_a_step_that_will_not_be_rolled_back_is_final(fmus, version, native):
    # The FMU keeps a step called with noSetFMUStatePriorToCurrentPoint = false provisional: with false
    # on every step its level would stay at x_in * h (the quarter-truck Wheel stayed at its first step).
    fmu = fmus["provisional", version]
    with Master(System().add("w", fmu), 0.01, native=native, record=["w.level", "w.steps", "w.provisional_steps"]) as master:
        assert master.loop_kind == ("C" if native else "Python")
        result = master.run(1.0, parameters={"w.x_in": 2.0})
    want = fmpy.simulate_fmu(str(fmu), stop_time=1.0, step_size=0.01, output_interval=0.01,
                             start_values={"x_in": 2.0}, output=["level"])
    np.testing.assert_allclose(result["w.level"], want["level"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(result["w.level"][-1], 2.0, rtol=1e-12)
    assert result["w.steps"][-1] == 100 and result["w.provisional_steps"][-1] == 0


def test_a_provisional_fmu_runs_as_in_libcosim(fmus, tmp_path):
    from support.ssp_hosts import run_libcosim

    ssd = minimal_ssd(tmp_path / "wheel.ssd", "w", fmus["provisional", "2"], {"level": "Real"}, {"x_in": ("input", 2.0)})
    ours = simulate(read_ssp(ssd), 1.0, 0.01, record=["w.level"])
    theirs = run_libcosim(ssd, 0.01, 100, ["w.level"])
    np.testing.assert_allclose(ours["w.level"][1:], theirs[1:, 0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(ours["w.level"][-1], 2.0, rtol=1e-12)  # libcosim too: not frozen at 0.02


@pytest.mark.parametrize("version", ["2", "3"])
def test_only_the_steps_of_an_algebraic_loop_may_be_rolled_back(fmus, version):
    # a and b feed through (x_out = x_in + counter) in a ring: an algebraic loop, stepped with state
    # rollback, so only its steps pass false; c, outside the loop, gets true on every step.
    fmu = fmus["plain", version]
    system = (System().add("a", fmu, {"period": 0.3}).add("b", fmu, {"period": 0.7}).add("c", fmu)
              .connect("a.x_out", "b.x_in", factor=0.5).connect("b.x_out", "a.x_in", factor=0.25, offset=1.0)
              .connect("b.x_out", "c.x_in"))
    record = ["a.x_out", "b.x_out", "a.counter", "b.counter", "a.steps", "a.provisional_steps", "b.steps",
              "b.provisional_steps", "c.steps", "c.provisional_steps", "c.level"]
    with Master(system, 0.1, record=record) as master:
        assert [stage.is_loop for stage in master.stages] == [True, False]
        result = master.run(2.0)
    # the loop's fixed point: xa = 0.25 xb + 1 + ca, xb = 0.5 xa + cb (x_out = x_in + counter)
    ca, cb = result["a.counter"], result["b.counter"]
    xa = (0.25 * cb + 1.0 + ca) / (1.0 - 0.125)
    np.testing.assert_allclose(result["a.x_out"], xa, rtol=1e-12)
    np.testing.assert_allclose(result["b.x_out"], 0.5 * xa + cb, rtol=1e-12)
    np.testing.assert_array_equal(result["a.provisional_steps"], result["a.steps"])
    np.testing.assert_array_equal(result["b.provisional_steps"], result["b.steps"])
    assert result["c.steps"][-1] == 20 and result["c.provisional_steps"][-1] == 0
    # c integrates b's output as it was after each macro step (Gauss-Seidel, c after the loop)
    np.testing.assert_allclose(result["c.level"][1:], 0.1 * np.cumsum(result["b.x_out"][1:]), rtol=1e-12)


def test_an_fmi3_loop_uses_the_state_rollback_the_fmus_declare(fmus):
    fmu = fmus["plain", "3"]
    assert fmpy.read_model_description(str(fmu)).coSimulation.canGetAndSetFMUstate
    system = (System().add("a", fmu).add("b", fmu).connect("a.x_out", "b.x_in", factor=0.5)
              .connect("b.x_out", "a.x_in", offset=2.0))
    with Master(system, 0.25, record=["a.x_out", "b.x_out", "a.counter"]) as master:
        assert master.stages[0].is_loop
        result = master.run(2.0)
    c = result["a.counter"]  # both counters: period 1
    xa = (2.0 + 2 * c) / 0.5  # xa = (0.5 xa + c) + 2 + c
    np.testing.assert_allclose(result["a.x_out"], xa, rtol=1e-12)


def test_an_fmi3_loop_without_state_rollback_is_still_refused_by_name(fmus, folder):
    from support.c_fmus import typed_stair3_description

    from shapefmu.cosim import AlgebraicLoopError as Refused

    fmu = fmus["plain", "3"]
    stateless = folder / "Stateless3.fmu"
    import zipfile

    with zipfile.ZipFile(fmu) as source, zipfile.ZipFile(stateless, "w") as target:
        for item in source.infolist():
            data = source.read(item)
            if item.filename == "modelDescription.xml":
                data = typed_stair3_description("Plain3").replace('canGetAndSetFMUState="true"', 'canGetAndSetFMUState="false"').encode()
            target.writestr(item, data)
    system = System().add("a", stateless).add("b", fmu).connect("a.x_out", "b.x_in").connect("b.x_out", "a.x_in", factor=0.5)
    with pytest.raises(Refused, match="a cannot get/set its FMU state"):
        Master(system, 0.25)
    assert Refused is AlgebraicLoopError


# ------------------------------------------------------------------------- 2: values reset in setup


@pytest.mark.parametrize("native", [True, False], ids=["C", "Python"])
def test_bindings_and_run_values_survive_an_fmu_that_resets_them_in_setup(fmus, tmp_path, native):
    fmu = fmus["reset in setup", "2"]
    system = System("crane").add("crane", fmu, {"increment": 69, "period": 0.5})
    ssd = read_ssp(system.write_ssd(tmp_path / "crane.ssd"))
    want = fmpy.simulate_fmu(str(fmu), stop_time=2.0, step_size=0.25, output_interval=0.25,
                             start_values={"increment": 69, "period": 0.5, "x_in": 1.5}, output=["counter", "level"])
    with Master(ssd, 0.25, native=native, record=["crane.counter", "crane.level"]) as master:
        for run in range(2):  # the second run starts from fmi2Reset: the bindings must arrive again
            result = master.run(2.0, parameters={"crane.x_in": 1.5})
            np.testing.assert_array_equal(result["crane.counter"], want["counter"])
            np.testing.assert_allclose(result["crane.level"], want["level"], rtol=0, atol=1e-12)
    assert result["crane.counter"][-1] == 69 * 4


def test_bindings_reach_an_fmu_that_resets_them_in_setup_as_in_libcosim(fmus, tmp_path):
    from support.ssp_hosts import run_libcosim

    ssd = minimal_ssd(tmp_path / "crane.ssd", "crane", fmus["reset in setup", "2"], {"counter": "Integer"},
                      {"increment": ("parameter", 69)})
    ours = simulate(read_ssp(ssd), 3.0, 0.5, record=["crane.counter"])
    theirs = run_libcosim(ssd, 0.5, 6, ["crane.counter"])
    np.testing.assert_array_equal(ours["crane.counter"][1:], theirs[1:, 0])
    assert ours["crane.counter"][-1] == 69 * 3


# ------------------------------------------------------------------------- 3: discrete inputs of Model Exchange


def step_table(times, columns: dict, shifts: dict):
    """fmpy's input for the values the consumer held over each macro step: ``columns[name][k + shift]``
    over [t_k, t_k+1] (shift 0: the value at t_k; 1: at t_k+1, a producer's output computed in its step
    that Gauss-Seidel passes on after it), as a table with both limits at every change (fmpy takes a
    repeated time as a discontinuity)."""
    n = len(times) - 1
    held = {name: np.asarray(values)[shifts[name]: shifts[name] + n] for name, values in columns.items()}
    rows = []
    for k in range(n):
        if k and any(held[name][k] != held[name][k - 1] for name in held):
            rows.append((times[k], *(held[name][k - 1] for name in held)))
        rows.append((times[k], *(held[name][k] for name in held)))
    rows.append((times[n], *(held[name][n - 1] for name in held)))
    dtype = [("time", "f8")] + [(name, np.asarray(values).dtype) for name, values in columns.items()]
    return np.array(rows, dtype=dtype)


CONNECTED = {"x_out": "x_in", "counter": "n_in", "r_out": "r_in", "e_out": "e_in", "b_out": "b_in", "s_out": "s_in"}


@pytest.mark.parametrize("version", ["2", "3"])
@pytest.mark.parametrize("algorithm", ["jacobi", "gauss-seidel"])
def test_discrete_inputs_of_a_model_exchange_fmu_change_in_event_mode(fmus, version, algorithm):
    # src (Co-Simulation) feeds every input of dst, a Model Exchange FMU that refuses its discrete
    # inputs outside initialization and event mode, as the standard says; dst's outputs echo them.
    fmu = fmus["plain", version]
    connected = dict(CONNECTED, **({f"{t}_out": f"{t}_in" for t in ("int8", "uint16", "uint64")} if version == "3" else {}))
    system = System().add("src", fmu, {"period": 0.3, "label": "src"}).add("dst", fmu, {"period": 1e9, "label": "dst"})
    for output, input_ in connected.items():
        system.connect(f"src.{output}", f"dst.{input_}")
    wide = {"src.int8_in": -7, "src.uint16_in": 65535, "src.uint64_in": 2**64 - 1} if version == "3" else {}
    record = [f"src.{o}" for o in connected] + ["dst.n_out", "dst.r_out", "dst.level", "dst.e_out", "dst.b_out", "dst.s_out"]
    record += [f"dst.{t}_out" for t in ("int8", "uint16", "uint64")] if version == "3" else []
    with Master(system, 0.1, algorithm=algorithm, model_exchange=["dst"], record=record) as master:
        result = master.run(1.5, parameters={"src.x_in": 0.5, "src.r_in": 0.25, "src.negate": True, **wide})
    # fmpy integrates dst alone, fed the values the master held over each macro step: in Gauss-Seidel
    # src's counter after src's step, its outputs that feed through its inputs as read before it
    numeric = {i: result[f"src.{o}"] for o, i in connected.items() if result.dtype[f"src.{o}"].kind != "O"}
    shifts = {i: int(algorithm == "gauss-seidel" and i == "n_in") for i in numeric}
    table = step_table(result["time"], numeric, shifts)
    want = fmpy.simulate_fmu(str(fmu), fmi_type="ModelExchange", stop_time=1.5, output_interval=0.1, input=table,
                             start_values={"period": 1e9, "label": "dst"},
                             output=["n_out", "r_out", "level", "e_out", "b_out"])
    want = first_row_per_time(want)
    np.testing.assert_allclose(want["time"], result["time"], atol=1e-12)
    np.testing.assert_array_equal(result["dst.n_out"][1:], want["n_out"][1:])
    np.testing.assert_array_equal(result["dst.r_out"][1:], want["r_out"][1:])
    np.testing.assert_allclose(result["dst.level"], want["level"], rtol=1e-8, atol=1e-10)
    np.testing.assert_array_equal(result["dst.e_out"], 1)  # src.e_out = down -> dst.e_out = up
    assert result["dst.b_out"].tolist() == [True] * len(result)
    assert set(result["dst.s_out"].tolist()[1:]) == {"dst:src:"}
    if version == "3":
        assert result["dst.int8_out"][-1] == -7 and result["dst.uint16_out"][-1] == 65535
        assert int(result["dst.uint64_out"][-1]) == 2**64 - 1
    # the counter's changes reached dst: n_out = 2 n_in (dst's own counter stays 0)
    assert len(set(result["dst.n_out"].tolist())) > 3


# ------------------------------------------------------------------------- 5: FMI 3.0 integer types


@pytest.mark.parametrize("name, value", [
    ("uint32_in", 4_000_000_000), ("int64_in", -(2**62) - 5), ("uint64_in", 2**63 + 11), ("int8_in", -128),
    ("uint8_in", 255), ("int16_in", -32768), ("uint16_in", 65535), ("increment", -(2**31)),
])
def test_every_fmi3_integer_type_takes_its_whole_range(fmus, name, value):
    fmu = fmus["plain", "3"]
    output = name.replace("_in", "_out") if name.endswith("_in") else "counter"
    result = simulate(System().add("a", fmu), 1.0, 0.5, record=[f"a.{output}"], parameters={f"a.{name}": str(value)})
    want = fmpy.simulate_fmu(str(fmu), stop_time=1.0, output_interval=0.5, start_values={name: value}, output=[output])
    assert [int(v) for v in result[f"a.{output}"]] == [int(v) for v in want[output]]
    if name.endswith("_in"):
        assert int(result[f"a.{output}"][-1]) == value


@pytest.mark.parametrize("name, value, range_", [
    ("int8_in", 200, r"\[-128, 127\] \(Int8\)"), ("uint8_in", 300, r"\[0, 255\] \(UInt8\)"),
    ("uint16_in", -1, r"\[0, 65535\] \(UInt16\)"), ("int16_in", 40000, r"\[-32768, 32767\] \(Int16\)"),
    ("uint32_in", 2**32, r"\[0, 4294967295\] \(UInt32\)"), ("increment", 2**31, r"\[-2147483648, 2147483647\] \(Int32\)"),
    ("int64_in", 2**63, r"\[-9223372036854775808, 9223372036854775807\] \(Int64\)"),
    ("uint64_in", -1, r"\[0, 18446744073709551615\] \(UInt64\)"),
])
def test_an_fmi3_integer_out_of_its_type_is_refused_naming_the_type(fmus, name, value, range_):
    with Master(System().add("a", fmus["plain", "3"]), 0.5) as master, \
            pytest.raises(ValueError, match=rf"parameter a.{name} must be an integer in {range_}, got '{value}'"):
        master.run(1.0, parameters={f"a.{name}": str(value)})
    with pytest.raises(ValueError, match=rf"parameter '{name}' must be an integer in {range_}"):
        System().add("a", fmus["plain", "3"], {name: value})


# ------------------------------------------------------------------------- 6: sources without dependencies


@pytest.mark.parametrize("version", ["2", "3"])
@pytest.mark.parametrize("native", [True, False], ids=["C", "Python"])
def test_a_source_without_declared_dependencies_is_passed_on_after_its_step(fmus, version, native):
    # No `dependencies` attribute means "depends on every input"; a source has none, so its output is
    # a result of its step, which the consumer stepping after it sees at once (Gauss-Seidel).
    h, stop = 0.1, 2.0
    results = {}
    for kind in ("source", "declared source"):
        system = (System().add("stair", fmus[kind, version], {"period": 0.25}).add("sink", fmus["plain", version])
                  .connect("stair.x_out", "sink.x_in"))
        with Master(system, h, native=native, record=["stair.x_out", "sink.level"]) as master:
            results[kind] = master.run(stop)
    assert results["source"].tobytes() == results["declared source"].tobytes()
    alone = fmpy.simulate_fmu(str(fmus["source", version]), stop_time=stop, output_interval=h,
                              start_values={"period": 0.25}, output=["x_out"])
    np.testing.assert_array_equal(results["source"]["stair.x_out"], alone["x_out"])
    # sink integrates over [t_k, t_k+1] the value the stair reached at t_k+1
    np.testing.assert_allclose(results["source"]["sink.level"][1:], h * np.cumsum(alone["x_out"][1:]), rtol=0, atol=1e-12)


# ------------------------------------------------------------------------- 7: a binary that cannot be loaded


def test_an_fmu_whose_library_cannot_be_loaded_is_named_with_the_loaders_words(folder, fmus, tmp_path, capsys):
    from shapefmu.cli import main

    broken = build_typed_stair(folder, "NeedsGfortran", missing_library="shapefmu_missing_gfortran")
    ssd = (System("broken").add("ok", fmus["plain", "2"]).add("solver", broken).connect("ok.x_out", "solver.x_in")
           .write_ssd(tmp_path / "broken.ssd"))
    here = os.getcwd()
    with pytest.raises(SystemExit) as exit_:
        main(["simulate", str(ssd), "--stop", "1", "--step", "0.1"])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and os.getcwd() == here  # fmpy changes the directory to load a library
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert "component 'solver' (NeedsGfortran.fmu)" in err
    assert "binaries/linux64/NeedsGfortran.so" in err
    assert "libshapefmu_missing_gfortran.so: cannot open shared object file" in err


def test_an_fmu_without_a_binary_for_this_platform_says_what_it_has(folder, tmp_path):
    import zipfile

    fmu = build_typed_stair(folder, "Renamed")
    renamed = tmp_path / "Renamed.fmu"
    with zipfile.ZipFile(fmu) as source, zipfile.ZipFile(renamed, "w") as target:
        for item in source.infolist():
            target.writestr(item.filename.replace("Renamed.so", "renamed_by_hand.so"), source.read(item))
    with pytest.raises(ValueError, match=r"component 'r' \(Renamed.fmu\): no binaries/linux64/Renamed.so in the FMU "
                                         r"\(its binaries: binaries/linux64/renamed_by_hand.so\)"):
        Master(System().add("r", renamed), 0.1)
