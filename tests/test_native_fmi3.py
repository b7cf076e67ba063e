"""Every native FMU as FMI 3.0 (the generic FMI 3.0 layer, c/fmi3_layer*.c) against its FMI 2.0 twin.

Each kind of native FMU -- the plants, the Shaper (a closed-form and a build-time design), the
ImpulseTrain, the ShapeFilter, the EKF tuner, the STOS controller, the reference player and the profile generator --
is built from the same start values as FMI 2.0 and as FMI 3.0. The second opinions:

- fmpy's own FMI 3.0 simulation of the FMI 3.0 FMU equals fmpy's FMI 2.0 simulation of the twin,
  with an input signal and a design parameter set as an array (FMI 3.0) or as its elements (2.0);
- our C hosts, which keep time as t += h, trim the last step onto stop = 500 h and tear down from an
  exit handler registered before the FMU was loaded: hosts_c/fmi3_host.c on the FMI 3.0 FMU prints
  the rows hosts_c/fmi2_host.c prints on the twin, for steps of stop/500 and of random sizes;
- the same FMI 3.0 host under valgrind memcheck;
- fmpy.validation.validate_fmu on every FMI 3.0 archive, and the array parameters it declares.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest

from support import HOSTS_C, MODELS
from support.c_hosts import fmi3_arguments, fmu_arguments, host_rows, run_host
from support.cross_platform import PLATFORMS, missing_tools, windows_path
from support.fixtures_fmi import TRAIN_STARTS
from support.fixtures_native import FILTERS, ONE_MODE, TWO_MODES, shaper_starts
from support.valgrind import assert_clean_under_memcheck, requires_valgrind

STOP = 0.5

# name -> (twin model name, start values, stop time): every kind of native FMU.
CASES = {
    "shaper zvd": ("Shaper", shaper_starts("zvd", TWO_MODES), STOP),
    "shaper ei2": ("Shaper", shaper_starts("ei2", ONE_MODE), STOP),
    "impulse train": ("ImpulseTrain", TRAIN_STARTS, STOP),
    "filter hanning2": ("ShapeFilter", FILTERS["hanning2"], STOP),
    "filter TP:BC": ("ShapeFilter", FILTERS["TP:BC"], STOP),
    "ekf tuner": ("EKFTuner", {}, STOP),
    "tracked shaper": ("TrackedShaper", {}, STOP),
    "stos controller": ("STOSController", {}, STOP),
    "reference player": ("ReferencePlayer", {}, STOP),
    "profile generator": ("ProfileGenerator", {}, STOP),
    "scheduled shaper": ("ScheduledShaper", {}, STOP),
}
# Set in initialisation on both: FMI 2.0 by element, FMI 3.0 as the array (its other elements as built).
ARRAY_SETS = {"shaper zvd": ("f", 1, 14.5), "impulse train": ("impulse_time", 2, 0.0131),
              "filter hanning2": ("tap", 3, 0.125), "plant": ("f", 1, 2100.0)}


def _job(name, version, clock=False):
    if name == "plant":
        return "plant", (MODELS / "disk_drive.toml",), {"fmi_version": version}
    model, starts, _ = CASES[name]
    return "native", (model,), {"fmi_version": version, "clock": clock, **starts}


@pytest.fixture(scope="module")
def twins(builds):
    """{name: (FMI 2.0 FMU, FMI 3.0 FMU)} of every case and the disk-drive plant."""
    names = [*CASES, "plant"]
    paths = builds.many({(n, v): _job(n, v) for n in names for v in ("2.0", "3.0")})
    return {n: (paths[(n, "2.0")], paths[(n, "3.0")]) for n in names}


def _variables(fmu):
    from fmpy import read_model_description

    return {v.name: v for v in read_model_description(str(fmu)).modelVariables}


def _array_set(name, fmu2):
    """({FMI 2.0 element: value}, {FMI 3.0 array: values}) of the case's array parameter set, if any."""
    if name not in ARRAY_SETS:
        return {}, {}
    base, index, value = ARRAY_SETS[name]
    elements = sorted((v for v in _variables(fmu2).values() if v.name.startswith(f"{base}[")),
                      key=lambda v: int(v.name[len(base) + 1:-1]))
    values = [float(v.start) for v in elements]
    values[index - 1] = value
    return {f"{base}[{index}]": value}, {base: values}


