"""The FMI 3.0 writer: ``modelDescription.xml`` of a ``ModelDescription`` (FMI 3.0, section 2.4) and
``terminalsAndIcons/terminalsAndIcons.xml`` (section 2.4.9).

The generic FMI 3.0 layer (``c/fmi3_layer.h``) numbers variables from the model part's values in the
contract's order (Real, Integer, Boolean, String): value reference 0 is time, the independent
variable; then one variable per value, except that the elements ``base[1]``, ``base[2]``, ... of a
parameter become the array parameter ``base`` with a ``<Dimension>`` of their count (a Shaper's
impulse times and amplitudes, a ShapeFilter's taps, the mode frequencies ``f`` and dampings
``zeta``). ``variables3`` makes the same list, so the XML and the C agree by construction; the sizes
are fixed at build time (a closed-form Shaper holds as many impulses as its build kind and modes
need, whatever it is re-designed to), so no array needs a structural parameter.

Types: Real is Float64, Integer Int32, Boolean and String keep their names.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from xml.etree.ElementTree import Element, SubElement, indent, tostring

from shapefmu.fmi.description.common import header, quantity
from shapefmu.fmi.description.model import ModelDescription
from shapefmu.fmi.description.xml_text import check_attributes, check_xml_string
from shapefmu.fmi.kinds.interface import Variable

TYPE3 = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean", "String": "String"}
_ELEMENT = re.compile(r"(.+)\[([0-9]+)\]")


@dataclass
class Variable3:
    """An FMI 3.0 variable: one value, or the elements of an array parameter."""

    name: str
    vr: int
    elements: list[Variable] = field(default_factory=list)

    @property
    def first(self) -> Variable:
        return self.elements[0]

    @property
    def is_array(self) -> bool:
        return _ELEMENT.fullmatch(self.first.name) is not None and self.first.causality == "parameter"


def variables3(variables) -> list[Variable3]:
    """The FMI 3.0 variables of ``variables`` as ``c/fmi3_layer.c`` numbers them (see the module doc)."""
    found: list[Variable3] = []
    arrays: dict[tuple[str, str], Variable3] = {}
    for v in variables:
        if v.causality == "independent":
            continue
        element = _ELEMENT.fullmatch(v.name) if v.causality == "parameter" else None
        key = (element.group(1), v.type) if element else None
        if key in arrays:
            variable = arrays[key]
            if (v.causality, v.variability) != (variable.first.causality, variable.first.variability):
                raise ValueError(f"{v.name}: the elements of array {variable.name} must share causality and "
                                 f"variability, got {v.variability} beside {variable.first.variability}")
            variable.elements.append(v)
        else:
            variable = Variable3(element.group(1) if element else v.name, len(found) + 1, [v])
            found.append(variable)
            if key:
                arrays[key] = variable
    for variable in arrays.values():
        indices = [int(_ELEMENT.fullmatch(e.name).group(2)) for e in variable.elements]
        if indices != list(range(1, len(indices) + 1)):
            raise ValueError(f"array parameter {variable.name} of an FMI 3.0 FMU needs elements [1] .. [n] in "
                             f"order, got indices {indices}")
    names = [v.name for v in found]
    clash = next((n for n in names if names.count(n) > 1), None)
    if clash is not None:
        raise ValueError(f"{clash} is both a scalar variable and an array parameter's name; FMI 3.0 needs one")
    return found


def _value(v: Variable, value) -> str:
    if v.type == "Boolean":
        return "true" if value else "false"
    return repr(float(value)) if v.type == "Real" else str(int(value))


def _variable_element(parent, variable: Variable3, vr_of: dict, clock_vr: int | None) -> Element:
    v = variable.first
    attributes = {"name": variable.name, "valueReference": str(variable.vr), "description": v.description,
                  "causality": v.causality, "variability": v.variability}
    if clock_vr is not None and v.causality in ("input", "output"):  # sampled at the clock's ticks
        attributes.update(variability="discrete", clocks=str(clock_vr))
    if v.initial:
        attributes["initial"] = v.initial
    attributes.update(quantity(v, vr_of))
    if v.start is not None and v.type != "String":
        attributes["start"] = " ".join(_value(e, e.start) for e in variable.elements)
    if not attributes["description"]:
        del attributes["description"]
    node = SubElement(parent, TYPE3[v.type], attributes)
    if variable.is_array:
        SubElement(node, "Dimension", {"start": str(len(variable.elements))})
    if v.start is not None and v.type == "String":
        for e in variable.elements:
            check_xml_string(e.start, variable.name, "start value")
            SubElement(node, "Start", {"value": e.start})
    return node


def write(md: ModelDescription) -> str:
    """The XML text of ``md`` as an FMI 3.0 model description."""
    variables = variables3(md.variables)
    vr_of = {e.name: v.vr for v in variables for e in v.elements} | {v.name: v.vr for v in variables}
    root = Element("fmiModelDescription", {
        "fmiVersion": "3.0", "modelName": md.model_name, "instantiationToken": md.guid, "description": md.description,
        "generationTool": md.generation_tool, "generationDateAndTime": md.generation_date or "",
        "variableNamingConvention": "structured"})
    for optional in ("description", "generationDateAndTime"):
        if not root.get(optional):
            del root.attrib[optional]
    common = {"modelIdentifier": md.identifier, "canGetAndSetFMUState": "true", "canSerializeFMUState": "true",
              "providesDirectionalDerivatives": "true" if md.directional_derivatives else "false"}
    if md.model_exchange:
        SubElement(root, "ModelExchange", common)
    SubElement(root, "CoSimulation", {**common, "canHandleVariableCommunicationStepSize": "true",
                                      "hasEventMode": "true" if md.clock_interval else "false"})
    header(root, md)
    model_variables = SubElement(root, "ModelVariables")
    SubElement(model_variables, "Float64", {"name": "time", "valueReference": "0", "causality": "independent",
                                            "variability": "continuous", "description": "simulation time"})
    clock_vr = len(variables) + 1
    owner = {}
    for variable in variables:
        node = _variable_element(model_variables, variable, vr_of, clock_vr if md.clock_interval else None)
        owner.update({child: variable.name for child in node})
    if md.clock_interval:
        SubElement(model_variables, "Clock", {
            "name": "sample", "valueReference": str(clock_vr), "causality": "input", "variability": "discrete",
            "intervalVariability": "constant", "intervalDecimal": repr(float(md.clock_interval)),
            "description": "the FMU's sample instants t0 + k Ts: tick it at each (Event Mode, fmi3SetClock)"})
    _structure(root, md, variables, vr_of)
    check_attributes(root, lambda node: owner.get(node, node.get("name", node.tag)))
    indent(root, space="  ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + tostring(root, encoding="unicode") + "\n"


def _structure(root: Element, md: ModelDescription, variables, vr_of) -> None:
    structure = SubElement(root, "ModelStructure")
    outputs = [v for v in variables if v.first.causality == "output"]
    derivatives = [v for v in variables if v.first.derivative_of is not None]
    parameters = [v.vr for v in variables if v.first.causality == "parameter"]

    def depends(name):
        return sorted({vr_of[d] for d in md.dependencies.get(name, ())})

    for v in outputs:
        SubElement(structure, "Output", {"valueReference": str(v.vr), "dependencies": " ".join(map(str, depends(v.name)))})
    for v in derivatives:
        SubElement(structure, "ContinuousStateDerivative",
                   {"valueReference": str(v.vr), "dependencies": " ".join(map(str, depends(v.name)))})
    # clocked outputs are no initial unknowns: they are computed at the clock's ticks (FMI 3.0 2.4.8)
    for v in sorted((outputs if not md.clock_interval else []) + derivatives, key=lambda v: v.vr):
        if md.designed:  # the design, made at initialisation, depends on every parameter
            known = sorted(set(parameters) | set(depends(v.name)))
            SubElement(structure, "InitialUnknown", {"valueReference": str(v.vr), "dependencies": " ".join(map(str, known))})
        else:  # a plant's: on every state, input and parameter (no dependencies attribute)
            SubElement(structure, "InitialUnknown", {"valueReference": str(v.vr)})


def terminals_and_icons(command_in: str | None, command_out: str | None) -> str:
    """terminalsAndIcons/terminalsAndIcons.xml (FMI 3.0 section 2.4.9) with the FMU's command
    terminals: ``command_in`` (an input) and ``command_out`` (an output), each one signal member named
    ``command``, matched as a plug, so a tool connects one FMU's command out to the next one's command
    in (a profile into a shaper, a shaper into a plant)."""
    root = Element("fmiTerminalsAndIcons", {"fmiVersion": "3.0"})
    if command_in is not None or command_out is not None:  # a list holds one element at least
        terminals = SubElement(root, "Terminals")
    for name, variable, text in (("command_in", command_in, "the command this FMU takes"),
                                 ("command_out", command_out, "the command this FMU gives")):
        if variable is not None:
            terminal = SubElement(terminals, "Terminal", {"name": name, "matchingRule": "plug", "description": text})
            SubElement(terminal, "TerminalMemberVariable",
                       {"variableName": variable, "memberName": "command", "variableKind": "signal"})
    # a user's text (a model's description, a table) XML 1.0 cannot hold is refused
    check_attributes(root, lambda node: node.get("name", node.tag))
    indent(root, space="  ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + tostring(root, encoding="unicode") + "\n"
