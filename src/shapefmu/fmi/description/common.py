"""What the FMI 2.0 and FMI 3.0 writers write alike: numbers, a variable's quantity attributes (unit,
nominal, derivative, min, max), the unit definitions, the log categories and the default experiment."""

from __future__ import annotations

from xml.etree.ElementTree import Element, SubElement

from shapefmu.fmi.description.model import ModelDescription
from shapefmu.fmi.description.units import base_units


def number(value) -> str:
    """A start, min, max or time as the standards write it: a Real's exact repr, an Integer's digits."""
    return repr(float(value)) if isinstance(value, float) else str(int(value))


def quantity(variable, reference_of: dict) -> dict:
    """The unit, nominal, derivative (``reference_of`` the state's index or value reference), min and
    max attributes of ``variable``, those it has."""
    attributes = {}
    if variable.type == "Real" and variable.unit:
        attributes["unit"] = variable.unit
    if variable.nominal is not None:
        attributes["nominal"] = repr(float(variable.nominal))
    if variable.derivative_of is not None:
        attributes["derivative"] = str(reference_of[variable.derivative_of])
    if variable.type in ("Real", "Integer"):
        for key, value in (("min", variable.minimum), ("max", variable.maximum)):
            if value is not None:
                attributes[key] = number(value)
    return attributes


def header(root: Element, md: ModelDescription) -> None:
    """UnitDefinitions (each unit with its SI BaseUnit where it is readable), LogCategories and
    DefaultExperiment, in the order both standards place them after the interfaces."""
    if md.units():
        definitions = SubElement(root, "UnitDefinitions")
        for name in md.units():
            unit = SubElement(definitions, "Unit", {"name": name})
            base = base_units(name)
            if base is not None:  # {} is "1": dimensionless, every exponent 0
                SubElement(unit, "BaseUnit", base)
    categories = SubElement(root, "LogCategories")
    for name, text in md.log_categories:
        SubElement(categories, "Category", {"name": name, **({"description": text} if text else {})})
    if md.experiment is not None:
        start, stop, step = md.experiment
        SubElement(root, "DefaultExperiment", {"startTime": number(start), "stopTime": number(stop),
                                               "stepSize": number(step)})