@pytest.mark.parametrize("name", [*CASES, "plant"])
def test_the_fmi3_fmu_passes_fmpy_validation_with_its_arrays(twins, name):
    from fmpy.validation import validate_fmu

    fmu2, fmu3 = twins[name]
    assert validate_fmu(str(fmu3)) == []
    two, three = _variables(fmu2), _variables(fmu3)
    assert three["time"].causality == "independent"
    for variable in three.values():
        if variable.dimensions:  # an array parameter: the FMI 2.0 twin's elements base[1] .. base[n]
            (dimension,) = variable.dimensions
            count = int(dimension.start)
            assert variable.causality == "parameter"
            assert [f"{variable.name}[{i}]" for i in range(1, count + 1)] == [
                n for n in two if n.startswith(f"{variable.name}[")]
            starts = [float(s) for s in str(variable.start).split()]
            assert starts == [float(two[f"{variable.name}[{i}]"].start) for i in range(1, count + 1)]
        elif variable.name != "time":
            assert variable.name in two and variable.causality == two[variable.name].causality
    for element in set(two) - set(three):  # every FMI 2.0 variable is an FMI 3.0 one, or an array's element
        assert three[element.split("[")[0]].dimensions, element


def _input_signal(fmu2):
    inputs = [v.name for v in _variables(fmu2).values() if v.causality == "input" and v.type == "Real"]
    t = np.linspace(0.0, STOP, 501)
    signal = np.zeros(t.size, dtype=[("time", float)] + [(n, float) for n in inputs])
    signal["time"] = t
    for j, n in enumerate(inputs):
        signal[n] = np.sin(2 * np.pi * t / 0.05 + j) + (np.mod(t, 0.05) < 0.025)
    return signal if inputs else None


@pytest.mark.parametrize(("name", "interface"), [*((name, "CoSimulation") for name in CASES),
                                                ("plant", "CoSimulation"), ("plant", "ModelExchange")])
def test_fmpy_runs_the_fmi3_fmu_as_its_fmi2_twin(twins, name, interface):
    from fmpy import simulate_fmu

    fmu2, fmu3 = twins[name]
    outputs = [v.name for v in _variables(fmu2).values() if v.causality == "output"]
    starts2, starts3 = _array_set(name, fmu2)
    options = dict(stop_time=STOP, step_size=1e-3, output_interval=1e-3, output=outputs, input=_input_signal(fmu2),
                   fmi_type=interface)
    two = simulate_fmu(str(fmu2), start_values=starts2, **options)
    three = simulate_fmu(str(fmu3), start_values=starts3, **options)
    assert len(two) == len(three) == 501
    moving = 0
    for output in outputs:
        reference = two[output].astype(float)
        np.testing.assert_allclose(three[output].astype(float), reference, rtol=0,
                                   atol=1e-12 * max(1.0, float(np.max(np.abs(reference)))), err_msg=output)
        moving += np.ptp(reference) > 0
    assert moving, "no output moved: the comparison would prove nothing"


def _sets(name, fmu2, fmu3):
    """The hosts' --set-real (FMI 2.0) and --set (FMI 3.0) options of the case's array set."""
    starts2, starts3 = _array_set(name, fmu2)
    two = [a for element, value in starts2.items() for a in ("--set-real", f"{_variables(fmu2)[element].valueReference}={value!r}")]
    three = [a for array, values in starts3.items()
             for a in ("--set", f"{_variables(fmu3)[array].valueReference}={','.join(map(repr, values))}")]
    return two, three


