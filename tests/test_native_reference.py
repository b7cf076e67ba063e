"""The native C ReferencePlayer FMU beyond the twin contract (tests/test_native_twin_contract.py:
equal to its pythonfmu twin bit for bit on and between the switches, with random steps and a
restored state, in every host, on three platforms, under valgrind): the declared start value (the
table's text, line ends included) is accepted, another table is refused with a message, and the
table's size is bounded and its text checked at build time."""

import re

import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException

from support.fmpy_slaves import configured
from support.hosts import run_fmpy
from support.twins import LINEAR_TABLE, REFERENCE_PLAYER

from shapefmu.fmi.native import reference
from shapefmu.fmi.native.reference import build_native_reference

OUTPUTS = REFERENCE_PLAYER.outputs


def test_the_declared_table_start_value_reads_back_as_the_fmu_holds_it(builds, time_optimal_solution):
    """A solution's JSON (to_json, as ``build reference solution.json`` bakes it) spans lines: the
    modelDescription start value keeps its line ends, so a host setting the declared start value
    (fmpy, an SSP binding) gets the table, not fmi2Error."""
    native, twin = REFERENCE_PLAYER.pair(builds, "time-optimal")
    text = time_optimal_solution.to_json()
    assert "\n" in text
    for fmu in (native, twin):
        assert [v.start for v in read_model_description(str(fmu)).modelVariables if v.name == "table"] == [text]
    h = time_optimal_solution.T / 100
    runs = [run_fmpy(fmu, [{}] * 120, h, OUTPUTS, start_values={"table": text}) for fmu in (native, twin)]
    assert runs[0] == runs[1] and len({row[0] for row in runs[1]}) > 2


@pytest.mark.parametrize(("character", "code"), [("\uffff", "U+FFFF"), ("\ufffe", "U+FFFE"), ("\ud800", "U+D800")])
def test_a_table_text_xml_cannot_hold_is_refused_before_any_c_is_written(tmp_path, character, code):
    text = LINEAR_TABLE[:-1] + f', "note": "{character}"}}'
    words = f"table: its value holds the character {code} at position {len(text) - 3}, which XML 1.0 (modelDescription"
    with pytest.raises(ValueError, match=re.escape(words)):
        build_native_reference(tmp_path / "Bad.fmu", table=text)
    assert not (tmp_path / "Bad.fmu").exists()


def test_another_table_is_refused_with_a_message(builds, capfd):
    native, _ = REFERENCE_PLAYER.pair(builds, "linear")
    slave, vr = configured(native, instance_name="bad")
    with pytest.raises(FMICallException):
        slave.setString([vr["table"]], [LINEAR_TABLE.replace("0.8", "0.9")])
    slave.freeInstance()
    assert "table is the signal table this native FMU was built with" in capfd.readouterr().out


def test_a_table_larger_than_the_bound_is_refused_before_any_c_is_written(tmp_path, monkeypatch):
    monkeypatch.setattr(reference, "MAX_TABLE_TIMES", 3)
    with pytest.raises(ValueError, match=r"the table has 4 distinct times, more than the 3 a native ReferencePlayer holds"):
        build_native_reference(tmp_path / "Big.fmu", table=LINEAR_TABLE)
    assert not (tmp_path / "Big.fmu").exists()
