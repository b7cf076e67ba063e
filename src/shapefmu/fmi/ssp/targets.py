"""SSP systems written for one consumer: libcosim's fixed step, or OMSimulator, which reads less of
SSP 1.0 than libcosim and ecos do.

``System.write_ssd(path, target="libcosim", step=1e-6)`` adds the Open Simulation Platform's
annotation of the default experiment, ``<osp:Algorithm><osp:FixedStepAlgorithm baseStepSize=".."/>``,
so libcosim (``cosim run``, ``CosimExecution.from_ssp_file`` without a step) runs the file with the
macro step it was written for.

``System.write_ssd(path, target="omsimulator", step=1e-6, fold={...})`` writes what OpenModelica's
OMSimulator imports and runs as it is meant:

* OMSimulator refuses an ``.ssd`` whose ``ssd:System`` lacks its vendor annotation: the system gets
  ``<ssc:Annotation type="org.openmodelica"><oms:Annotations><oms:SimulationInformation>
  <oms:FixedStepMaster description="oms-ma" stepSize=".."/>`` with the macro ``step``, and the
  default experiment an ``oms:SimulationInformation`` naming the result file
  (``<system name>_res.csv``).
* It imports no String connector and no String parameter binding: String connectors are left out;
  a String binding equal to the FMU's own start value is dropped (the FMU already has it), any
  other is refused (build the FMU with that start value instead), as is a String connection.
* It has no code for ``ssc:LinearTransformation`` (it would run the connection with factor 1): each
  transformed connection is written plain and its factor *folded* into parameters, as ``fold``
  says, e.g. ``{"shaper.y": ["u"]}`` (the shaper's output is proportional to its input ``u``: scale
  ``u``) or ``{"plant.voltage": ["b2", "b4[1]"]}`` (the plant's input enters only through those
  gains: scale them). A connection with a factor that ``fold`` does not cover, or with an offset,
  is refused for this target, naming the connection.

Every parameter binding is written inline (the .ssv files' values merged in the SSP order), so the
folded values are the ones written. The rewritten system is a copy; the original is unchanged.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from xml.etree import ElementTree as ET

TARGETS = ("omsimulator", "libcosim")
OMS = "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd"
OSP = "http://opensimulationplatform.com/SSP/OSPAnnotations"
_SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
_SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
ET.register_namespace("oms", OMS)
ET.register_namespace("osp", OSP)


def for_target(system, target: str | None, step: float | None = None, fold: dict | None = None):
    """``system`` as written for ``target`` (None: unchanged; see the module docstring)."""
    if target is None:
        if step is not None or fold:
            raise ValueError("step and fold apply to a target ('omsimulator' or 'libcosim') only, got target=None")
        return system
    if target not in TARGETS:
        raise ValueError(f"target must be None or one of {TARGETS}, got {target!r}")
    if not (isinstance(step, (int, float)) and math.isfinite(step) and step > 0):
        raise ValueError(f"target {target!r} needs step, the fixed macro step in s (> 0), got {step!r}")
    if target == "libcosim":
        if fold:
            raise ValueError("fold applies to target 'omsimulator' only: libcosim runs linear transformations itself")
        result = copy.copy(system)
        result.experiment_annotations = [_annotation(f'<osp:Algorithm><osp:FixedStepAlgorithm baseStepSize="{float(step)!r}"/>'
                                                     f'</osp:Algorithm>', "com.opensimulationplatform", OSP, "osp")]
        return result
    return _omsimulator(system, float(step), dict(fold or {}))


def _omsimulator(system, step: float, fold: dict):
    result = copy.copy(system)
    result.components = {}
    for name, component in system.components.items():
        twin = copy.copy(component)
        twin.parameters = _without_strings(name, component, system.parameter_values(name))
        twin.ssv_sources = []
        twin.connectors = {k: c for k, c in component.connectors.items() if c.type != "String"}
        result.components[name] = twin
    result.connections = []
    scaled: dict[tuple[str, str], float] = {}
    for connection in system.connections:
        end = system.connector(connection.end_component, connection.end_connector)[0]
        if end.type == "String":
            raise ValueError(f"target 'omsimulator': connection {connection.start} -> {connection.end} joins String "
                             f"connectors, which OMSimulator does not import")
        if connection.factor != 1.0 or connection.offset != 0.0:
            _fold(result, connection, fold, scaled)
            connection = dataclasses.replace(connection, factor=1.0, offset=0.0)
        result.connections.append(connection)
    result.system_annotations = [_annotation(f'<oms:SimulationInformation><oms:FixedStepMaster description="oms-ma" '
                                             f'stepSize="{step!r}" relativeTolerance="1e-06"/></oms:SimulationInformation>')]
    result.experiment_annotations = [_annotation(f'<oms:SimulationInformation resultFile="{_attribute(system.name)}_res.csv" '
                                                 f'loggingInterval="0"/>')]
    return result


def _without_strings(name: str, component, values: dict) -> dict:
    kept = {}
    for key, value in values.items():
        connector = component.connectors.get(key)
        if connector is None or connector.type != "String":
            kept[key] = value
        elif str(value) != (connector.start or ""):
            raise ValueError(f"target 'omsimulator': OMSimulator does not import String parameter bindings, and "
                             f"{name}.{key} = {value!r} differs from the FMU's start value {connector.start!r}; "
                             f"build the FMU with that start value baked in (build_fmu(..., {key}={value!r}))")
    return kept


def _fold(result, connection, fold: dict, scaled: dict) -> None:
    """Scale the parameters ``fold`` names for ``connection`` by its factor (once per parameter)."""
    where = f"target 'omsimulator': connection {connection.start} -> {connection.end}"
    if connection.offset != 0.0:
        raise ValueError(f"{where} has offset {connection.offset!r}, which OMSimulator cannot apply (it has no "
                         f"ssc:LinearTransformation) and which no parameter can absorb; remove the offset")
    for reference, component_name in ((connection.end, connection.end_component),
                                      (connection.start, connection.start_component)):
        if reference in fold:
            break
    else:
        raise ValueError(f"{where} has factor {connection.factor!r}, which OMSimulator ignores (no "
                         f"ssc:LinearTransformation); pass fold={{{connection.start!r}: [parameters its output is "
                         f"proportional to]}} or fold={{{connection.end!r}: [the gains its input enters through]}}")
    names = [fold[reference]] if isinstance(fold[reference], str) else list(fold[reference])
    component = result.components[component_name]
    for name in names:
        connector = component.connectors.get(name)
        if connector is None or connector.type != "Real" or connector.kind not in ("parameter", "input"):
            raise ValueError(f"{where}: fold names {component_name}.{name}, which is not a Real parameter or input "
                             f"of {component.fmu.name}")
        key = (component_name, name)
        if key in scaled:
            if scaled[key] != connection.factor:
                raise ValueError(f"{where}: {component_name}.{name} is already scaled by {scaled[key]!r} for another "
                                 f"connection; one parameter cannot fold two factors")
            continue
        value = component.parameters.get(name, float(connector.start) if connector.start is not None else 0.0)
        component.parameters[name] = float(value) * connection.factor
        scaled[key] = connection.factor


def _attribute(text: str) -> str:
    return text.replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;")


def _annotation(body: str, kind: str = "org.openmodelica", namespace: str = OMS, prefix: str = "oms") -> ET.Element:
    """``<ssd:Annotations><ssc:Annotation type="kind">body`` (OMSimulator's: in ``oms:Annotations``)."""
    if kind == "org.openmodelica":
        body = f"<oms:Annotations>{body}</oms:Annotations>"
    return ET.fromstring(f'<ssd:Annotations xmlns:ssd="{_SSD}" xmlns:ssc="{_SSC}" xmlns:{prefix}="{namespace}">'
                         f'<ssc:Annotation type="{kind}">{body}</ssc:Annotation></ssd:Annotations>')


def written_step(system) -> float | None:
    """The macro step a system was written for, as ``for_target`` records it (OSP's
    ``baseStepSize``, OMSimulator's ``stepSize``), read back from its annotations; None when it
    records none. ``shapefmu simulate`` and ``sweep`` take it when no ``--step`` is given."""
    for annotations in (*system.experiment_annotations, *system.system_annotations):
        for element in annotations.iter():
            text = element.get("baseStepSize", element.get("stepSize"))
            if text is None:
                continue
            try:
                step = float(text)
            except ValueError:
                step = math.nan
            if not (math.isfinite(step) and step > 0):
                raise ValueError(f"system {system.name!r}: the macro step in its annotations must be a number > 0 s, "
                                 f"got {text!r}")
            return step
    return None