@pytest.mark.parametrize("steps", ["stop/500", "random"])
@pytest.mark.parametrize("name", [*CASES, "plant"])
def test_c_hosts_keeping_time_as_t_plus_h_see_the_fmi3_fmu_as_its_twin(twins, c_host, fmi3_host, tmp_path, name, steps):
    fmu2, fmu3 = twins[name]
    stepping = ["--stop", STOP, "--steps", 500] if steps == "stop/500" else ["--random", 7, 1e-5, 5e-3, 400]
    set2, set3 = _sets(name, fmu2, fmu3)
    fmi2_fmu = fmu_arguments(fmu2, tmp_path / "two")
    two = run_host(c_host, [[*fmi2_fmu, *set2]], *stepping, *(["0"] if steps == "random" else []),
                   "--teardown", "atexit", "--csv", tmp_path / "two.csv")
    assert two.returncode == 0, two.stderr[-2000:]
    three = subprocess.run([str(fmi3_host), *map(str, stepping), *set3, "--teardown", "atexit", "--csv",
                            str(tmp_path / "three.csv"), *fmi3_arguments(fmu3, tmp_path / "three")],
                           capture_output=True, text=True, timeout=300)
    assert three.returncode == 0 and "exit handler: atexit done" in three.stderr, three.stderr[-2000:]
    rows2, rows3 = host_rows(tmp_path / "two.csv")[(0, 0, 0)], host_rows(tmp_path / "three.csv")[(0, 0, 0)]
    assert rows2.shape == rows3.shape and rows2.shape[0] > 400
    if steps == "stop/500":
        assert rows3[-1, 0] == STOP
    scale = max(1.0, float(np.max(np.abs(rows2))))
    np.testing.assert_allclose(rows3, rows2, rtol=0, atol=1e-12 * scale)
    assert np.ptp(rows2[:, 1:], axis=0).max() > 0


@pytest.mark.foreign
@requires_valgrind
@pytest.mark.parametrize("name", ["shaper zvd", "filter hanning2", "ekf tuner", "stos controller", "reference player",
                                  "profile generator", "plant"])
def test_the_fmi3_host_under_valgrind_finds_no_error_and_no_leak(twins, fmi3_host, tmp_path, name):
    fmu2, fmu3 = twins[name]
    _, set3 = _sets(name, fmu2, fmu3)
    for teardown in ("normal", "atexit"):
        assert_clean_under_memcheck([fmi3_host, "--stop", "0.05", "--steps", "50", *set3, "--teardown", teardown,
                                     *fmi3_arguments(fmu3, tmp_path / teardown)])


@pytest.mark.parametrize("name", [*CASES, "plant"])
def test_the_command_terminals_validate_and_name_the_command_variables(twins, name):
    import zipfile

    from lxml import etree

    import fmpy

    _, fmu3 = twins[name]
    schema = etree.XMLSchema(etree.parse(str(Path(fmpy.__file__).parent / "schema" / "fmi3" / "fmi3TerminalsAndIcons.xsd")))
    with zipfile.ZipFile(fmu3) as archive:
        document = etree.fromstring(archive.read("terminalsAndIcons/terminalsAndIcons.xml"))
        assert "terminalsAndIcons/icon.png" in archive.namelist()
    schema.assertValid(document)
    variables = _variables(fmu3)
    terminals = {t.get("name"): t.find("TerminalMemberVariable") for t in document.iter("Terminal")}
    assert terminals, "no command terminal"
    for terminal, causality in (("command_in", "input"), ("command_out", "output")):
        if terminal in terminals:
            member = terminals[terminal]
            assert member.get("memberName") == "command" and member.get("variableKind") == "signal"
            assert variables[member.get("variableName")].causality == causality


