"""modelDescription.xml (FMI 3.0) of a plant FMU built for ``fmi_version="3.0"``.

The same variables as the FMI 2.0 description (:mod:`.description`), as FMI 3.0 writes them: every
variable is a ``Float64`` with the value reference of plant_model.h; time (value reference 0) is
listed, as the independent variable FMI 3.0 requires; ``derivative`` and the ModelStructure's
``dependencies`` name value references; the ModelStructure lists each ``Output``, each
``ContinuousStateDerivative`` and every ``InitialUnknown`` (outputs and derivatives, FMI 3.0
sec. 2.4.8).
"""

from __future__ import annotations

from shapefmu import __version__
from shapefmu.fmi.native.description import LOG_CATEGORIES, _attributes, _real, model_identifier
from shapefmu.fmi.native.model_part import ModelPart


def model_description(part: ModelPart, token: str, source_files: tuple[str, ...] = ()) -> str:
    """The FMI 3.0 modelDescription.xml of ``part`` with instantiation token ``token``."""
    del source_files  # FMI 3.0 lists sources in sources/buildDescription.xml only
    nx, nu, ny = len(part.states), len(part.inputs), len(part.outputs)
    identifier = model_identifier(part)
    common = _attributes(modelIdentifier=identifier, canGetAndSetFMUState="true", canSerializeFMUState="true",
                         providesDirectionalDerivatives="true")
    units = sorted({s.unit for s in (*part.states, *part.inputs, *part.outputs) if s.unit}
                   | {p.unit for p in part.parameters if p.unit})
    variables = ['    <Float64 name="time" valueReference="0" causality="independent" variability="continuous"'
                 ' description="simulation time"/>']
    state_vr = [1 + i for i in range(nx)]
    derivative_vr = [1 + nx + i for i in range(nx)]
    input_vr = [1 + 2 * nx + j for j in range(nu)]
    output_vr = [1 + 2 * nx + nu + k for k in range(ny)]
    for vr, state in zip(state_vr, part.states):
        variables.append(f"    <Float64{_attributes(name=f'state.{state.name}', valueReference=vr, description=state.description)}"
                         f' causality="local" variability="continuous" initial="exact"'
                         f"{_attributes(start=_real(state.start), unit=state.unit, nominal=_real(state.nominal))}/>")
    for vr, state_reference, state in zip(derivative_vr, state_vr, part.states):
        variables.append(f"    <Float64{_attributes(name=f'der(state.{state.name})', valueReference=vr)}"
                         f' causality="local" variability="continuous" initial="calculated" derivative="{state_reference}"/>')
    for vr, signal in zip(input_vr, part.inputs):
        variables.append(f"    <Float64{_attributes(name=signal.name, valueReference=vr, description=signal.description)}"
                         f' causality="input" variability="continuous"{_attributes(start=_real(signal.start), unit=signal.unit)}/>')
    for vr, signal in zip(output_vr, part.outputs):
        variables.append(f"    <Float64{_attributes(name=signal.name, valueReference=vr, description=signal.description)}"
                         f' causality="output" variability="continuous" initial="calculated"{_attributes(unit=signal.unit)}/>')
    for offset, parameter in enumerate(part.parameters):
        vr = 1 + 2 * nx + nu + ny + offset
        variability = "tunable" if parameter.tunable else "fixed"
        variables.append(f"    <Float64{_attributes(name=parameter.name, valueReference=vr, description=parameter.description)}"
                         f' causality="parameter" variability="{variability}"'
                         f"{_attributes(start=_real(parameter.value), unit=parameter.unit)}/>")

    known_vr = state_vr + input_vr
    derivative_dependencies, output_dependencies = part.dependencies()

    def unknown(element: str, vr: int, dependencies: list[int]) -> str:
        return f'    <{element} valueReference="{vr}" dependencies="{" ".join(str(known_vr[d]) for d in dependencies)}"/>'

    structure = ([unknown("Output", vr, deps) for vr, deps in zip(output_vr, output_dependencies)]
                 + [unknown("ContinuousStateDerivative", vr, deps) for vr, deps in zip(derivative_vr, derivative_dependencies)]
                 + [f'    <InitialUnknown valueReference="{vr}"/>' for vr in sorted(output_vr + derivative_vr)])
    unit_definitions = "".join(f"    <Unit{_attributes(name=unit)}/>\n" for unit in units)
    if unit_definitions:
        unit_definitions = f"  <UnitDefinitions>\n{unit_definitions}  </UnitDefinitions>\n"
    categories = "".join(f'    <Category name="{category}"/>\n' for category in LOG_CATEGORIES)
    newline = "\n"
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription{_attributes(fmiVersion="3.0", modelName=part.name, instantiationToken=token, description=part.description,
                                  generationTool=f"shapefmu {__version__} plant generator", variableNamingConvention="structured")}>
  <ModelExchange{common}/>
  <CoSimulation{common} canHandleVariableCommunicationStepSize="true" hasEventMode="false"/>
{unit_definitions}  <LogCategories>
{categories}  </LogCategories>
  <ModelVariables>
{newline.join(variables)}
  </ModelVariables>
  <ModelStructure>
{newline.join(structure)}
  </ModelStructure>
</fmiModelDescription>
"""
