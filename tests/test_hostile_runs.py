"""Runs bounded before they start, and systems checked when they are read (issue 23).

Output intervals and stop times that would overflow the compiled loop, RK4 substep counts past any
use, more components than start in seconds, a Python FMU asked for minutes of work in one step,
nested sub-systems, component names that would break a results file, non-finite factors.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from hostile_support import guarded

from shapefmu.cosim import Master, simulate
from shapefmu.cosim.fmpy_log import listening
from shapefmu.fmi.ssp import System, read_ssp
from shapefmu.runtime import limits


@pytest.fixture(scope="module")
def plant_ssp(plant_fmus, tmp_path_factory):
    return (System("plant_alone").add("plant", plant_fmus["disk_drive"], {"voltage": 1.0})
            .write_ssp(tmp_path_factory.mktemp("runs") / "plant.ssp"))


@pytest.mark.parametrize("native", [True, False], ids=["C", "Python"])
def test_an_output_interval_longer_than_the_run_records_its_ends(plant_ssp, native):
    # 1e300 / 1e-6 does not fit the compiled loop's integer: it was a SIGFPE
    with Master(plant_ssp, 1e-6, output_interval=1e300, record=["plant.position"], native=native) as master:
        result = master.run(1e-3)
    assert result["time"].tolist() == [0.0, 1e-3]
    np.testing.assert_allclose(result["plant.position"][-1], 2.7e3 * 1e-3**2 / 2, rtol=1e-9)


def test_a_run_of_more_macro_steps_than_doubles_count_is_refused_at_once(plant_ssp):
    code, out, err = guarded(["simulate", str(plant_ssp), "--stop", "1e40", "--step", "1", "--output-interval", "1e40"],
                             seconds=20)
    assert code == 2 and "1e+40 macro steps, more than the limit of 9,007,199,254,740,992" in err and out == ""


@pytest.mark.parametrize("version", ["2.0", "3.0"])
@pytest.mark.parametrize("h, substep", [(1e300, None), (1e-3, 1e-300)])
def test_a_step_of_more_rk4_substeps_than_the_bound_is_refused(plant_fmus, tmp_path, version, h, substep):
    from fmpy import instantiate_fmu

    from shapefmu.fmi.native import build_plant_fmu, model_from_file

    fmu = plant_fmus["pendulum"] if version == "2.0" else build_plant_fmu(model_from_file("pendulum"), tmp_path / "P3.fmu",
                                                                          fmi_version="3.0")
    messages = []
    description = read_model_description(str(fmu))
    if version == "2.0":  # fmpy's logger proxy is one slot for the process: instantiate_fmu(logger=) would dangle in it
        instance = FMU2Slave(guid=description.guid, unzipDirectory=extract(str(fmu)),
                             modelIdentifier=description.coSimulation.modelIdentifier, instanceName="plant")
        instance.instantiate(callbacks=listening(lambda status, category, message: messages.append(message)))
    else:
        instance = instantiate_fmu(extract(str(fmu)), description, fmi_type="CoSimulation",
                                   logger=lambda environment, status, category, message: messages.append(message.decode()))
    vr = {v.name: v.valueReference for v in description.modelVariables}
    if version == "2.0":
        instance.setupExperiment(startTime=0.0)
        instance.enterInitializationMode()
    else:
        instance.enterInitializationMode(startTime=0.0)
    if substep is not None:
        (instance.setReal if version == "2.0" else instance.setFloat64)([vr["substep"]], [substep])
    instance.exitInitializationMode()
    with pytest.raises(FMICallException):
        instance.doStep(0.0, h)  # it answered OK, unintegrated, when the substep count overflowed
    assert any(f"more than the {limits.MAX_RK4_SUBSTEPS} substeps allowed per step" in m for m in messages), messages
    instance.freeInstance()


def test_a_system_of_more_components_than_the_bound_is_refused_before_loading_any(plant_fmus, monkeypatch):
    import shapefmu.cosim.master

    system = System("crowd")
    for i in range(limits.MAX_COMPONENTS + 1):
        system.add(f"p{i}", plant_fmus["mass_spring_chain"])
    loaded = []
    monkeypatch.setattr(shapefmu.cosim.master, "load_units", lambda *args: loaded.append(args))
    with pytest.raises(ValueError, match=r"system 'crowd' has 2,001 components, more than the limit of 2,000"):
        Master(system, 1e-3)
    assert loaded == []  # refused before 2001 libraries were bound (minutes), whatever the machine's speed


def test_a_system_past_the_compiled_loop_s_size_runs_the_python_loop_and_says_why(plant_fmus):
    system = System("many")
    for i in range(129):
        system.add(f"p{i}", plant_fmus["mass_spring_chain"], {"force": 1.0})
    with Master(system, 1e-3, record=["p0.x_1", "p128.x_1"]) as master:
        assert master.loop_kind == "Python" and "129 components, more than the 128" in master.loop_reason
        result = master.run(1e-2)
    assert result["p0.x_1"].tobytes() == result["p128.x_1"].tobytes() and result["p0.x_1"][-1] > 0


def test_a_python_fmu_refuses_a_step_of_minutes_of_work_at_once(ekf_fmu, capfd):
    description = read_model_description(str(ekf_fmu))
    slave = FMU2Slave(guid=description.guid, unzipDirectory=extract(str(ekf_fmu)),
                      modelIdentifier=description.coSimulation.modelIdentifier)
    slave.instantiate(loggingOn=True)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    ts = next(float(v.start) for v in description.modelVariables if v.name == "Ts")
    before = slave.serializeFMUstate(slave.getFMUstate())
    with pytest.raises(FMICallException):
        slave.doStep(0.0, 1e6 * ts)  # 10^6 samples of 22 us: 22 s of EKF work
    assert "per step (about a second of this FMU's work" in capfd.readouterr().out
    # refused before its first sample (the state, its sample clock included, is as it was), on any machine
    assert slave.serializeFMUstate(slave.getFMUstate()) == before
    slave.freeInstance()


NESTED = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" version="1.0" name="outer">
  <ssd:System name="outer"><ssd:Elements>
    <ssd:Component name="plant" source="{fmu}"/>
    <ssd:System name="sub"><ssd:Elements><ssd:Component name="hidden" source="{fmu}"/></ssd:Elements></ssd:System>
  </ssd:Elements></ssd:System>
</ssd:SystemStructureDescription>
"""


