"""Hostile plant model files: nothing a model file holds reaches the C compiler unchecked, every wrong
value is one line naming it, and `plant build` writes the FMU it was asked for and nothing else."""

import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu
from hostile_support import guarded

from shapefmu.fmi.native import build_plant_fmu, fmu_file_name
from shapefmu.plants import Plant

HOSTILE = Path(__file__).parent / "hostile"
MODELS = Path(__file__).resolve().parents[1] / "models"


def injection(tmp_path):
    """The attack of tests/hostile/injection.toml, its proof file (created only if the attack runs)."""
    proof = tmp_path / "proof"
    model = tmp_path / "injection.toml"
    model.write_text((HOSTILE / "injection.toml").read_text().replace("PROOF", str(proof)))
    return model, proof


def test_an_injected_plant_name_is_refused_before_any_code_is_generated(tmp_path):
    model, proof = injection(tmp_path)
    out = tmp_path / "out" / "Plant.fmu"
    code, _, err = guarded(["plant", "build", str(model), "-o", str(out)])
    assert code == 2
    assert err.count("\n") == 1 and "name must be an identifier" in err and "injection.toml" in err
    assert not out.parent.exists() and not proof.exists()


def test_a_plant_object_named_like_the_attack_compiles_without_it(tmp_path):
    # Through the Python API a plant's name is free text (python-control calls systems "sys[3]"):
    # the generated C must see only the identifier made of it, so the FMU loads and runs harmlessly.
    _, proof = injection(tmp_path)
    name = (HOSTILE / "injection.toml").read_text().split('name = "', 1)[1].split('"\n', 1)[0]
    name = name.replace('\\"', '"').replace("PROOF", str(proof))
    plant = Plant([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], [[1.0, 0.0]], [[0.0]], inputs=["u"], outputs=["y"],
                  name=name)
    fmu = build_plant_fmu(plant, tmp_path / "Plant.fmu")
    with zipfile.ZipFile(fmu) as archive:
        model_c = archive.read("sources/model.c").decode()
    assert "system(" not in model_c and "*/ extern" not in model_c
    assert read_model_description(str(fmu)).modelName == name  # kept, escaped, in the XML only
    assert validate_fmu(str(fmu)) == []
    result = simulate_fmu(str(fmu), stop_time=1.0, output_interval=0.5, start_values={"u": 2.0})
    np.testing.assert_allclose(result["y"][-1], 1.0, rtol=1e-9)  # y = u t^2 / 2 at t = 1 s
    assert not proof.exists()


def test_fmu_file_names_keep_no_separator_of_a_model_name():
    assert fmu_file_name("../../etc/evil_plant") == "EtcevilPlant.fmu"
    assert fmu_file_name("disk_drive") == "DiskDrive.fmu"
    with pytest.raises(ValueError, match="no letter or digit"):
        fmu_file_name("../..")


def mutated(tmp_path, old, new):
    """models/disk_drive.toml with one line changed: a careless or hostile edit."""
    text = (MODELS / "disk_drive.toml").read_text()
    assert old in text
    path = tmp_path / "edited.toml"
    path.write_text(text.replace(old, new, 1))
    return path


DESCRIPTION = 'description = "voice-coil disk drive, rigid body + 2.0 kHz and 3.0 kHz modes"'
BAD_FIELDS = [
    ('name = "disk_drive"', "name = 5", "name must be an identifier"),
    ('name = "disk_drive"', 'name = "../../evil"', "name must be an identifier"),
    ('kind = "rigid_flexible"', 'kind = ["rigid_flexible"]', "kind must be one of"),
    (DESCRIPTION, "description = { a = 1 }", "description must be a string"),
    (DESCRIPTION, 'description = "bell \\u0007"', "control character(s) U+0007"),
    ("b2 = { value = 2.7e3,", "b2 = { value = 1" + "0" * 400 + ",", "parameters.b2.value must be a finite number"),
    ("b2 = { value = 2.7e3,", 'b2 = { value = "big",', "parameters.b2.value must be a finite number"),
    ('zeta = { value = [0.01, 0.01], unit = "1"', "zeta = { value = [0.01, 0.01], unit = 1",
     "parameters.zeta.unit is missing"),
    ('voltage = { unit = "V", max = 11.0', 'voltage = { unit = "V", max = 1' + "0" * 400,
     "inputs.voltage.max must be a finite number"),
    ('position = { unit = "rad"', '"pos */ x" = { unit = "rad"', "must be an identifier"),
    ('position = { unit = "rad"', 'position = { unit = "rad\\u0000"', "outputs.position.unit holds the control"),
    ('description = "rigid-body input gain"', "description = 7", "parameters.b2.description must be a string"),
]


@pytest.mark.parametrize("old, new, message", BAD_FIELDS, ids=[new[:24] for _, new, _ in BAD_FIELDS])
def test_a_model_file_value_of_the_wrong_type_is_one_line_naming_it(tmp_path, old, new, message):
    model = mutated(tmp_path, old, new)
    for command in (["plant", "show", str(model)], ["plant", "build", str(model), "-o", str(tmp_path / "P.fmu")]):
        code, _, err = guarded(command)
        assert code == 2, err
        assert err.count("\n") == 1 and message in err and "edited.toml" in err
    assert not (tmp_path / "P.fmu").exists()


def test_a_file_that_is_not_text_is_named_as_not_a_plant_model(tmp_path):
    model = tmp_path / "binary.toml"
    model.write_bytes(b"\x00\xff\xfe garbage")
    code, _, err = guarded(["plant", "show", str(model)])
    assert code == 2 and err.count("\n") == 1 and "binary.toml: not a plant model (not UTF-8" in err


def test_a_plant_of_more_states_than_the_limit_is_refused_before_generating(tmp_path):
    # A transfer function of order 1001: generating and compiling it would take hours.
    den = ", ".join(["1.0"] * 1002)
    model = tmp_path / "order1001.toml"
    model.write_text(f'name = "tall"\nkind = "transfer_function"\n[parameters]\nnum = {{ value = [1.0], unit = "1" }}\n'
                     f'den = {{ value = [{den}], unit = "1" }}\n[inputs]\nu = {{ unit = "V" }}\n'
                     f'[outputs]\ny = {{ unit = "m" }}\n')
    code, _, err = guarded(["plant", "build", str(model), "-o", str(tmp_path / "T.fmu")])
    assert code == 2 and "has 1,001 states, more than the limit of 200" in err and "MAX_PLANT_STATES" in err


def test_plant_build_into_a_folder_is_refused_and_writes_nothing(tmp_path):
    folder = tmp_path / "DiskDrive.fmu"  # a folder that even ends in .fmu
    folder.mkdir()
    code, _, err = guarded(["plant", "build", str(MODELS / "disk_drive.toml"), "-o", str(folder)])
    assert code == 2 and err.count("\n") == 1 and "is a folder; give a file name" in err
    with pytest.raises(ValueError, match="is a folder"):
        build_plant_fmu(MODELS / "disk_drive.toml", folder)
    assert list(folder.iterdir()) == [] and sorted(p.name for p in tmp_path.iterdir()) == ["DiskDrive.fmu"]
