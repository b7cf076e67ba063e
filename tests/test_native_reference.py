"""The native C ReferencePlayer FMU equals its pythonfmu twin.

Both play the same tables: the CasADi time-optimal input of the disk drive's move (a hold table with
exact switch instants) and a linear table with a jump; the native y and y_mean equal the pythonfmu
ones bit for bit in fmpy with steps that land on the switches (t += h) and with random steps (an
FMU state restored mid-run replays them), in libcosim and ecos, in our C host (t += h, exit-handler
teardown), and to 1e-12 on win64 under Wine and aarch64 under qemu. Another table is refused with a message, the declared start value
(the table's text, line ends included) is accepted, the table's size is bounded and its text checked
at build time, and valgrind finds nothing.
"""

import json
import re
import shutil

import numpy as np
import pytest
from cross_hosts import run_on_every_platform
from fmpy.validation import validate_fmu
from fmu_drivers import configured, initialised
from fmu_signal_drivers import run_ecos, run_fmpy, run_libcosim
from native_drivers import PRELUDE, declared, replayed_run

from shapefmu.fmi import build_fmu
from shapefmu.fmi.native import reference
from shapefmu.fmi.native.reference import build_native_reference

LINEAR = json.dumps({"kind": "signal_table", "interpolation": "linear", "before": -0.5,
                     "time": [0.1, 0.35, 0.35, 0.6, 0.8], "value": [0.0, 1.0, -2.0, 0.5, 0.5]})
OUTPUTS = ["y", "y_mean"]


@pytest.fixture(scope="module")
def players(tmp_path_factory, time_optimal_solution):
    folder = tmp_path_factory.mktemp("native_reference")
    tables = {"time-optimal": time_optimal_solution.to_json(), "linear": LINEAR}
    return {name: (build_native_reference(folder / f"native_{i}.fmu", table=text),
                   build_fmu("ReferencePlayer", folder / f"twin_{i}.fmu", table=text))
            for i, (name, text) in enumerate(tables.items())}


def test_validation_passes_and_the_variables_are_the_twins(players):
    native, twin = players["time-optimal"]
    assert validate_fmu(str(native)) == []
    assert declared(native, units=False) == declared(twin, units=False)


@pytest.mark.parametrize("case", ["time-optimal", "linear"])
def test_equals_the_twin_bit_for_bit_on_and_between_the_switches(players, case, time_optimal_solution):
    native, twin = players[case]
    end = time_optimal_solution.T if case == "time-optimal" else 1.0
    h = end / 400  # t += h drifts onto and around the switches
    runs = [run_fmpy(fmu, [{}] * 480, h, OUTPUTS) for fmu in (native, twin)]
    assert runs[0] == runs[1]
    assert len({row[0] for row in runs[1]}) > 2  # the table switched


def _random_times(end, seed):
    """Random communication points over [0, 1.2 end], one step in seven of 1e-15 s."""
    rng = np.random.default_rng(seed)
    steps = rng.uniform(1e-9, end / 14, 300)
    steps[::7] = 1e-15
    return np.concatenate([[0.0], np.cumsum(steps)])


@pytest.mark.parametrize("case", ["time-optimal", "linear"])
def test_equals_the_twin_with_random_steps_and_a_restored_state(players, case, time_optimal_solution):
    """Random steps straddle and end near the switches; the FMU state taken at step 120, restored
    after the run, replays the steps from there as the twin runs them."""
    native, twin = players[case]
    times = _random_times(time_optimal_solution.T if case == "time-optimal" else 1.0, 4)
    still = lambda k: {}  # noqa: E731
    rows, replayed = replayed_run(native, times, OUTPUTS, still, 120, still)
    twin_rows, _ = replayed_run(twin, times, OUTPUTS, still)
    assert rows == twin_rows and replayed == twin_rows[120:]
    assert len({row[0] for row in twin_rows}) > 2 and any(row[0] != row[1] for row in twin_rows)  # switched in steps


def test_the_declared_table_start_value_reads_back_as_the_fmu_holds_it(players, time_optimal_solution):
    """A solution's JSON (to_json, as ``build reference solution.json`` bakes it) spans lines: the
    modelDescription start value keeps its line ends, so a host setting the declared start value
    (fmpy, an SSP binding) gets the table, not fmi2Error."""
    from fmpy import read_model_description

    native, twin = players["time-optimal"]
    text = time_optimal_solution.to_json()
    assert "\n" in text
    for fmu in (native, twin):
        assert [v.start for v in read_model_description(str(fmu)).modelVariables if v.name == "table"] == [text]
    h = time_optimal_solution.T / 100
    runs = [run_fmpy(fmu, [{}] * 120, h, OUTPUTS, start_values={"table": text}) for fmu in (native, twin)]
    assert runs[0] == runs[1] and len({row[0] for row in runs[1]}) > 2


@pytest.mark.parametrize(("character", "code"), [("\uffff", "U+FFFF"), ("\ufffe", "U+FFFE"), ("\ud800", "U+D800")])
def test_a_table_text_xml_cannot_hold_is_refused_before_any_c_is_written(tmp_path, character, code):
    text = LINEAR[:-1] + f', "note": "{character}"}}'
    words = f"table: its value holds the character {code} at position {len(text) - 3}, which XML 1.0 (modelDescription"
    with pytest.raises(ValueError, match=re.escape(words)):
        build_native_reference(tmp_path / "Bad.fmu", table=text)
    assert not (tmp_path / "Bad.fmu").exists()


