"""What an FMU declares in its modelDescription.xml, as the tests read it.

    declared(fmu, units=True) -> sorted (name, causality, variability, type, (unit,) start) per variable
    model_xml(fmu) -> the root element of its modelDescription.xml
    assert_documented(root) -> {variable name: its 1-based index}, after checking that the
        Co-Simulation FMU needs no tool and saves and serialises its state, and that every variable
        has a description and every Real a unit the UnitDefinitions define
"""

import xml.etree.ElementTree as ET
import zipfile

from fmpy import read_model_description


def declared(fmu, units: bool = True) -> list[tuple]:
    return sorted((v.name, v.causality, v.variability, v.type, *((v.unit,) if units else ()), v.start)
                  for v in read_model_description(str(fmu)).modelVariables)


def model_xml(fmu) -> ET.Element:
    with zipfile.ZipFile(fmu) as archive:
        return ET.fromstring(archive.read("modelDescription.xml"))


def assert_documented(root: ET.Element) -> dict:
    cs = root.find("CoSimulation")
    assert (cs.get("needsExecutionTool"), cs.get("canGetAndSetFMUstate"), cs.get("canSerializeFMUstate")) == ("false", "true", "true")
    variables = root.find("ModelVariables").findall("ScalarVariable")
    assert all(v.get("description") for v in variables)
    assert all(r.get("unit") for v in variables for r in v.iter("Real"))
    assert {r.get("unit") for r in root.iter("Real")} <= {u.get("name") for u in root.find("UnitDefinitions")}
    return {v.get("name"): str(i + 1) for i, v in enumerate(variables)}
