"""modelDescription.xml for a shapefmu slave (FMI 2.0 co-simulation), written from the slave itself.

pythonfmu's generator is not used: it lists outputs without dependencies, omits InitialUnknowns and
units, and declares state handling off. Here every variable carries its unit and description,
ModelStructure gives each output's real dependencies (``Fmi2Slave.output_dependencies``, computed
from the design the start values produce) and the InitialUnknowns, and the capability flags say what
the FMU does: no external tool, state get/set and serialisation.
"""

import datetime
import re
from xml.etree.ElementTree import Element, SubElement, indent, tostring

from shapefmu import __version__
from shapefmu.fmi.python.slave_base import UNITS


# Characters outside XML 1.0's Char production (section 2.2): no reference can write them either.
_NOT_XML = re.compile("[^\t\n\r\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")
# libxml2's XML_MAX_TEXT_LENGTH: the longest attribute value it reads without XML_PARSE_HUGE, which fmpy
# (through lxml) and most FMI hosts do not set; a longer String start value makes an FMU they cannot open.
XML_MAX_TEXT_LENGTH = 10_000_000
# What ElementTree writes for each character that an attribute value cannot hold as itself.
_ESCAPED = {"&": 5, "<": 4, ">": 4, '"': 6, "\n": 5, "\r": 5, "\t": 5}


def check_xml_string(value, owner, what="value"):
    """Refuse a string XML 1.0 cannot hold (a String start value from a user's file), naming ``owner``."""
    bad = _NOT_XML.search(value)
    if bad:
        raise ValueError(f"{owner}: its {what} holds the character U+{ord(bad.group()):04X} at position {bad.start()}, "
                         f"which XML 1.0 (modelDescription.xml) cannot hold")
    written = len(value.encode("utf-8", "surrogatepass")) + sum((n - 1) * value.count(c) for c, n in _ESCAPED.items())
    if written >= XML_MAX_TEXT_LENGTH:
        raise ValueError(f"{owner}: its {what} is {written:,} bytes in modelDescription.xml, more than the "
                         f"{XML_MAX_TEXT_LENGTH:,} that fmpy and other hosts' XML parsers (libxml2) read")


def _check_xml_text(root):
    owners = {child: variable.get("name") for variable in root.iter("ScalarVariable") for child in variable}
    for node in root.iter():
        for name, value in node.attrib.items():
            check_xml_string(value, owners.get(node, node.get("name", node.tag)), f"{name} value")


def _number(value):
    return repr(float(value)) if isinstance(value, float) else str(value)


# The log categories of a pythonfmu FMU: (name, description).
LOG_CATEGORIES = (
    ("logStatusWarning", "Warnings"),
    ("logStatusError", "Errors: bad parameters, non-finite inputs, calls out of order"),
    ("logStatusFatal", "Failures of the embedded Python runtime"),
    ("logAll", "Everything else (debug logging)"),
)


