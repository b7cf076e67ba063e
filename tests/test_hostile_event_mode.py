"""An FMI 3.0 FMU without Event Mode refuses eventModeUsed = fmi3True at instantiation (issue 34, item 14).

FMI 3.0 (fmi3InstantiateCoSimulation's eventModeUsed) allows fmi3True only for an FMU whose
hasEventMode is true and asks any other FMU to raise an error. Every unclocked FMI 3.0 FMU shapefmu builds declares hasEventMode="false" but instantiated anyway,
then failed at the host's first fmi3UpdateDiscreteStates ("not allowed in Step Complete"), far from
the cause. Now the instantiation returns NULL with a message naming eventModeUsed and hasEventMode;
with eventModeUsed = fmi3False it instantiates, and an FMU built with --clock (hasEventMode="true")
takes eventModeUsed = fmi3True.
"""

from __future__ import annotations

from pathlib import Path

import pytest

MODELS = Path(__file__).resolve().parent.parent / "models"


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    from shapefmu.fmi.native import build_plant_fmu
    from shapefmu.fmi.native.twins import build_native

    folder = tmp_path_factory.mktemp("event_mode")
    shaper = {"kind": "zvd", "n_modes": 1, "f[1]": 13.0, "zeta[1]": 0.05, "Ts": 1e-3}
    return {
        "Shaper": build_native("Shaper", folder / "Shaper.fmu", fmi_version="3.0", **shaper),
        "EKFTuner": build_native("EKFTuner", folder / "EKFTuner.fmu", fmi_version="3.0"),
        "plant": build_plant_fmu(MODELS / "disk_drive.toml", folder / "plant.fmu", fmi_version="3.0"),
        "Shaper --clock": build_native("Shaper", folder / "clocked.fmu", fmi_version="3.0", clock=True, **shaper),
    }


def _slave(path):
    from fmpy import extract, read_model_description
    from fmpy.fmi3 import FMU3Slave

    md = read_model_description(str(path))
    slave = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(path)), modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="host")
    return md, slave


@pytest.mark.parametrize("name", ["Shaper", "EKFTuner", "plant"])
def test_an_fmu_without_event_mode_refuses_event_mode_used_with_a_message(fmus, name, capfd):
    md, slave = _slave(fmus[name])
    assert md.coSimulation.hasEventMode is not True  # what the FMU declares
    with pytest.raises(Exception, match="Failed to instantiate"):
        slave.instantiate(eventModeUsed=True)
    out = capfd.readouterr().out
    assert "eventModeUsed = fmi3True" in out and 'hasEventMode="false"' in out, out
    slave.instantiate(eventModeUsed=False)  # the same FMU, asked rightly
    slave.freeInstance()


def test_a_clocked_fmu_declares_event_mode_and_takes_event_mode_used(fmus):
    md, slave = _slave(fmus["Shaper --clock"])
    assert md.coSimulation.hasEventMode is True
    slave.instantiate(eventModeUsed=True)
    slave.freeInstance()
