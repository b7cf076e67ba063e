"""SSP 1.0 parameter values (``ssv:ParameterSet``, ``.ssv`` files) and the namespaces and XML helpers
the system's reader and writer share."""

from __future__ import annotations

from pathlib import Path
from xml.etree import ElementTree as ET

from shapefmu.files import write_bytes
from shapefmu.fmi.ssp.connectors import Connector, resolve
from shapefmu.fmi.variable_types import KINDS

SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
NAMESPACES = {"ssd": SSD, "ssc": SSC, "ssv": SSV}
for _prefix, _uri in NAMESPACES.items():
    ET.register_namespace(_prefix, _uri)

TYPES = KINDS
# Name of every parameter set we write. ecos applies parameter sets by name at initialisation
# (``EcosSimulation.init(parameter_set=PARAMETER_SET)``); libcosim applies every binding.
PARAMETER_SET = "parameters"


def parameter_set(name: str, values: dict, connectors: dict[str, Connector] | None = None) -> ET.Element:
    parameter_set = ET.Element(f"{{{SSV}}}ParameterSet", {"version": "1.0", "name": name})
    parameters = ET.SubElement(parameter_set, f"{{{SSV}}}Parameters")
    for key, value in values.items():
        try:  # an array's element is typed by the array's connector
            connector = resolve(connectors, "", key)[0] if connectors else None
        except ValueError:
            connector = None
        kind = connector.type if connector else _type_of(value)
        text = str(value).lower() if kind == "Boolean" else (repr(float(value)) if kind == "Real" else str(value))
        if kind == "Enumeration":  # an ssv:Enumeration value is the item's name
            text = {number: item for item, number in connector.items.items()}.get(value, text)
        node = ET.SubElement(parameters, f"{{{SSV}}}Parameter", {"name": key})
        ET.SubElement(node, f"{{{SSV}}}{kind}", {"value": text})
    return parameter_set


def _type_of(value) -> str:
    if isinstance(value, bool):
        return "Boolean"
    if isinstance(value, int):
        return "Integer"
    if isinstance(value, str):
        return "String"
    return "Real"


def write_ssv(path, parameters: dict, name: str = PARAMETER_SET, named: bool = True) -> Path:
    """Write ``{variable: value}`` as an SSP 1.0 parameter-value file (.ssv); ``named``: the user named
    ``path`` (else it is written beside a file they named, and an existing one is refused: ``shapefmu.files``)."""
    root = parameter_set(name, parameters)
    ET.indent(root)
    return write_bytes(path, ET.tostring(root, encoding="UTF-8", xml_declaration=True), "parameter set", named)


def read_ssv(path) -> dict:
    """``{variable: value}`` from an .ssv file (Real, Integer, Boolean and String values)."""
    path = Path(path)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as error:
        raise ValueError(f"{path}: cannot read parameter values: {error}") from None
    return parameter_values(root, str(path))


def local(tag: str) -> str:
    return tag.rpartition("}")[2]


def children(node: ET.Element, name: str) -> list[ET.Element]:
    return [child for child in node if local(child.tag) == name]


def child(node: ET.Element, name: str) -> ET.Element | None:
    found = children(node, name)
    return found[0] if found else None


def parameter_values(parameter_set: ET.Element, where: str) -> dict:
    values = {}
    for parameters in children(parameter_set, "Parameters"):
        for parameter in children(parameters, "Parameter"):
            name = parameter.get("name")
            typed = next((child for child in parameter if local(child.tag) in TYPES), None)
            if name is None or typed is None or typed.get("value") is None:
                raise ValueError(f"{where}: Parameter {name!r} needs a name and a Real/Integer/Boolean/String value")
            text = typed.get("value")
            kind = local(typed.tag)
            try:
                values[name] = {"Real": float, "Integer": int, "String": str, "Enumeration": str,
                                "Boolean": lambda s: {"true": True, "false": False, "1": True, "0": False}[s]}[kind](text)
            except (KeyError, ValueError):
                raise ValueError(f"{where}: Parameter {name!r} has an invalid {kind} value {text!r}") from None
    return values
