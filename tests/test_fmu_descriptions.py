"""What a Modelica or Simulink user reads of an FMU (issue 35): every variable of every FMU kind and
of every shipped plant has a description, every Real a unit whose SI base unit the model description
declares, the inputs' limits are min and max, every FMU a DefaultExperiment, a generation date, an
icon drawn from what it is and a page naming its papers; ``fmpy info`` shows the units and
descriptions of the inputs and outputs. References: the SI's own definition of the volt
(kg m^2 s^-3 A^-1, BIPM SI brochure, table 4) and Table I of paper 002 (|u| <= 11 V)."""

import math
import re
import zipfile
from xml.etree import ElementTree as ET

import pytest

from shapefmu.fmi import build_fmu
from shapefmu.fmi.kinds import KINDS
from shapefmu.fmi.native import build_plant_fmu, model_from_file
from shapefmu.fmi.native.twins import build_native
from shapefmu.plants.shipped import shipped

PLANTS = [path.stem for path in shipped((".toml", ".py"))]


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """{label: FMU path}: every kind as a pythonfmu FMU and as its FMI 3.0 native twin, every shipped plant."""
    folder = tmp_path_factory.mktemp("described")
    fmus = {f"pythonfmu {name}": build_fmu(name, folder / f"{name}.fmu") for name in KINDS}
    fmus |= {f"native3 {name}": build_native(name, folder / f"{name}3.fmu", fmi_version="3.0") for name in KINDS}
    for name in PLANTS:
        model = model_from_file(name)
        fmus[f"plant {name}"] = build_plant_fmu(model, folder / f"{name}.fmu")
    return fmus


def _description(fmu):
    return ET.fromstring(zipfile.ZipFile(fmu).read("modelDescription.xml"))


def _variables(root):
    """(name, type, causality, unit, description, min, max) of every variable but time."""
    fmi2 = root.get("fmiVersion") == "2.0"
    for var in root.find("ModelVariables"):
        typed = var[0] if fmi2 else var
        if var.get("name") != "time":
            yield (var.get("name"), typed.tag, var.get("causality"), typed.get("unit"), var.get("description"),
                   typed.get("min"), typed.get("max"))


def test_every_variable_has_a_description_and_every_real_a_unit_with_its_base_unit(built):
    missing = []
    for label, fmu in built.items():
        root = _description(fmu)
        bases = {unit.get("name") for unit in root.iter("Unit") if unit.find("BaseUnit") is not None}
        variables = list(_variables(root))
        # A transfer function's realisation (the motor of paper 001) has states with no physical unit.
        unitless = {name for name, *_, description, _, _ in variables if "no physical unit" in (description or "")}
        unitless |= {f"der({name})" for name in unitless}
        for name, tag, _, unit, description, _, _ in variables:
            if not description:
                missing.append(f"{label}: {name} has no description")
            if tag in ("Real", "Float64") and unit not in bases and name not in unitless:
                missing.append(f"{label}: {name} has unit {unit!r} without an SI BaseUnit")
    assert missing == []


def test_the_disk_drive_declares_its_voltage_limit_and_the_volt_in_si_base_units(built):
    root = _description(built["plant disk_drive"])
    voltage = next(v for v in _variables(root) if v[0] == "voltage")
    assert (voltage[3], voltage[5], voltage[6]) == ("V", "-11.0", "11.0")  # Table I of paper 002
    volt = next(u for u in root.iter("Unit") if u.get("name") == "V").find("BaseUnit").attrib
    assert volt == {"kg": "1", "m": "2", "s": "-3", "A": "-1"}


def test_every_fmu_has_a_default_experiment_and_a_generation_date(built):
    for label, fmu in built.items():
        root = _description(fmu)
        experiment = root.find("DefaultExperiment")
        assert experiment is not None and float(experiment.get("stopTime")) > float(experiment.get("stepSize")) > 0, label
        assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", root.get("generationDateAndTime", "")), label


def test_the_disk_drive_runs_ten_periods_of_its_slowest_mode_in_steps_under_a_twentieth_of_the_fastest(built):
    experiment = _description(built["plant disk_drive"]).find("DefaultExperiment")
    stop, step = float(experiment.get("stopTime")), float(experiment.get("stepSize"))
    assert math.isclose(stop, 10 / 2000.0) and step <= 1 / 3000.0 / 20  # modes at 2.0 and 3.0 kHz


def test_fmpy_info_shows_the_unit_and_the_description_of_every_input_and_output(built, capsys):
    from fmpy import dump

    for label, fmu in built.items():
        dump(str(fmu))
        shown = capsys.readouterr().out
        for name, tag, causality, unit, description, _, _ in _variables(_description(fmu)):
            if causality in ("input", "output"):
                line = next((row for row in shown.splitlines() if row.split()[:1] == [name]), "")
                assert description in line and (unit or "") in line, f"{label}: {name}: {line!r}"


def _icon(fmu):
    names = zipfile.ZipFile(fmu).namelist()
    return zipfile.ZipFile(fmu).read("model.png" if "model.png" in names else "terminalsAndIcons/icon.png")


def test_each_kind_and_plant_has_an_icon_of_its_own(built):
    icons = {label: _icon(fmu) for label, fmu in built.items() if not label.startswith("native3")}
    assert len(set(icons.values())) == len(icons)
    for name in KINDS:  # the twin draws what its pythonfmu FMU draws: the same design
        assert _icon(built[f"native3 {name}"]) == icons[f"pythonfmu {name}"]


def test_an_undamped_mode_on_the_icon_grid_draws_its_peak_there(tmp_path):
    """The single undamped mode of paper 000's example (1 rad/s, zeta = 0): the icon's grid, a quarter
    to four times the mode, has the mode at its middle point, where j omega I - A is singular; the
    picture's highest point is that mode."""
    from shapefmu.fmi.native.linear import model_part
    from shapefmu.plants import rigid_flexible

    omega = 1.0
    plant = rigid_flexible(1.0, [(omega, 0.0, omega**2)], name="single_mode")
    (kind, points), = model_part(plant).picture()
    peak = max(points, key=lambda point: point[1])
    assert kind == "line" and peak[0] == pytest.approx(math.log10(omega), abs=1e-12)
    assert build_plant_fmu(plant, tmp_path / "SingleMode.fmu").is_file()


def test_the_page_names_the_papers_and_the_meaning_of_the_signals(built):
    page = zipfile.ZipFile(built["native3 STOSController"]).read("documentation/index.html").decode()
    assert "La-orpacharapan, L. Y. Pao, Nonlinear control for maneuvering multiple flexible mode systems" in page
    assert "<b>target</b> (input, m): target position" in page
    page = zipfile.ZipFile(built["plant disk_drive"]).read("documentation/index.html").decode()
    assert "paper 002" in page and "<b>voltage</b> (input, V): voice-coil voltage" in page