def test_a_nested_sub_system_is_refused_by_name(plant_fmus, tmp_path):
    ssd = tmp_path / "nested.ssd"
    ssd.write_text(NESTED.format(fmu=plant_fmus["disk_drive"]))
    with pytest.raises(ValueError, match=r"System 'sub' in the Elements of system 'outer' is a nested element, which "
                                         r"shapefmu does not run"):
        read_ssp(ssd)


@pytest.mark.parametrize("name", ["pl\nant", "pl\rant", " plant", "pla.nt", "pl\tant"])
def test_a_component_name_that_would_break_a_results_file_is_refused(plant_fmus, tmp_path, name):
    with pytest.raises(ValueError, match="component name must be non-empty printable text without"):
        System().add(name, plant_fmus["disk_drive"])
    text = System("s").add("plant", plant_fmus["disk_drive"]).write_ssd(tmp_path / "s.ssd").read_text()
    escaped = name.replace("\n", "&#10;").replace("\r", "&#13;").replace("\t", "&#9;")  # kept by the XML parser
    (tmp_path / "s.ssd").write_text(text.replace('name="plant"', f'name="{escaped}"'))
    with pytest.raises(ValueError, match="its name must be non-empty printable text"):
        read_ssp(tmp_path / "s.ssd")


def test_a_component_name_with_a_comma_keeps_its_columns_in_the_csv(plant_fmus, tmp_path):
    from shapefmu.cosim import save_results

    result = simulate(System().add("pl,ant", plant_fmus["disk_drive"], {"voltage": 1.0}), 1e-5, 1e-6,
                      record=["pl,ant.position", "pl,ant.deflection_1"])
    rows = np.genfromtxt(save_results(result, tmp_path / "r.csv"), delimiter=",", skip_header=1)
    header = (tmp_path / "r.csv").read_text().splitlines()[0]
    assert header == 'time,"pl,ant.position","pl,ant.deflection_1"' and rows.shape == (11, 3)


@pytest.mark.parametrize("attribute", ['factor="nan"', 'factor="inf"', 'offset="1e400"', 'factor="x"'])
def test_a_non_finite_connection_factor_is_refused_when_read(plant_fmus, tmp_path, attribute):
    system = (System("s").add("a", plant_fmus["disk_drive"]).add("b", plant_fmus["disk_drive"])
              .connect("a.position", "b.voltage", factor=2.0, offset=0.5))
    text = system.write_ssd(tmp_path / "s.ssd").read_text()
    key = attribute.split("=")[0]
    changed = text.replace(f'{key}="{2.0 if key == "factor" else 0.5}"', attribute)
    assert changed != text
    (tmp_path / "s.ssd").write_text(changed)
    with pytest.raises(ValueError, match=rf"Connection 1: LinearTransformation {key} must be a finite real number"):
        read_ssp(tmp_path / "s.ssd")
    with pytest.raises(ValueError, match=rf"connection a.position -> b.voltage: {key} must be a finite real number"):
        System().add("a", plant_fmus["disk_drive"]).add("b", plant_fmus["disk_drive"]).connect(
            "a.position", "b.voltage", **{key: float("nan")})


def test_the_bounds_are_documented_where_every_limit_is(tmp_path):
    text = Path(limits.__file__).read_text()
    for name in ("MAX_RK4_SUBSTEPS", "MAX_COMPONENTS", "MAX_MACRO_STEPS", "MAX_WORKERS_PER_CORE", "MAX_INPUT_FILE_BYTES",
                 "PYTHON_STEP_SECONDS"):
        assert text.count(f"\n{name} = ") == 2, name  # its paragraph and its value
