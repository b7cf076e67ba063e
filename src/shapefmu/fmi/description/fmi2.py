"""The FMI 2.0 writer: ``modelDescription.xml`` of a ``ModelDescription`` (FMI 2.0.4, section 2.2).

Every variable is listed as a ScalarVariable with its value reference (its position) but time, the
independent variable, which FMI 2.0 lists nowhere (FMI Library, which libcosim reads descriptions
with, logs an error for a listed one without a start value, the only form the standard allows).
ModelStructure indices are 1-based positions in ModelVariables.
"""

from __future__ import annotations

from xml.etree.ElementTree import Element, SubElement, indent, tostring

from shapefmu.fmi.description.common import header, number, quantity
from shapefmu.fmi.description.model import ModelDescription
from shapefmu.fmi.description.xml_text import check_attributes


def _flag(value: bool) -> str:
    return "true" if value else "false"


def _interfaces(root: Element, md: ModelDescription) -> None:
    common = {"modelIdentifier": md.identifier, "needsExecutionTool": "false"}
    flags = {"canBeInstantiatedOnlyOncePerProcess": "false",
             "canNotUseMemoryManagementFunctions": _flag(not md.host_memory), "canGetAndSetFMUstate": "true",
             "canSerializeFMUstate": "true", "providesDirectionalDerivative": _flag(md.directional_derivatives)}
    elements = [SubElement(root, "ModelExchange", {**common, **flags})] if md.model_exchange else []
    elements.append(SubElement(root, "CoSimulation", {
        **common, "canHandleVariableCommunicationStepSize": "true", "canInterpolateInputs": "false",
        "maxOutputDerivativeOrder": "0", "canRunAsynchronuously": "false", **flags}))
    for element in elements if md.source_files else ():
        files = SubElement(element, "SourceFiles")
        for name in md.source_files:
            SubElement(files, "File", {"name": name})


def _typed(variable, index_of) -> dict:
    typed = {}
    if variable.start is not None:
        start = variable.start
        typed["start"] = _flag(start) if variable.type == "Boolean" else start if variable.type == "String" else number(start)
    return typed | quantity(variable, index_of)


def write(md: ModelDescription) -> str:
    """The XML text of ``md`` as an FMI 2.0 model description."""
    root = Element("fmiModelDescription", {
        "fmiVersion": "2.0", "modelName": md.model_name, "guid": md.guid, "description": md.description,
        "generationTool": md.generation_tool, "generationDateAndTime": md.generation_date or "",
        "variableNamingConvention": "structured", "numberOfEventIndicators": "0"})
    for optional in ("description", "generationDateAndTime"):
        if not root.get(optional):
            del root.attrib[optional]
    _interfaces(root, md)
    header(root, md)
    listed = [(vr, v) for vr, v in enumerate(md.variables) if v.causality != "independent"]
    index_of = {v.name: position for position, (_, v) in enumerate(listed, 1)}
    variables = SubElement(root, "ModelVariables")
    owner = {}
    for vr, v in listed:
        attributes = {"name": v.name, "valueReference": str(vr), "description": v.description,
                      "causality": v.causality, "variability": v.variability}
        if not v.description:
            del attributes["description"]
        if v.initial:
            attributes["initial"] = v.initial
        node = SubElement(variables, "ScalarVariable", attributes)
        owner[SubElement(node, v.type, _typed(v, index_of))] = v.name
    _structure(root, md, [v for _, v in listed], index_of)
    check_attributes(root, lambda node: owner.get(node, node.get("name", node.tag)))
    # ElementTree writes tabs and line ends in attribute values as character references, so a
    # String start value (a table's JSON text) reads back exactly as the FMU holds it; a literal
    # line end would read back as a space (attribute-value normalisation, XML 1.0 section 3.3.3).
    indent(root, space="  ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + tostring(root, encoding="unicode") + "\n"


def _structure(root: Element, md: ModelDescription, listed, index_of) -> None:
    outputs = [v for v in listed if v.causality == "output"]
    derivatives = [v for v in listed if v.derivative_of is not None]
    parameters = [index_of[v.name] for v in listed if v.causality == "parameter"]
    structure = SubElement(root, "ModelStructure")

    def depends(v):
        return sorted(index_of[name] for name in md.dependencies.get(v.name, ()))

    for tag, unknowns in (("Outputs", outputs), ("Derivatives", derivatives)):
        if unknowns:
            node = SubElement(structure, tag)
            for v in unknowns:
                attributes = {"index": str(index_of[v.name]), "dependencies": " ".join(map(str, depends(v)))}
                if md.designed and depends(v):
                    # The feed-through factor (e.g. the first impulse's amplitude) is fixed at initialisation.
                    attributes["dependenciesKind"] = " ".join("fixed" for _ in depends(v))
                SubElement(node, "Unknown", attributes)
    initial = outputs if md.designed else sorted(outputs + derivatives, key=lambda v: index_of[v.name])
    if initial:
        node = SubElement(structure, "InitialUnknowns")
        for v in initial:
            attributes = {"index": str(index_of[v.name])}
            if md.designed:  # the design made at initialisation depends on every parameter
                attributes["dependencies"] = " ".join(map(str, sorted(parameters + depends(v))))
            SubElement(node, "Unknown", attributes)
