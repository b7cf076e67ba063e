"""SSP files written for OMSimulator: its vendor annotation, no String connectors or bindings, and
linear transformations folded into parameters -- checked by running both files in the master."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest
from support.c_fmus import build_typed_stair

from shapefmu.cosim import simulate
from shapefmu.fmi.ssp import System, read_ssp, write_ssv

VOLTS = 11.0


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    from shapefmu.fmi import build_fmu
    from shapefmu.fmi.native import build_plant_fmu

    folder = tmp_path_factory.mktemp("targets")
    return {"shaper": build_fmu("Shaper", folder / "Shaper.fmu", kind="zvd"),
            "plant": build_plant_fmu("models/disk_drive.toml", folder / "DiskDrive.fmu"),
            "stair": build_typed_stair(folder)}


def shaped_seek(fmus) -> System:
    """The shaped disk drive: a ZVD shaper on a unit step, scaled to 11 V by the connection."""
    return (System("shaped_seek")
            .add("shaper", fmus["shaper"], {"kind": "zvd", "f[1]": 2000.0, "zeta[1]": 0.01, "Ts": 1e-6, "u": 1.0})
            .add("plant", fmus["plant"], {"f[1]": 2100.0})
            .connect("shaper.y", "plant.voltage", factor=VOLTS))


def ssd_of(path) -> str:
    with zipfile.ZipFile(path) as archive:
        return archive.read("SystemStructure.ssd").decode()


def test_the_omsimulator_file_carries_its_annotation_and_no_linear_transformation(fmus, tmp_path):
    path = shaped_seek(fmus).write_ssp(tmp_path / "oms.ssp", target="omsimulator", step=1e-6, fold={"shaper.y": "u"})
    text = ssd_of(path)
    assert '<ssc:Annotation type="org.openmodelica">' in text
    assert '<oms:FixedStepMaster description="oms-ma" stepSize="1e-06" relativeTolerance="1e-06" />' in text
    assert '<oms:SimulationInformation resultFile="shaped_seek_res.csv" loggingInterval="0" />' in text
    assert "LinearTransformation" not in text
    assert '<ssc:String' not in text and 'name="kind"' not in text  # the FMU's own start value is zvd
    system = read_ssp(path)
    assert system.parameter_values("shaper")["u"] == VOLTS
    assert [(c.factor, c.offset) for c in system.connections] == [(1.0, 0.0)]
    # the default target keeps what libcosim and ecos read
    default = ssd_of(shaped_seek(fmus).write_ssp(tmp_path / "default.ssp"))
    assert 'factor="11.0"' in default and "org.openmodelica" not in default


def test_folding_the_factor_into_a_parameter_gives_the_same_run(fmus, tmp_path):
    h, n = 1e-6, 400
    record = ["plant.position", "plant.deflection_1"]
    original = simulate(shaped_seek(fmus).write_ssp(tmp_path / "a.ssp"), n * h, h, record=record)
    folded = {"shaper.y": "u"}, {"plant.voltage": ["b2", "b4[1]", "b4[2]"]}
    for number, fold in enumerate(folded):
        path = shaped_seek(fmus).write_ssp(tmp_path / f"oms{number}.ssp", target="omsimulator", step=h, fold=fold)
        again = simulate(path, n * h, h, record=record)
        assert np.ptp(original["plant.position"]) > 1e-4
        for name in record:
            scale = np.max(np.abs(original[name]))
            np.testing.assert_allclose(again[name], original[name], rtol=0, atol=1e-13 * scale, err_msg=f"{fold} {name}")


def test_ssv_bindings_are_merged_inline_before_folding(fmus, tmp_path):
    ssv = write_ssv(tmp_path / "shaper.ssv", {"u": 0.5, "Ts": 1e-6})
    system = (System("seek").add("shaper", fmus["shaper"], {"f[1]": 2000.0}, ssv=ssv).add("plant", fmus["plant"])
              .connect("shaper.y", "plant.voltage", factor=4.0))
    again = read_ssp(system.write_ssd(tmp_path / "oms.ssd", target="omsimulator", step=1e-6, fold={"shaper.y": ["u"]}))
    assert again.parameter_values("shaper") == {"u": 2.0, "Ts": 1e-6, "f[1]": 2000.0}
    assert again.components["shaper"].ssv_sources == []


@pytest.mark.parametrize("change, kwargs, message", [
    (lambda s: s, {"fold": {}}, r"connection shaper.y -> plant.voltage has factor 11.0, which OMSimulator ignores"),
    (lambda s: s, {"fold": {"shaper.y": "kind"}}, r"fold names shaper.kind, which is not a Real parameter or input"),
    (lambda s: s.components["shaper"].parameters.update(kind="zv") or s, {"fold": {"shaper.y": "u"}},
     r"OMSimulator does not import String parameter bindings, and shaper.kind = 'zv' differs from the FMU's start value 'zvd'"),
    (lambda s: s, {"fold": {"shaper.y": "u"}, "step": None}, r"target 'omsimulator' needs step"),
])
def test_what_omsimulator_cannot_run_is_refused_naming_it(fmus, tmp_path, change, kwargs, message):
    options = {"target": "omsimulator", "step": 1e-6, **kwargs}
    with pytest.raises(ValueError, match=message):
        change(shaped_seek(fmus)).write_ssd(tmp_path / "x.ssd", **options)


def test_an_offset_and_a_string_connection_are_refused_for_omsimulator(fmus, tmp_path):
    offset = (System().add("shaper", fmus["shaper"]).add("plant", fmus["plant"])
              .connect("shaper.y", "plant.voltage", factor=2.0, offset=0.5))
    with pytest.raises(ValueError, match=r"shaper.y -> plant.voltage has offset 0.5, which OMSimulator cannot apply"):
        offset.write_ssd(tmp_path / "x.ssd", target="omsimulator", step=1e-3, fold={"shaper.y": "u"})
    strings = System().add("a", fmus["stair"]).add("b", fmus["stair"]).connect("a.s_out", "b.s_in")
    with pytest.raises(ValueError, match=r"connection a.s_out -> b.s_in joins String connectors"):
        strings.write_ssd(tmp_path / "x.ssd", target="omsimulator", step=1e-3)


def test_the_omsimulator_annotations_survive_a_round_trip(fmus, tmp_path):
    ssd = shaped_seek(fmus).write_ssd(tmp_path / "oms.ssd", target="omsimulator", step=2e-6, fold={"shaper.y": "u"})
    again = read_ssp(ssd).write_ssd(tmp_path / "again.ssd").read_text()
    assert 'stepSize="2e-06"' in again and 'resultFile="shaped_seek_res.csv"' in again
