"""SSP 1.0 files: round trips, parameter bindings, kept annotations, and errors that point at the spot."""

from __future__ import annotations

import zipfile

import pytest
from support.cosim_fmus import build_test_fmu

from shapefmu.fmi.ssp import System, read_ssp, read_ssv, write_ssv


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    directory = tmp_path_factory.mktemp("ssp_fmus")
    return {name: build_test_fmu(name, directory) for name in ("CosimRamp", "CosimGain")}


def two(fmus) -> System:
    return (System("pair").add("ramp", fmus["CosimRamp"], {"slope": 2.5})
            .add("gain", fmus["CosimGain"], {"k": -3.0}).connect("ramp.y", "gain.u", factor=4.0, offset=-1.0))


def test_ssp_round_trip_keeps_components_connections_and_parameters(fmus, tmp_path):
    original = two(fmus)
    original.stop_time = 2.0
    for path in (original.write_ssp(tmp_path / "pair.ssp"), original.write_ssd(tmp_path / "pair.ssd")):
        again = read_ssp(path)
        assert list(again.components) == ["ramp", "gain"]
        assert again.connections == original.connections
        assert again.parameter_values("ramp") == {"slope": 2.5}
        assert again.parameter_values("gain") == {"k": -3.0}
        assert again.stop_time == 2.0
    with zipfile.ZipFile(tmp_path / "pair.ssp") as archive:
        assert sorted(archive.namelist()) == ["SystemStructure.ssd", "resources/CosimGain.fmu", "resources/CosimRamp.fmu"]


def test_ssv_values_round_trip_with_their_types(tmp_path):
    values = {"a": 1.25, "n": 3, "on": True, "kind": "zvd"}
    assert read_ssv(write_ssv(tmp_path / "p.ssv", values)) == values


def edited_pair(fmus, folder, old: str, new: str):
    """The two-component system written as an .ssd whose first ``old`` is replaced by ``new``."""
    ssd = two(fmus).write_ssd(folder / "pair.ssd")
    ssd.write_text(ssd.read_text().replace(old, new, 1))
    return ssd


def test_unknown_annotations_are_kept_and_ignored(fmus, tmp_path):
    ssd = edited_pair(fmus, tmp_path, "</ssd:SystemStructureDescription>",
                      '<ssd:Annotations><ssc:Annotation type="com.opensimulationplatform"><osp:Algorithm xmlns:osp="urn:osp">'
                      '<osp:FixedStepAlgorithm baseStepSize="1e-4"/></osp:Algorithm></ssc:Annotation></ssd:Annotations>'
                      "</ssd:SystemStructureDescription>")
    system = read_ssp(ssd)
    assert len(system.components) == 2
    again = system.write_ssd(tmp_path / "again.ssd").read_text()
    assert "FixedStepAlgorithm" in again and "com.opensimulationplatform" in again


def test_system_level_binding_with_component_prefixed_names(fmus, tmp_path):
    ssd = edited_pair(fmus, tmp_path, "<ssd:Elements>",
                      '<ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues><ssv:ParameterSet version="1.0" name="p">'
                      '<ssv:Parameters><ssv:Parameter name="gain.c"><ssv:Real value="0.75"/></ssv:Parameter></ssv:Parameters>'
                      "</ssv:ParameterSet></ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings><ssd:Elements>")
    assert read_ssp(ssd).parameter_values("gain") == {"k": -3.0, "c": 0.75}


@pytest.mark.parametrize("build, message", [
    (lambda s: s.connect("ramp.y", "nope.u"), "unknown component 'nope'"),
    (lambda s: s.connect("ramp.y", "gain.nope"), "component 'gain' has no connector 'nope'"),
    (lambda s: s.connect("gain.u", "ramp.slope"), "start gain.u has causality 'input'"),
    (lambda s: s.connect("ramp.y", "gain.y"), "end gain.y has causality 'output'"),
    (lambda s: s.connect("gain.y", "gain.u"), "input gain.u is already connected from ramp.y"),
    (lambda s: s.connect("ramp", "gain.u"), "connection start must be 'component.variable'"),
    (lambda s: s.add("ramp", "missing.fmu"), "already in system"),
    (lambda s: s.add("other", "missing.fmu"), "FMU file of component 'other' not found: missing.fmu"),
    (lambda s: s.add("other2", s.components["ramp"].fmu, {"nope": 1.0}), "has no parameter or input 'nope'"),
])
def test_building_errors_name_the_element(fmus, build, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)").replace(".", r"\.")):
        build(two(fmus))


@pytest.mark.parametrize("edit, message", [
    (lambda x: x.replace('endElement="gain"', 'endElement="gian"'), r"pair\.ssd: Connection 1 \(ramp\.y -> gian\.u\): unknown component 'gian'"),
    (lambda x: x.replace('endConnector="u"', 'endConnector="v"'), r"Connection 1 \(ramp\.y -> gain\.v\): component 'gain' has no connector 'v'"),
    (lambda x: x.replace('source="CosimGain.fmu"', 'source="Gone.fmu"'), r"Component 'gain': FMU file not found: Gone\.fmu"),
    (lambda x: x.replace('<ssd:Connector name="u" kind="input">\n            <ssc:Real />',
                         '<ssd:Connector name="u" kind="input">\n            <ssc:Integer />'),
     r"Component 'gain': Connector 'u' is declared Integer but the FMU has Real"),
    (lambda x: x.replace("</ssd:Connections>",
                         '<ssd:Connection startElement="gain" startConnector="y" endElement="gain" endConnector="u" /></ssd:Connections>'),
     r"Connection 2 \(gain\.y -> gain\.u\): input gain\.u is already connected from ramp\.y"),
])
def test_file_errors_name_the_file_element_and_name(fmus, tmp_path, edit, message):
    ssd = two(fmus).write_ssd(fmus["CosimRamp"].parent / "pair.ssd")
    ssd.write_text(edit(ssd.read_text()))
    with pytest.raises(ValueError, match=message):
        read_ssp(ssd)