def test_equals_the_twin_in_libcosim_and_ecos(players):
    native, twin = players["time-optimal"]
    reference_rows = run_fmpy(twin, [{}] * 300, 1e-5, OUTPUTS)
    for run in (run_libcosim, run_ecos):
        np.testing.assert_allclose(run(native, [{}] * 300, 1e-5, OUTPUTS), reference_rows, rtol=0, atol=1e-12 * 11)


def test_equals_the_twin_in_the_c_host_with_drifting_time_and_exit_handler_teardown(players, c_host, tmp_path):
    from c_host import fmu_arguments, host_rows, run_host

    native, twin = players["linear"]
    csv = tmp_path / "both.csv"
    result = run_host(c_host, [fmu_arguments(twin, tmp_path / "twin"), fmu_arguments(native, tmp_path / "native")],
                      "--stop", 1.0, "--step", 1e-3, "--teardown", "atexit", "--csv", csv)
    assert result.returncode == 0, result.stderr[-3000:]
    rows = host_rows(csv)
    assert np.array_equal(rows[(0, 0, 0)], rows[(0, 1, 0)]) and len(rows[(0, 0, 0)]) >= 1000


def test_another_table_is_refused_with_a_message(players, capfd):
    from fmpy.fmi1 import FMICallException

    native, _ = players["linear"]
    slave, vr = configured(native, instance_name="bad")
    with pytest.raises(FMICallException):
        slave.setString([vr["table"]], [LINEAR.replace("0.8", "0.9")])
    slave.freeInstance()
    assert "table is the signal table this native FMU was built with" in capfd.readouterr().out


def test_a_table_larger_than_the_bound_is_refused_before_any_c_is_written(tmp_path, monkeypatch):
    monkeypatch.setattr(reference, "MAX_TABLE_TIMES", 3)
    with pytest.raises(ValueError, match=r"the table has 4 distinct times, more than the 3 a native ReferencePlayer holds"):
        build_native_reference(tmp_path / "Big.fmu", table=LINEAR)
    assert not (tmp_path / "Big.fmu").exists()


def test_the_c_host_on_linux64_win64_and_aarch64_gives_the_same_numbers(players, tmp_path):
    from fmpy import read_model_description

    native, _ = players["linear"]
    vr = {v.name: v.valueReference for v in read_model_description(str(native)).modelVariables}
    outputs = run_on_every_platform(native, f"output {vr['y']}\noutput {vr['y_mean']}\nrun 1000 0.001\n", tmp_path)
    assert outputs["linux64"].size == 2000 and np.ptp(outputs["linux64"]) > 2
    for platform in ("aarch64-linux", "win64"):
        np.testing.assert_allclose(outputs[platform], outputs["linux64"], rtol=0, atol=1e-12 * 2, err_msg=platform)


VALGRIND_DRIVER = PRELUDE + '#include "table_model.h"\n' + r"""
int main(void) {
    const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    const fmi2ValueReference outputs[2] = {0, 1}, table = 2;
    double out[2], t = 0.0;
    fmi2Component c = fmi2Instantiate("c", fmi2CoSimulation, table_model.guid, "", &callbacks, fmi2False, fmi2True);
    if (c == NULL) return 1;
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    const fmi2String same = table_model.table_text[0], other = "{}";  /* the whole text: one piece of 4000 bytes at most */
    CHECK(fmi2SetString(c, &table, 1, &same));
    REFUSED(fmi2SetString(c, &table, 1, &other));
    CHECK(fmi2Reset(c));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    CHECK(fmi2ExitInitializationMode(c));
    fmi2FMUstate state = NULL;
    for (int k = 0; k < 500; k++) {
        const double h = k % 5 == 0 ? 1e-16 : 3e-3;
        CHECK(fmi2DoStep(c, t, h, fmi2True));
        t += h;
        CHECK(fmi2GetReal(c, outputs, 2, out));
        if (k == 100) CHECK(fmi2GetFMUstate(c, &state));
    }
    fmi2String text = NULL;
    CHECK(fmi2GetString(c, &table, 1, &text));
    if (table_model.n_text_pieces != 1 || strcmp(text, table_model.table_text[0]) != 0) return 1;
    size_t size = 0;
    CHECK(fmi2SerializedFMUstateSize(c, state, &size));
    fmi2Byte *bytes = malloc(size);
    CHECK(fmi2SerializeFMUstate(c, state, bytes, size));
    fmi2FMUstate copy = NULL;
    CHECK(fmi2DeSerializeFMUstate(c, bytes, size, &copy));
    free(bytes);
    CHECK(fmi2SetFMUstate(c, copy));
    CHECK(fmi2FreeFMUstate(c, &copy));
    CHECK(fmi2FreeFMUstate(c, &state));
    CHECK(fmi2Terminate(c));
    fmi2FreeInstance(c);
    printf("ok %g\n", out[1]);
    return 0;
}
"""


@pytest.mark.skipif(shutil.which("valgrind") is None or shutil.which("gcc") is None, reason="needs valgrind and gcc")
def test_valgrind_finds_no_invalid_access_and_no_leak(players, tmp_path):
    from test_plantgen_valgrind import run_driver_under_valgrind

    run_driver_under_valgrind(players["time-optimal"][0], VALGRIND_DRIVER, tmp_path)
