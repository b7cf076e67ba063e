"""The ReferencePlayer FMU playing a CasADi time-optimal solution, against the runtime player and the solution."""

import json
import zipfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from support.fmpy_slaves import initialised, instantiated, variable_references
from support.hosts import run_ecos, run_fmpy, run_libcosim

from shapefmu.cli import main
from shapefmu.runtime.reference_player import from_dict


def _steps(solution, count=61):
    # A step that is no divisor of any switch instant: most steps straddle a switch.
    return solution.T * 1.17 / count, count


def test_model_description_passes_fmpy_validation(reference_fmu):
    assert validate_fmu(str(reference_fmu)) == []


def test_outputs_depend_on_no_input_and_the_solution_is_baked_in(reference_fmu, time_optimal_solution):
    root = ET.fromstring(zipfile.ZipFile(reference_fmu).read("modelDescription.xml"))
    assert [o.get("dependencies") for o in root.find("ModelStructure/Outputs")] == ["", ""]
    (table,) = [v for v in root.iter("ScalarVariable") if v.get("name") == "table"]
    assert json.loads(table.find("String").get("start")) == time_optimal_solution.to_dict()


def test_outputs_equal_the_solution_and_the_exact_step_mean(reference_fmu, time_optimal_solution):
    h, count = _steps(time_optimal_solution)
    rows = run_fmpy(reference_fmu, [{}] * count, h, ["y", "y_mean"])
    table = from_dict(time_optimal_solution.to_dict())
    ends = [(k + 1) * h for k in range(count)]
    # y at the end of each step is the solution's command there (right-continuous at switches).
    np.testing.assert_array_equal([row[0] for row in rows], time_optimal_solution.command(np.array(ends)))
    np.testing.assert_allclose([row[1] for row in rows], [table.average(k * h, (k + 1) * h) for k in range(count)],
                               rtol=0, atol=1e-12)


def test_a_step_ending_on_a_switch_returns_the_new_level(reference_fmu, time_optimal_solution):
    slave, vr = initialised(reference_fmu)
    switch = time_optimal_solution.switch_times[0]
    slave.doStep(0.0, switch)
    assert slave.getReal([vr["y"], vr["y_mean"]]) == [time_optimal_solution.levels[1], time_optimal_solution.levels[0]]
    slave.freeInstance()


def test_outputs_identical_in_fmpy_libcosim_and_ecos(reference_fmu, time_optimal_solution):
    h, count = _steps(time_optimal_solution, 40)
    h = round(h * 1e9) * 1e-9  # libcosim steps in whole nanoseconds: give every host that step
    reference = run_fmpy(reference_fmu, [{}] * count, h, ["y", "y_mean"])
    for other in (run_libcosim(reference_fmu, [{}] * count, h, ["y", "y_mean"]),
                  run_ecos(reference_fmu, [{}] * count, h, ["y", "y_mean"])):
        np.testing.assert_allclose(other, reference, rtol=0, atol=1e-12)


def test_state_restores_the_playback_position(reference_fmu, time_optimal_solution):
    h, count = _steps(time_optimal_solution)
    slave, vr = initialised(reference_fmu)
    for k in range(20):
        slave.doStep(k * h, h)
    state = slave.getFMUState()
    first = []
    for k in range(20, count):
        slave.doStep(k * h, h)
        first.append(slave.getReal([vr["y"], vr["y_mean"]]))
    slave.setFMUState(state)
    again = []
    for k in range(20, count):
        slave.doStep(k * h, h)
        again.append(slave.getReal([vr["y"], vr["y_mean"]]))
    slave.freeInstance()
    assert again == first


def test_a_table_that_is_not_json_fails_initialisation_with_a_logged_error(reference_fmu, capfd):
    vr = variable_references(reference_fmu)
    slave = instantiated(reference_fmu, "bad")
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setString([vr["table"]], ["time,u\n0,1\n"])
    with pytest.raises(FMICallException) as failure:
        slave.exitInitializationMode()
    assert failure.value.status == 3
    slave.freeInstance()
    assert "table must be JSON text of a signal_table or time_optimal object" in capfd.readouterr().out


def test_build_reference_from_csv_plays_the_same_signal(tmp_path, time_optimal_solution):
    (tmp_path / "solution.csv").write_text(time_optimal_solution.to_csv())
    out = tmp_path / "FromCsv.fmu"
    assert main(["build", "reference", str(tmp_path / "solution.csv"), "-o", str(out)]) == 0
    h, count = _steps(time_optimal_solution, 30)
    ends = np.arange(1, count + 1) * h
    np.testing.assert_array_equal([row[0] for row in run_fmpy(out, [{}] * count, h, ["y"])],
                                  time_optimal_solution.command(ends))


def test_build_reference_refuses_a_missing_file(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_status:
        main(["build", "reference", str(tmp_path / "none.json"), "-o", str(tmp_path / "x.fmu")])
    assert exit_status.value.code == 2
    assert "cannot read signal table" in capsys.readouterr().err


def test_cli_optimal_json_builds_a_player_of_that_solution(tmp_path):
    from shapefmu.optimal import time_optimal
    from shapefmu.plants import load

    model = Path(__file__).resolve().parents[1] / "models" / "disk_drive.toml"
    solution_file, out = tmp_path / "solution.json", tmp_path / "TimeOptimal.fmu"
    assert main(["optimal", str(model), "--distance", "0.05", "--json", str(solution_file)]) == 0
    assert main(["build", "reference", str(solution_file), "-o", str(out)]) == 0
    # The solver run anew gives the same move; the FMU plays it.
    solution = time_optimal(load(model), 0.05, 11.0)
    h, count = _steps(solution, 40)
    ends = np.arange(1, count + 1) * h
    np.testing.assert_allclose([row[0] for row in run_fmpy(out, [{}] * count, h, ["y"])], solution.command(ends),
                               rtol=0, atol=1e-12)