def model_description(slave, guid, dependencies, experiment, pythonfmu_version, *, native_sources=None,
                      log_categories=LOG_CATEGORIES):
    """The XML text for ``slave`` (an initialised instance) with the given GUID.

    ``dependencies`` maps each output to the inputs it feeds through from; ``experiment`` is
    (start, stop, step) for the DefaultExperiment. ``native_sources`` (the C files) describes a
    native FMU made from the slave's variables (``shapefmu.fmi.native.sampled``): it uses the
    host's memory callbacks and lists its sources; ``log_categories`` its log categories.
    """
    root = Element(
        "fmiModelDescription",
        {
            "fmiVersion": "2.0",
            "modelName": slave.model_name,
            "guid": guid,
            "description": slave.description,
            "generationTool": f"shapefmu {__version__} "
            + ("native C generator" if native_sources is not None
               else f"(pythonfmu {pythonfmu_version} export library)"),
            "generationDateAndTime": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "variableNamingConvention": "structured",
            "numberOfEventIndicators": "0",
        },
    )
    cosimulation = SubElement(
        root,
        "CoSimulation",
        {
            "modelIdentifier": slave.model_name,
            "needsExecutionTool": "false",
            "canHandleVariableCommunicationStepSize": "true",
            "canInterpolateInputs": "false",
            "maxOutputDerivativeOrder": "0",
            "canRunAsynchronuously": "false",
            "canBeInstantiatedOnlyOncePerProcess": "false",
            "canNotUseMemoryManagementFunctions": "true" if native_sources is None else "false",
            "canGetAndSetFMUstate": "true",
            "canSerializeFMUstate": "true",
            "providesDirectionalDerivative": "false",
        },
    )
    if native_sources:
        files = SubElement(cosimulation, "SourceFiles")
        for name in native_sources:
            SubElement(files, "File", {"name": name})
    used = sorted({v.unit for v in slave.variables if v.type == "Real"})
    units = SubElement(root, "UnitDefinitions")
    for name in used:
        unit = SubElement(units, "Unit", {"name": name})
        if UNITS[name]:
            SubElement(unit, "BaseUnit", {k: str(e) for k, e in UNITS[name].items()})
    categories = SubElement(root, "LogCategories")
    for name, text in log_categories:
        SubElement(categories, "Category", {"name": name, "description": text})
    start, stop, step = experiment
    SubElement(root, "DefaultExperiment", {"startTime": _number(start), "stopTime": _number(stop), "stepSize": _number(step)})
    variables = SubElement(root, "ModelVariables")
    for var in slave.variables:
        attributes = {
            "name": var.name,
            "valueReference": str(var.vr),
            "description": var.description,
            "causality": var.causality,
            "variability": var.variability,
        }
        if var.causality == "parameter":
            attributes["initial"] = "exact"
        elif var.causality == "output":
            attributes["initial"] = "calculated"
        node = SubElement(variables, "ScalarVariable", attributes)
        typed = {}
        if var.causality != "output":
            start_value = slave.values[var.name]
            typed["start"] = ("true" if start_value else "false") if var.type == "Boolean" else _number(start_value)
        if var.type == "Real":
            typed["unit"] = var.unit
        if var.type in ("Real", "Integer"):
            if var.minimum is not None:
                typed["min"] = _number(var.minimum)
            if var.maximum is not None:
                typed["max"] = _number(var.maximum)
        SubElement(node, var.type, typed)
    index = {var.name: var.vr + 1 for var in slave.variables}  # ModelStructure indices are 1-based
    parameters = [index[v.name] for v in slave.variables if v.causality == "parameter"]
    structure = SubElement(root, "ModelStructure")
    outputs = [v for v in slave.variables if v.causality == "output"]
    if outputs:
        node = SubElement(structure, "Outputs")
        for var in outputs:
            inputs = sorted(index[name] for name in dependencies[var.name])
            attributes = {"index": str(index[var.name]), "dependencies": " ".join(map(str, inputs))}
            if inputs:
                # The feed-through factor (e.g. the first impulse's amplitude) is fixed at initialisation.
                attributes["dependenciesKind"] = " ".join("fixed" for _ in inputs)
            SubElement(node, "Unknown", attributes)
        node = SubElement(structure, "InitialUnknowns")
        for var in outputs:
            # At initialisation the design itself depends on every parameter.
            inputs = sorted(parameters + [index[name] for name in dependencies[var.name]])
            SubElement(node, "Unknown", {"index": str(index[var.name]), "dependencies": " ".join(map(str, inputs))})
    _check_xml_text(root)
    # ElementTree writes tabs and line ends in attribute values as character references, so a
    # String start value (a table's JSON text) reads back exactly as the FMU holds it; a literal
    # line end would read back as a space (attribute-value normalisation, XML 1.0 section 3.3.3).
    indent(root, space="  ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + tostring(root, encoding="unicode") + "\n"