def test_the_cli_builds_a_native_fmu_as_fmi3_and_refuses_fmi3_for_pythonfmu(tmp_path, capsys):
    from fmpy import read_model_description

    from shapefmu.cli import main

    out = tmp_path / "STOS3.fmu"
    assert main(["build", "stos-controller", "--native", "--fmi-version", "3.0", "--param", "b=3000", "-o", str(out)]) == 0
    description = read_model_description(str(out))
    variables = {v.name: v for v in description.modelVariables}
    assert description.fmiVersion == "3.0" and float(variables["b"].start) == 3000.0
    assert [int(d.start) for d in variables["f"].dimensions] == [4]
    with pytest.raises(SystemExit):
        main(["build", "shaper", "--mode", "2000:0.01", "--fmi-version", "3.0", "-o", str(tmp_path / "S.fmu")])
    assert "--fmi-version 3.0 needs --native: the pythonfmu FMUs are FMI 2.0 only" in capsys.readouterr().err
    assert not (tmp_path / "S.fmu").exists()
    clocked = tmp_path / "EKF3.fmu"
    assert main(["build", "ekf-tuner", "--native", "--fmi-version", "3.0", "--clock", "--ts", "0.002", "-o",
                 str(clocked)]) == 0
    assert _interval(clocked) == 0.002 and _clock(clocked).name == "sample"
    with pytest.raises(SystemExit):
        main(["build", "ekf-tuner", "--native", "--clock", "-o", str(tmp_path / "E.fmu")])
    assert "--clock needs --fmi-version 3.0" in capsys.readouterr().err


# ---------------------------------------------------------------- --clock: the periodic input clock

SAMPLED = [name for name in CASES if name != "reference player"]


@pytest.fixture(scope="module")
def clocked(builds):
    """{name: FMI 3.0 FMU built with --clock} of every sampled case."""
    return builds.many({name: _job(name, "3.0", clock=True) for name in SAMPLED})


def _clock(fmu):
    (clock,) = [v for v in _variables(fmu).values() if v.type == "Clock"]
    return clock


def _interval(fmu) -> float:
    """The clock's intervalDecimal as modelDescription.xml declares it."""
    import re
    import zipfile

    text = zipfile.ZipFile(fmu).read("modelDescription.xml").decode()
    return float(re.search(r'intervalDecimal="([^"]+)"', text).group(1))


@pytest.mark.parametrize("name", SAMPLED)
def test_a_clocked_fmu_declares_its_sample_clock_and_clocks_its_inputs_and_outputs(twins, clocked, name):
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    fmu = clocked[name]
    assert validate_fmu(str(fmu)) == []
    description = read_model_description(str(fmu))
    assert description.coSimulation.hasEventMode
    clock = _clock(fmu)
    assert clock.causality == "input" and clock.intervalVariability == "constant"
    assert _interval(fmu) == float(_variables(twins[name][0])["Ts"].start)  # no case adjusts Ts
    for variable in description.modelVariables:
        if variable.causality in ("input", "output") and variable.type != "Clock":
            assert variable.variability == "discrete"
            assert [c.valueReference for c in variable.clocks] == [clock.valueReference]


@pytest.mark.parametrize("per_tick", [1, 2])
@pytest.mark.parametrize("name", SAMPLED)
def test_a_host_ticking_the_clock_sees_the_clocked_fmu_as_the_fmi2_twin(twins, clocked, c_host, fmi3_host, tmp_path,
                                                                        name, per_tick):
    """The clock ticks every Ts from t = 0; the hosts take per_tick steps of t += h between ticks: rows alike."""
    fmu2, _ = twins[name]
    fmu3 = clocked[name]
    ts = _interval(fmu3)
    steps = round(STOP / ts) * per_tick
    two = run_host(c_host, [fmu_arguments(fmu2, tmp_path / "two")], "--stop", STOP, "--steps", steps, "--teardown",
                   "atexit", "--csv", tmp_path / "two.csv")
    assert two.returncode == 0, two.stderr[-2000:]
    three = subprocess.run([str(fmi3_host), "--stop", str(STOP), "--steps", str(steps), "--clock",
                            str(_clock(fmu3).valueReference), repr(ts), "--teardown", "atexit", "--csv",
                            str(tmp_path / "three.csv"), *fmi3_arguments(fmu3, tmp_path / "three")],
                           capture_output=True, text=True, timeout=300)
    assert three.returncode == 0 and "exit handler: atexit done" in three.stderr, three.stderr[-2000:]
    rows2, rows3 = host_rows(tmp_path / "two.csv")[(0, 0, 0)], host_rows(tmp_path / "three.csv")[(0, 0, 0)]
    assert rows2.shape == rows3.shape and rows2.shape[0] >= steps + 1  # + 1: a trimmed sliver of a last step
    np.testing.assert_allclose(rows3, rows2, rtol=0, atol=1e-12 * max(1.0, float(np.max(np.abs(rows2)))))
    assert np.ptp(rows2[:, 1:], axis=0).max() > 0


