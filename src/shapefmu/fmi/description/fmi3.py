"""modelDescription.xml (FMI 3.0) of a native FMU on the generic FMI 3.0 layer: a plant or a twin.

The layer (``c/fmi3_layer.h``) numbers FMI 3.0 variables from the model part's values ("slots", in
the contract's order: Real, Integer, Boolean, String): value reference 0 is time, the independent
variable; then one variable per slot, except that the elements ``base[1]``, ``base[2]``, ... of a
parameter become the array parameter ``base`` with a ``<Dimension>`` of their count (a Shaper's
impulse times and amplitudes, a ShapeFilter's taps, the mode frequencies ``f`` and dampings
``zeta``). ``variables3`` makes the same list, so the XML and the C agree by construction; the sizes
are fixed at build time (a closed-form Shaper holds as many impulses as its build kind and modes
need, whatever it is re-designed to), so no array needs a structural parameter.

Types: Real is Float64, Integer Int32, Boolean and String keep their names.
"""

from __future__ import annotations

import datetime
import re
from dataclasses import dataclass, field
from xml.etree.ElementTree import Element, SubElement, indent, tostring

from shapefmu import __version__
from shapefmu.fmi.python.model_description import check_xml_string
from shapefmu.fmi.python.slave_base import UNITS

TYPE3 = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean", "String": "String"}
_ELEMENT = re.compile(r"(.+)\[([0-9]+)\]")


@dataclass(frozen=True)
class Slot:
    """One value of the model part, in the contract's order (``c/fmi2_model.h``)."""

    name: str
    type: str                      # Real, Integer, Boolean, String
    causality: str                 # parameter, input, output, local; "time" for a part's time slot
    variability: str
    start: object = None           # None: no start value (outputs, calculated locals)
    unit: str = ""
    description: str = ""
    initial: str | None = None
    nominal: float | None = None
    derivative_of: str | None = None   # a derivative: the state's name
    minimum: float | None = None
    maximum: float | None = None


@dataclass
class Variable3:
    """An FMI 3.0 variable: one slot, or the elements of an array parameter."""

    name: str
    vr: int
    slots: list[Slot] = field(default_factory=list)

    @property
    def first(self) -> Slot:
        return self.slots[0]

    @property
    def is_array(self) -> bool:
        return _ELEMENT.fullmatch(self.first.name) is not None and self.first.causality == "parameter"


def variables3(slots) -> list[Variable3]:
    """The FMI 3.0 variables of ``slots`` as ``c/fmi3_layer.c`` numbers them (see the module doc)."""
    variables: list[Variable3] = []
    arrays: dict[tuple[str, str], Variable3] = {}
    for slot in slots:
        if slot.causality == "time":
            continue
        element = _ELEMENT.fullmatch(slot.name) if slot.causality == "parameter" else None
        key = (element.group(1), slot.type) if element else None
        if key in arrays:
            variable = arrays[key]
            if (slot.causality, slot.variability) != (variable.first.causality, variable.first.variability):
                raise ValueError(f"{slot.name}: the elements of array {variable.name} must share causality and "
                                 f"variability, got {slot.variability} beside {variable.first.variability}")
            variable.slots.append(slot)
        else:
            variable = Variable3(element.group(1) if element else slot.name, len(variables) + 1, [slot])
            variables.append(variable)
            if key:
                arrays[key] = variable
    for variable in arrays.values():
        indices = [int(_ELEMENT.fullmatch(s.name).group(2)) for s in variable.slots]
        if indices != list(range(1, len(indices) + 1)):
            raise ValueError(f"array parameter {variable.name} of an FMI 3.0 FMU needs elements [1] .. [n] in "
                             f"order, got indices {indices}")
    names = [v.name for v in variables]
    clash = next((n for n in names if names.count(n) > 1), None)
    if clash is not None:
        raise ValueError(f"{clash} is both a scalar variable and an array parameter's name; FMI 3.0 needs one")
    return variables


def _number(value) -> str:
    return repr(float(value)) if isinstance(value, float) else str(int(value))


def _value(slot: Slot, value) -> str:
    if slot.type == "Boolean":
        return "true" if value else "false"
    return repr(float(value)) if slot.type == "Real" else str(int(value))


