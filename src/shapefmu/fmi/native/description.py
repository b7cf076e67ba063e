"""modelDescription.xml (FMI 2.0) and sources/buildDescription.xml (FMI 2.0.4 / 3.0 build description)
of a plant FMU.

Value references follow plant_model.h: 0 time, then the states, their derivatives, the inputs,
the outputs and the parameters; variables are listed in that order, so the ModelStructure index
of a variable is its value reference + 1.
"""

from __future__ import annotations

import hashlib
import uuid
from xml.sax.saxutils import quoteattr

from shapefmu import __version__
from shapefmu.fmi.native.model_part import ModelPart

LOG_CATEGORIES = ("logStatusError", "logAll")


def _attributes(**values) -> str:
    return "".join(f" {key}={quoteattr(str(value))}" for key, value in values.items() if value not in (None, ""))


def _real(value: float) -> str:
    return repr(float(value))


def guid_of(part: ModelPart, sources: dict[str, str]) -> str:
    """A GUID that changes whenever the model description or any source changes."""
    digest = hashlib.md5(model_description(part, "").encode())
    for name in sorted(sources):
        digest.update(name.encode())
        digest.update(sources[name].encode())
    return "{" + str(uuid.UUID(digest.hexdigest())) + "}"


def model_identifier(part: ModelPart) -> str:
    """The C identifier the shared library is named by: the plant's name with non-word characters replaced."""
    identifier = "".join(c if c.isalnum() or c == "_" else "_" for c in part.name)
    return identifier if identifier[:1].isalpha() else f"plant_{identifier}"


def model_description(part: ModelPart, guid: str, source_files: tuple[str, ...] = ()) -> str:
    nx, nu, ny = len(part.states), len(part.inputs), len(part.outputs)
    identifier = model_identifier(part)
    files = "".join(f'      <File name="{name}"/>\n' for name in source_files)
    sources = f"    <SourceFiles>\n{files}    </SourceFiles>\n" if source_files else ""
    common = _attributes(modelIdentifier=identifier, canGetAndSetFMUstate="true", canSerializeFMUstate="true",
                         canNotUseMemoryManagementFunctions="false")
    units = sorted({s.unit for s in (*part.states, *part.inputs, *part.outputs) if s.unit}
                   | {p.unit for p in part.parameters if p.unit})
    # Time is the implicit independent variable (FMI 2.0, section 2.2.7), not listed: FMI Library,
    # which libcosim reads model descriptions with, logs an error for a listed one without a start
    # value, which is the only form the standard allows. The wrapper keeps value reference 0 for it.
    variables = []
    vr = 1
    for state in part.states:
        variables.append(
            f"    <ScalarVariable{_attributes(name=f'state.{state.name}', valueReference=vr, description=state.description)}"
            f' causality="local" variability="continuous" initial="exact">'
            f"<Real{_attributes(start=_real(state.start), unit=state.unit, nominal=_real(state.nominal))}/></ScalarVariable>")
        vr += 1
    for i, state in enumerate(part.states):
        variables.append(
            f"    <ScalarVariable{_attributes(name=f'der(state.{state.name})', valueReference=vr)}"
            f' causality="local" variability="continuous" initial="calculated">'
            f"<Real{_attributes(derivative=i + 1)}/></ScalarVariable>")
        vr += 1
    for signal in part.inputs:
        variables.append(
            f"    <ScalarVariable{_attributes(name=signal.name, valueReference=vr, description=signal.description)}"
            f' causality="input" variability="continuous">'
            f"<Real{_attributes(start=_real(signal.start), unit=signal.unit)}/></ScalarVariable>")
        vr += 1
    for signal in part.outputs:
        variables.append(
            f"    <ScalarVariable{_attributes(name=signal.name, valueReference=vr, description=signal.description)}"
            f' causality="output" variability="continuous" initial="calculated">'
            f"<Real{_attributes(unit=signal.unit)}/></ScalarVariable>")
        vr += 1
    for parameter in part.parameters:
        variability = "tunable" if parameter.tunable else "fixed"
        variables.append(
            f"    <ScalarVariable{_attributes(name=parameter.name, valueReference=vr, description=parameter.description)}"
            f' causality="parameter" variability="{variability}" initial="exact">'
            f"<Real{_attributes(start=_real(parameter.value), unit=parameter.unit)}/></ScalarVariable>")
        vr += 1

    # ModelStructure indices are 1-based positions in ModelVariables = value reference.
    known_index = [1 + i for i in range(nx)] + [1 + 2 * nx + j for j in range(nu)]
    derivative_dependencies, output_dependencies = part.dependencies()

    def unknown(index: int, dependencies: list[int]) -> str:
        return f'      <Unknown index="{index}" dependencies="{" ".join(str(known_index[d]) for d in dependencies)}"/>'

    output_index = [1 + 2 * nx + nu + k for k in range(ny)]
    derivative_index = [1 + nx + i for i in range(nx)]
    outputs = [unknown(output_index[k], deps) for k, deps in enumerate(output_dependencies)]
    derivatives = [unknown(derivative_index[i], deps) for i, deps in enumerate(derivative_dependencies)]
    initial = [f'      <Unknown index="{index}"/>' for index in sorted(output_index + derivative_index)]
    newline = "\n"
    unit_definitions = "".join(f"    <Unit name={quoteattr(unit)}/>\n" for unit in units)
    if unit_definitions:
        unit_definitions = f"  <UnitDefinitions>\n{unit_definitions}  </UnitDefinitions>\n"
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription{_attributes(fmiVersion="2.0", modelName=part.name, guid=guid, description=part.description,
                                  generationTool=f"shapefmu {__version__} plant generator", variableNamingConvention="structured",
                                  numberOfEventIndicators=0)}>
  <ModelExchange{common} providesDirectionalDerivative="true">
{sources}  </ModelExchange>
  <CoSimulation{common} canHandleVariableCommunicationStepSize="true" canInterpolateInputs="false" maxOutputDerivativeOrder="0">
{sources}  </CoSimulation>
{unit_definitions}  <LogCategories>
{newline.join(f'    <Category name="{category}"/>' for category in LOG_CATEGORIES)}
  </LogCategories>
  <ModelVariables>
{newline.join(variables)}
  </ModelVariables>
  <ModelStructure>
    <Outputs>
{newline.join(outputs)}
    </Outputs>
    <Derivatives>
{newline.join(derivatives)}
    </Derivatives>
    <InitialUnknowns>
{newline.join(initial)}
    </InitialUnknowns>
  </ModelStructure>
</fmiModelDescription>
"""