def _clocked_slave(fmu, event_mode=True):
    from fmpy import extract, read_model_description
    from fmpy.fmi3 import FMU3Slave

    md = read_model_description(str(fmu))
    slave = FMU3Slave(guid=md.instantiationToken, unzipDirectory=extract(str(fmu)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="clocked")
    slave.instantiate(eventModeUsed=event_mode)
    return slave


def test_a_clocked_fmu_refuses_every_run_that_would_not_tick_it_rightly(clocked, capfd):
    """Each refusal logs a message naming the tick and returns fmi3Error (fmpy raises on it)."""
    from fmpy.fmi1 import FMICallException

    fmu = clocked["shaper zvd"]
    clock, ts = _clock(fmu).valueReference, _interval(fmu)
    with pytest.raises(Exception):
        _clocked_slave(fmu, event_mode=False)
    assert "instantiate it with eventModeUsed = fmi3True" in capfd.readouterr().out

    def started():
        slave = _clocked_slave(fmu)
        slave.enterInitializationMode(startTime=0.0)
        slave.exitInitializationMode()  # in Event Mode now, at the tick t = 0
        return slave

    refusals = {
        "not ticked before Step Mode": (lambda s: s.enterStepMode(), "t = 0 is a tick of the clock 'sample', which was not set"),
        "a step across a tick": (lambda s: (s.setClock([clock], [True]), s.updateDiscreteStates(), s.enterStepMode(),
                                            s.doStep(0.0, 1.5 * ts)), "passes the tick of the clock 'sample' at 0.001"),
        "a step from an untaken tick": (lambda s: (s.setClock([clock], [True]), s.enterStepMode(), s.doStep(0.0, ts),
                                                   s.doStep(ts, ts)), "was not ticked at t = 0.001"),
        "a tick off the grid": (lambda s: (s.setClock([clock], [True]), s.enterStepMode(), s.doStep(0.0, ts / 2),
                                           s.enterEventMode(), s.setClock([clock], [True])),
                                "ticks at t0 + k Ts (Ts = 0.001), not at t = 0.0005"),
    }
    for case, (calls, words) in refusals.items():
        slave = started()
        with pytest.raises(FMICallException) as refused:
            calls(slave)
        assert refused.value.status == 3, case
        assert words in capfd.readouterr().out, case
        slave.freeInstance()
    slave = _clocked_slave(fmu)  # a Ts other than the clock's interval
    slave.enterInitializationMode(startTime=0.0)
    variables = _variables(fmu)
    slave.setFloat64([variables["Ts"].valueReference], [2e-3])
    with pytest.raises(FMICallException):
        slave.exitInitializationMode()
    assert "Ts = 0.002, but this FMU's clock 'sample' ticks every 0.001 s" in capfd.readouterr().out
    slave.freeInstance()


def test_fmpy_which_ticks_no_clock_stops_on_a_clocked_fmu_with_the_reason(clocked, capfd):
    """fmpy 0.3.32 never calls fmi3SetClock: the run stops, it is never silently the unclocked one."""
    from fmpy import simulate_fmu

    for event_mode in (False, True):
        with pytest.raises(Exception):
            simulate_fmu(str(clocked["shaper zvd"]), stop_time=0.01, output_interval=1e-3, use_event_mode=event_mode)
        out = capfd.readouterr().out
        assert ("eventModeUsed = fmi3True" in out) if not event_mode else ("which was not set" in out), out[-500:]


def test_clock_builds_are_refused_where_no_clock_can_tick(tmp_path):
    from shapefmu.fmi.native.twins import build_native

    with pytest.raises(ValueError, match="--clock: the ReferencePlayer FMU has no sample period Ts"):
        build_native("ReferencePlayer", tmp_path / "R.fmu", fmi_version="3.0", clock=True)
    with pytest.raises(ValueError, match="--clock needs --fmi-version 3.0"):
        build_native("Shaper", tmp_path / "S.fmu", clock=True)
    assert not list(tmp_path.iterdir())


@pytest.mark.foreign
@requires_valgrind
@pytest.mark.parametrize("name", ["shaper zvd", "ekf tuner", "profile generator"])
def test_a_clocked_fmu_under_valgrind_finds_no_error_and_no_leak(clocked, fmi3_host, tmp_path, name):
    fmu = clocked[name]
    assert_clean_under_memcheck([fmi3_host, "--stop", "0.05", "--steps", "100", "--clock", _clock(fmu).valueReference,
                                 repr(_interval(fmu)), "--teardown", "atexit", *fmi3_arguments(fmu, tmp_path)])


# ---------------------------------------------------------------- our master

SOURCE_TABLE = ('{"kind": "signal_table", "interpolation": "hold", "time": [0, 0.004, 0.011, 0.02, 0.031], '
                '"value": [0.0, 1.0, -0.5, 2.0, 0.25]}')


@pytest.fixture(scope="module")
def source(builds):
    """A native FMI 2.0 ReferencePlayer playing steps, to drive every input of a case."""
    return builds.native("ReferencePlayer", table=SOURCE_TABLE)


def _master_run(source, fmu, step, stop):
    from shapefmu.cosim import Master
    from shapefmu.fmi.ssp import System

    variables = _variables(fmu)
    system = System("driven").add("source", source).add("case", fmu)
    for variable in variables.values():
        if variable.causality == "input" and variable.type in ("Real", "Float64"):
            system.connect("source.y", f"case.{variable.name}")
    outputs = [f"case.{v.name}" for v in variables.values() if v.causality == "output" and v.type in ("Real", "Float64")]
    with Master(system, step, record=outputs) as master:
        return master.run(stop), outputs, master.loop_kind


@pytest.mark.parametrize("name", SAMPLED)
def test_our_master_runs_the_fmi3_fmu_with_and_without_its_clock_as_the_fmi2_twin(twins, clocked, source, name):
    fmu2, fmu3 = twins[name]
    step = _interval(clocked[name])
    stop = min(0.05, 2000 * step)
    two, outputs, kind2 = _master_run(source, fmu2, step, stop)
    three, _, kind3 = _master_run(source, fmu3, step, stop)
    ticked, _, kind_clocked = _master_run(source, clocked[name], step, stop)
    assert kind3 == kind2 and kind_clocked == "Python"  # the master ticks clocks in its Python loop
    moving = 0
    for output in outputs:
        scale = max(1.0, float(np.max(np.abs(two[output]))))
        np.testing.assert_allclose(three[output], two[output], rtol=0, atol=1e-12 * scale, err_msg=output)
        np.testing.assert_allclose(ticked[output], two[output], rtol=0, atol=1e-12 * scale, err_msg=output)
        moving += np.ptp(two[output]) > 0
    assert moving


def test_our_master_refuses_a_step_that_would_miss_a_clock_tick(clocked, source):
    from shapefmu.cosim import Master
    from shapefmu.fmi.ssp import System

    fmu = clocked["shaper zvd"]
    with pytest.raises(ValueError, match=r"component 'case': its clock \(value reference \d+\) has interval 0.001 s, "
                                         r"not a whole number of its communication step 0.0003 s"):
        Master(System("s").add("case", fmu), 3e-4)
    with pytest.raises(ValueError, match="not a whole number of its communication step 0.002 s"):
        Master(System("s").add("case", fmu), 1e-3, step_multiples={"case": 2})


@pytest.mark.parametrize("per_tick", [1, 2])
@pytest.mark.parametrize("name", SAMPLED)
def test_fmpy_simulates_the_clocked_fmu_as_its_fmi2_twin_when_a_hook_ticks_the_clock(twins, clocked, name, per_tick):
    """fmpy's simulate_fmu (0.3.32) schedules no clock, but runs an instance it is given and calls
    step_finished after every step: the test initialises the clocked FMU and ticks its clock at t0
    (as a clock-scheduling host does), and the hook ticks it at every tick the run reaches (Event
    Mode, fmi3SetClock, fmi3UpdateDiscreteStates, fmi3EnterStepMode). fmpy's own stepping, inputs and
    recording then give what fmpy's simulation of the FMI 2.0 twin gives."""
    from fmpy import simulate_fmu

    fmu2, fmu3 = twins[name][0], clocked[name]
    ts = _interval(fmu3)
    stop = min(STOP, 2000 * ts)
    h = ts / per_tick
    variables3 = _variables(fmu3)
    inputs = [v.name for v in _variables(fmu2).values() if v.causality == "input" and v.type == "Real"]
    outputs = [v.name for v in _variables(fmu2).values() if v.causality == "output" and v.type == "Real"]
    t = np.arange(round(stop / h) + 1) * h
    signal = np.zeros(t.size, dtype=[("time", float)] + [(n, float) for n in inputs])
    signal["time"] = t
    for j, n in enumerate(inputs):
        signal[n] = np.sin(2 * np.pi * t / (100 * ts) + j) + (np.mod(t, 100 * ts) < 50 * ts)
    options = dict(stop_time=stop, step_size=h, output_interval=h, output=outputs, input=signal if inputs else None)
    two = simulate_fmu(str(fmu2), **options)
    slave = _clocked_slave(fmu3)
    clock = [_clock(fmu3).valueReference]

    def tick():
        slave.setClock(clock, [True])
        slave.updateDiscreteStates()
        slave.enterStepMode()

    def ticking(time, recorder):
        if abs(time / ts - round(time / ts)) < 1e-6:
            slave.enterEventMode()
            tick()
        return True

    slave.enterInitializationMode(startTime=0.0)
    for n in inputs:  # fmpy applies the inputs at t0 in initialisation
        slave.setFloat64([variables3[n].valueReference], [float(signal[n][0])])
    slave.exitInitializationMode()
    tick()
    three = simulate_fmu(str(fmu3), fmu_instance=slave, initialize=False, terminate=False, step_finished=ticking, **options)
    slave.terminate()
    slave.freeInstance()
    assert len(three) == len(two) == t.size
    for output in outputs:
        reference = two[output].astype(float)
        scale = max(1.0, float(np.max(np.abs(reference))))
        np.testing.assert_allclose(three[output].astype(float), reference, rtol=0, atol=1e-12 * scale, err_msg=output)
    assert max(np.ptp(two[o]) for o in outputs) > 0


@pytest.mark.parametrize("name", ["reference player", "plant"])
def test_our_master_runs_the_unsampled_fmi3_fmus_as_their_fmi2_twins(twins, source, name):
    fmu2, fmu3 = twins[name]
    step, stop = (1e-4, 0.05) if name == "plant" else (1e-3, STOP)  # the default table moves after 0.05 s
    two, outputs, kind2 = _master_run(source, fmu2, step, stop)
    three, _, kind3 = _master_run(source, fmu3, step, stop)
    assert kind3 == kind2
    for output in outputs:
        scale = max(1.0, float(np.max(np.abs(two[output]))))
        np.testing.assert_allclose(three[output], two[output], rtol=0, atol=1e-12 * scale, err_msg=output)
    assert max(np.ptp(two[o]) for o in outputs) > 0


# ---------------------------------------------------------------- Windows and ARM

@pytest.mark.foreign
@pytest.mark.parametrize("platform", ["aarch64-linux", "x86_64-windows"])
def test_the_fmi3_libraries_for_windows_and_arm_run_as_the_linux_one(twins, clocked, cross_hosts, tmp_path, platform):
    """hosts_c/fmi3_host.c cross-compiled (mingw-w64 for Windows, run under Wine; gcc-aarch64 for ARM,
    under qemu) loads each FMI 3.0 FMU's library for its platform and prints the x86_64-linux rows
    (1e-12 of their scale): every kind, a clocked one too."""
    from fmpy import read_model_description

    host_platform = "win64" if platform == "x86_64-windows" else platform  # plan-host platform names
    reason = missing_tools(host_platform)
    if reason:
        pytest.skip(reason)
    linux, cross = (cross_hosts.host(HOSTS_C / "fmi3_host.c", name) for name in ("linux64", host_platform))
    windows = windows_path if host_platform == "win64" else str
    fmus = {**{name: pair[1] for name, pair in twins.items()}, "clocked shaper": clocked["shaper zvd"]}
    for name, fmu in fmus.items():
        folder = tmp_path / name.replace(" ", "_").replace(":", "_")
        arguments = fmi3_arguments(fmu, folder)
        identifier = read_model_description(str(fmu)).coSimulation.modelIdentifier
        library = Path(arguments[1]) / "binaries" / platform / f"{identifier}{PLATFORMS[host_platform][2]}"
        clock = ["--clock", str(_clock(fmu).valueReference), repr(_interval(fmu))] if name == "clocked shaper" else []
        options = ["--stop", "0.2", "--steps", "200", *clock, "--teardown", "atexit"]
        native = cross_hosts.run("linux64", linux, [*options, "--csv", folder / "linux.csv", *arguments])
        assert native.returncode == 0, native.stderr[-2000:]
        foreign = [*options, "--library", windows(library), "--csv", windows(folder / "cross.csv"), arguments[0],
                   windows(arguments[1]), *arguments[2:]]
        completed = cross_hosts.run(host_platform, cross, foreign)
        assert completed.returncode == 0 and "atexit done" in completed.stderr, (name, completed.stderr[-2000:])
        reference, rows = host_rows(folder / "linux.csv")[(0, 0, 0)], host_rows(folder / "cross.csv")[(0, 0, 0)]
        assert reference.shape == rows.shape and reference.shape[0] > 200, name
        scale = max(1.0, float(np.max(np.abs(reference))))
        np.testing.assert_allclose(rows, reference, rtol=0, atol=1e-12 * scale, err_msg=name)


def test_a_clocked_fmu_state_keeps_the_ticks_taken(clocked):
    """An FMU state saved after the tick at t = 2 Ts, serialised and restored into a new instance,
    resumes there: the step from 2 Ts needs no new tick, and the replay equals the first run."""
    fmu = clocked["shaper zvd"]
    clock, ts, variables = [_clock(fmu).valueReference], _interval(fmu), _variables(fmu)
    u, y = variables["u"].valueReference, variables["y"].valueReference
    slave = _clocked_slave(fmu)
    slave.enterInitializationMode(startTime=0.0)
    slave.exitInitializationMode()

    def run(k0, k1, save_at=None):
        saved, out = None, []
        for k in range(k0, k1):
            if k > k0 or k0 == 0:
                if k > 0:
                    slave.enterEventMode()
                slave.setFloat64([u], [float(k % 3)])
                slave.setClock(clock, [True])
                slave.updateDiscreteStates()
                slave.enterStepMode()
            if k == save_at:
                saved = slave.serializeFMUState(slave.getFMUState())
            slave.doStep(k * ts, ts)
            out.append(slave.getFloat64([y])[0])
        return out, saved

    first, saved = run(0, 8, save_at=2)
    slave.freeInstance()
    slave = _clocked_slave(fmu)  # a new instance, in the Event Mode of t0 with no tick taken
    slave.enterInitializationMode(startTime=0.0)
    slave.exitInitializationMode()
    slave.setFMUState(slave.deserializeFMUState(saved))
    replay, _ = run(2, 8)  # a step from 2 Ts without the three ticks before it would be refused
    assert replay == first[2:] and len(set(first)) > 1
    slave.freeInstance()