def _variable_element(parent, variable: Variable3, vr_of: dict, clock_vr: int | None) -> None:
    slot = variable.first
    attributes = {"name": variable.name, "valueReference": str(variable.vr), "description": slot.description,
                  "causality": slot.causality, "variability": slot.variability}
    if clock_vr is not None and slot.causality in ("input", "output"):  # sampled at the clock's ticks
        attributes.update(variability="discrete", clocks=str(clock_vr))
    if slot.initial:
        attributes["initial"] = slot.initial
    if slot.type == "Real" and slot.unit:
        attributes["unit"] = slot.unit
    if slot.nominal is not None:
        attributes["nominal"] = repr(float(slot.nominal))
    if slot.derivative_of is not None:
        attributes["derivative"] = str(vr_of[slot.derivative_of])
    if slot.type in ("Real", "Integer"):
        if slot.minimum is not None:
            attributes["min"] = _number(slot.minimum)
        if slot.maximum is not None:
            attributes["max"] = _number(slot.maximum)
    if slot.start is not None and slot.type != "String":
        attributes["start"] = " ".join(_value(s, s.start) for s in variable.slots)
    if not attributes["description"]:
        del attributes["description"]
    node = SubElement(parent, TYPE3[slot.type], attributes)
    if variable.is_array:
        SubElement(node, "Dimension", {"start": str(len(variable.slots))})
    if slot.start is not None and slot.type == "String":
        for s in variable.slots:
            check_xml_string(s.start, variable.name, "start value")
            SubElement(node, "Start", {"value": s.start})


def model_description3(*, model_name: str, identifier: str, token: str, description: str, slots,
                       dependencies: dict, log_categories, model_exchange: bool = False,
                       directional_derivatives: bool = False, experiment=None, generation_tool: str = "",
                       clock_interval: float = 0.0) -> str:
    """The FMI 3.0 modelDescription.xml of a native FMU whose model part has ``slots``.

    ``dependencies`` maps each output (and each state derivative) to the names of the inputs (and
    states) it depends on; ``log_categories`` are (name, description) pairs; ``experiment`` is
    (start, stop, step) or None; ``clock_interval`` > 0 declares the periodic input clock ``sample``
    (value reference: the last variable's + 1, as ``c/fmi3_layer_clock.c`` numbers it) that clocks
    the inputs and outputs, and Event Mode.
    """
    variables = variables3(slots)
    vr_of = {s.name: v.vr for v in variables for s in v.slots} | {v.name: v.vr for v in variables}
    root = Element("fmiModelDescription", {
        "fmiVersion": "3.0", "modelName": model_name, "instantiationToken": token, "description": description,
        "generationTool": f"shapefmu {__version__} {generation_tool or 'native C generator'}",
        "generationDateAndTime": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "variableNamingConvention": "structured"})
    if not description:
        del root.attrib["description"]
    common = {"modelIdentifier": identifier, "canGetAndSetFMUState": "true", "canSerializeFMUState": "true",
              "providesDirectionalDerivatives": "true" if directional_derivatives else "false"}
    if model_exchange:
        SubElement(root, "ModelExchange", common)
    SubElement(root, "CoSimulation", {**common, "canHandleVariableCommunicationStepSize": "true",
                                      "hasEventMode": "true" if clock_interval else "false"})
    units = sorted({s.unit for s in slots if s.type == "Real" and s.unit})
    if units:
        definitions = SubElement(root, "UnitDefinitions")
        for name in units:
            unit = SubElement(definitions, "Unit", {"name": name})
            if UNITS.get(name):
                SubElement(unit, "BaseUnit", {k: str(e) for k, e in UNITS[name].items()})
    categories = SubElement(root, "LogCategories")
    for name, text in log_categories:
        SubElement(categories, "Category", {"name": name, **({"description": text} if text else {})})
    if experiment is not None:
        start, stop, step = experiment
        SubElement(root, "DefaultExperiment", {"startTime": _number(start), "stopTime": _number(stop),
                                               "stepSize": _number(step)})
    model_variables = SubElement(root, "ModelVariables")
    SubElement(model_variables, "Float64", {"name": "time", "valueReference": "0", "causality": "independent",
                                            "variability": "continuous", "description": "simulation time"})
    clock_vr = len(variables) + 1
    for variable in variables:
        _variable_element(model_variables, variable, vr_of, clock_vr if clock_interval else None)
    if clock_interval:
        SubElement(model_variables, "Clock", {
            "name": "sample", "valueReference": str(clock_vr), "causality": "input", "variability": "discrete",
            "intervalVariability": "constant", "intervalDecimal": repr(float(clock_interval)),
            "description": "the FMU's sample instants t0 + k Ts: tick it at each (Event Mode, fmi3SetClock)"})
    structure = SubElement(root, "ModelStructure")
    outputs = [v for v in variables if v.first.causality == "output"]
    derivatives = [v for v in variables if v.first.derivative_of is not None]
    parameters = [v.vr for v in variables if v.first.causality == "parameter"]

    def depends(name):
        return sorted({vr_of[d] for d in dependencies.get(name, ())})

    for v in outputs:
        SubElement(structure, "Output", {"valueReference": str(v.vr), "dependencies": " ".join(map(str, depends(v.name)))})
    for v in derivatives:
        SubElement(structure, "ContinuousStateDerivative",
                   {"valueReference": str(v.vr), "dependencies": " ".join(map(str, depends(v.name)))})
    # clocked outputs are no initial unknowns: they are computed at the clock's ticks (FMI 3.0 2.4.8)
    for v in sorted((outputs if not clock_interval else []) + derivatives, key=lambda v: v.vr):
        if model_exchange:  # a plant's: on every state, input and parameter (no dependencies attribute)
            SubElement(structure, "InitialUnknown", {"valueReference": str(v.vr)})
        else:  # a twin's design, made at initialisation, depends on every parameter
            known = sorted(set(parameters) | set(depends(v.name)))
            SubElement(structure, "InitialUnknown", {"valueReference": str(v.vr), "dependencies": " ".join(map(str, known))})
    indent(root, space="  ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + tostring(root, encoding="unicode") + "\n"


# The command each native twin takes and gives (FMI 3.0 terminals): (command in, command out).
TWIN_TERMINALS = {"Shaper": ("u", "y"), "ShapeFilter": ("u", "y"), "EKFTuner": ("u", "y"),
                  "STOSController": ("target", "u"), "ReferencePlayer": (None, "y"),
                  "ProfileGenerator": (None, "position")}


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
    for node in root.iter():  # a user's text (a model's description, a table) XML 1.0 cannot hold is refused
        for name, value in node.attrib.items():
            check_xml_string(value, node.get("name", node.tag), f"{name} value")
    indent(root, space="  ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + tostring(root, encoding="unicode") + "\n"


def plant_slots(part) -> list[Slot]:
    """The slots of a plant's model part (``c/plant_fmi2.c``): time, states, derivatives, inputs,
    outputs, parameters."""
    slots = [Slot("time", "Real", "time", "continuous")]
    for s in part.states:
        slots.append(Slot(f"state.{s.name}", "Real", "local", "continuous", s.start, s.unit, s.description,
                          "exact", s.nominal))
    for s in part.states:
        slots.append(Slot(f"der(state.{s.name})", "Real", "local", "continuous", None, "", "", "calculated",
                          derivative_of=f"state.{s.name}"))
    slots += [Slot(s.name, "Real", "input", "continuous", s.start, s.unit, s.description) for s in part.inputs]
    slots += [Slot(s.name, "Real", "output", "continuous", None, s.unit, s.description, "calculated")
              for s in part.outputs]
    slots += [Slot(p.name, "Real", "parameter", "tunable" if p.tunable else "fixed", p.value, p.unit, p.description,
                   "exact") for p in part.parameters]
    return slots


def plant_dependencies(part) -> dict:
    """Each output's and derivative's dependencies on states and inputs (names of ``plant_slots``)."""
    known = [f"state.{s.name}" for s in part.states] + [s.name for s in part.inputs]
    derivative_dependencies, output_dependencies = part.dependencies()
    result = {f"der(state.{s.name})": [known[d] for d in deps] for s, deps in zip(part.states, derivative_dependencies)}
    result.update({s.name: [known[d] for d in deps] for s, deps in zip(part.outputs, output_dependencies)})
    return result


def twin_slots(variables, values: dict) -> list[Slot]:
    """The slots of a native twin from its numbered pythonfmu variables (``kernel_fmu.number_by_type``)."""
    initial = {"parameter": "exact", "output": "calculated"}
    return [Slot(v.name, v.type, v.causality, v.variability, None if v.causality == "output" else values[v.name],
                 v.unit if v.type == "Real" else "", v.description, initial.get(v.causality), None, None,
                 v.minimum, v.maximum) for v in variables]
