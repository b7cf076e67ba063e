"""SSP 1.0 system descriptions: read and write ``.ssd``, ``.ssp`` and ``.ssv`` files.

A :class:`System` is a set of FMU components, the connections between their connectors (each with
an optional SSP linear transformation ``u = factor * y + offset``), parameter bindings (inline
``ssv:ParameterSet`` values or ``.ssv`` files) and the default experiment. It is built either from a
file (:func:`read_ssp`) or in Python::

    system = (System("seek")
              .add("shaper", "fmus/Shaper.fmu", {"omega": 12566.4})
              .add("plant", "fmus/DiskDrive.fmu")
              .connect("shaper.y", "plant.voltage"))
    system.write_ssp("seek.ssp")          # the FMUs travel under resources/

The written ``.ssd`` uses only SSP 1.0 elements that libcosim and ecos read (components with typed
connectors, ``ssc:LinearTransformation``, ``ssd:ParameterBinding`` with inline values or an ``.ssv``
source), so the same file runs unchanged in those hosts. Annotations we do not understand (e.g.
OSP's algorithm settings) are kept on read and written back, and otherwise ignored.

Errors name the file, the element and the name: an unknown component or connector, a connection
whose types or causalities do not fit (output -> input only), an input connected twice, a missing
FMU file.

Connectors, FMI 3.0 array connectors and parameter values typed by connectors: :mod:`.connectors`;
parameter values and .ssv files: :mod:`.values`; reading .ssp and .ssd files: :mod:`.reading`.
"""

from __future__ import annotations

import copy
import math
import os
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from xml.etree import ElementTree as ET

from shapefmu.files import check_output, write_bytes, write_file
from shapefmu.fmi.ssp.connectors import Connector, checked_values, elements, fmu_connectors, resolve
from shapefmu.fmi.ssp.targets import for_target
from shapefmu.fmi.ssp.values import PARAMETER_SET, SSC, SSD, parameter_set, read_ssv
from shapefmu.runtime.checks import check_finite


@dataclass
class Component:
    """An FMU instance in the system. ``source`` is as written in the .ssd; ``fmu`` is resolved."""

    name: str
    fmu: Path
    source: str
    connectors: dict[str, Connector] = field(default_factory=dict)
    parameters: dict[str, float | int | bool | str] = field(default_factory=dict)
    ssv_sources: list[Path] = field(default_factory=list)  # .ssv files bound to this component
    annotations: list[ET.Element] = field(default_factory=list)


@dataclass(frozen=True)
class Connection:
    """``end = factor * start + offset`` (SSP 1.0 ssc:LinearTransformation)."""

    start_component: str
    start_connector: str
    end_component: str
    end_connector: str
    factor: float = 1.0
    offset: float = 0.0

    @property
    def start(self) -> str:
        return f"{self.start_component}.{self.start_connector}"

    @property
    def end(self) -> str:
        return f"{self.end_component}.{self.end_connector}"


def check_component_name(name, what: str) -> str:
    """A component name: it heads the component's columns of every results file and names it in
    messages, so it is one line of printable text, without a '.' (which separates it from a variable)."""
    if not isinstance(name, str) or not name or "." in name or name != name.strip() or not name.isprintable():
        raise ValueError(f"{what} must be non-empty printable text without '.', line breaks or surrounding "
                         f"spaces, got {name!r}")
    return name


def _split(reference: str, what: str) -> tuple[str, str]:
    component, dot, variable = reference.partition(".")
    if not dot or not component or not variable:
        raise ValueError(f"{what} must be 'component.variable', got {reference!r}")
    return component, variable


class System:
    """An SSP system of FMU components; see the module docstring."""

    def __init__(self, name: str = "system"):
        if not name:
            raise ValueError("system name must be a non-empty string, got ''")
        self.name = name
        self.components: dict[str, Component] = {}
        self.connections: list[Connection] = []
        self.start_time = 0.0
        self.stop_time: float | None = None
        self.annotations: list[ET.Element] = []  # kept from the file, written back unchanged
        self.system_annotations: list[ET.Element] = []  # those of the ssd:System element, likewise
        self.experiment_annotations: list[ET.Element] = []  # those of ssd:DefaultExperiment, likewise
        self.origin = "<System>"  # the file this system was read from, for error messages

    # ----------------------------------------------------------------------------- building
    def add(self, name: str, fmu_path, parameters: dict | None = None, ssv=None) -> System:
        """Add the FMU at ``fmu_path`` as component ``name``, with optional parameter values.

        ``parameters`` become an inline parameter binding; ``ssv`` (a path) a binding to an .ssv
        file whose values are applied first (inline values override them, as SSP orders bindings).
        """
        check_component_name(name, "component name")
        if name in self.components:
            raise ValueError(f"component {name!r} is already in system {self.name!r}")
        fmu = Path(fmu_path)
        if not fmu.is_file():
            raise ValueError(f"FMU file of component {name!r} not found: {fmu}")
        component = Component(name, fmu.resolve(), str(fmu), fmu_connectors(fmu))
        if ssv is not None:
            ssv = Path(ssv)
            if not ssv.is_file():
                raise ValueError(f"parameter file of component {name!r} not found: {ssv}")
            component.ssv_sources.append(ssv.resolve())
        component.parameters.update(self._checked_parameters(component, parameters or {}, f"component {name!r}"))
        self.components[name] = component
        return self

    def connect(self, start: str, end: str, factor: float = 1.0, offset: float = 0.0) -> System:
        """Connect output ``start`` ("comp.y") to input ``end`` ("comp.u"): end = factor*start + offset."""
        start_component, start_connector = _split(start, "connection start")
        end_component, end_connector = _split(end, "connection end")
        factor, offset = (check_finite(value, f"connection {start} -> {end}: {what}") for value, what in
                          ((factor, "factor"), (offset, "offset")))
        connection = Connection(start_component, start_connector, end_component, end_connector, factor, offset)
        self._check_connection(connection, f"connection {start} -> {end}")
        self.connections.append(connection)
        return self

    # ----------------------------------------------------------------------------- queries
    def parameter_values(self, component: str) -> dict:
        """Every value bound to ``component``: its .ssv files first, then inline values."""
        item = self.components[component]
        values = {}
        for ssv in item.ssv_sources:
            values.update(read_ssv(ssv))
        values.update(item.parameters)
        return values

    def for_experiment(self, stop_time: float, parameters: dict | None = None) -> System:
        """A copy of the system for one experiment: run from its start time to ``stop_time``, with
        ``{"component.variable": value}`` added to the components' bindings (typed by each FMU's
        variable, as ``--set`` values are), so a file written from it runs the same experiment."""
        if not (isinstance(stop_time, (int, float)) and math.isfinite(stop_time) and stop_time > self.start_time):
            raise ValueError(f"stop_time must be a finite number > start time {self.start_time!r} s, got {stop_time!r}")
        result = copy.copy(self)
        result.components = {name: copy.copy(c) for name, c in self.components.items()}
        result.stop_time = float(stop_time)
        for reference, value in (parameters or {}).items():
            name, variable = _split(reference, "parameter name")
            if name not in result.components:
                raise ValueError(f"parameter {reference!r} names unknown component {name!r}")
            component = result.components[name]
            component.parameters = {**component.parameters,
                                    **self._checked_parameters(component, {variable: value}, f"component {name!r}")}
        return result

    def connector(self, component: str, reference: str) -> tuple[Connector, int | None]:
        """The connector of ``component`` that ``reference`` names, and the element's 1-based index
        when it names one element of an array (``"u[2]"``); ValueError if there is none."""
        return resolve(self.components[component].connectors, component, reference)

    def validate(self) -> System:
        """Check every component's FMU exists and every connection fits; return self."""
        for component in self.components.values():
            if not component.fmu.is_file():
                raise ValueError(f"{self.origin}: Component {component.name!r}: FMU file not found: {component.fmu}")
        seen = {}
        for connection in self.connections:
            self._check_connection(connection, f"{self.origin}: Connection {connection.start} -> {connection.end}", seen)
        return self

    def _check_connection(self, connection: Connection, where: str, seen: dict | None = None) -> None:
        ends, sizes = [], []
        for role, component_name, connector_name, allowed in (
            ("start", connection.start_component, connection.start_connector, ("output", "calculatedParameter", "parameter")),
            ("end", connection.end_component, connection.end_connector, ("input", "parameter")),
        ):
            component = self.components.get(component_name)
            if component is None:
                known = ", ".join(self.components) or "none"
                raise ValueError(f"{where}: unknown component {component_name!r} (components: {known})")
            try:
                connector, index = self.connector(component_name, connector_name)
            except ValueError as error:
                raise ValueError(f"{where}: {error}") from None
            sizes.append(connector.size if index is None and connector.size is not None else 1)
            if connector.kind not in allowed:
                raise ValueError(
                    f"{where}: {role} {component_name}.{connector_name} has causality {connector.kind!r}, "
                    f"a connection {role} must be one of {allowed}"
                )
            ends.append(connector)
        if (ends[0].type, ends[0].declared_type) != (ends[1].type, ends[1].declared_type):
            def typed(connector, reference):
                return f"{connector.type}{' ' + connector.declared_type if connector.declared_type else ''} {reference}"

            raise ValueError(f"{where}: type mismatch, {typed(ends[0], connection.start)} -> {typed(ends[1], connection.end)}")
        if ends[0].type != "Real" and (connection.factor != 1.0 or connection.offset != 0.0):
            raise ValueError(f"{where}: a linear transformation needs Real connectors, got {ends[0].type}")
        if sizes[0] != sizes[1]:
            raise ValueError(f"{where}: size mismatch, {connection.start} has {sizes[0]} element(s) and {connection.end} "
                             f"{sizes[1]}; connect arrays of one size, or single elements as name[i]")
        already = seen if seen is not None else {
            element: c for c in self.connections
            for element in elements(self.components[c.end_component].connectors, c.end_component, c.end_connector)}
        for element in elements(self.components[connection.end_component].connectors, connection.end_component,
                                connection.end_connector):
            if element in already:
                raise ValueError(f"{where}: input {element} is already connected from {already[element].start}")
            if seen is not None:
                seen[element] = connection

    def _checked_parameters(self, component: Component, values: dict, where: str) -> dict:
        return checked_values(component.connectors, component.fmu.name, values, where)

    # ----------------------------------------------------------------------------- writing
    def write_ssd(self, path, *, target: str | None = None, step: float | None = None, fold: dict | None = None) -> Path:
        """Write ``SystemStructure.ssd``-style XML to ``path``; FMU sources relative to its folder.

        ``target="omsimulator"`` writes the system as OpenModelica's OMSimulator imports it, with
        its fixed macro ``step`` (s) and ``fold`` for linear transformations: see
        :func:`shapefmu.fmi.ssp.targets.for_target`. The default target (None) writes what
        libcosim and ecos read.
        """
        self = for_target(self, target, step, fold)
        path = Path(path)
        sources = {name: os.path.relpath(c.fmu, path.parent.resolve()) for name, c in self.components.items()}
        ssv = {name: [os.path.relpath(s, path.parent.resolve()) for s in c.ssv_sources] for name, c in self.components.items()}
        return write_bytes(path, self._xml(sources, ssv), "system file")

    def write_ssp(self, path, *, target: str | None = None, step: float | None = None, fold: dict | None = None) -> Path:
        """Write an .ssp archive: SystemStructure.ssd plus the FMUs and .ssv files under resources/
        (``target``, ``step``, ``fold``: as for :meth:`write_ssd`)."""
        self = for_target(self, target, step, fold)
        path = Path(path)
        names: dict[Path, str] = {}
        sources, ssv = {}, {}
        for name, component in self.components.items():
            sources[name] = "resources/" + _unique_name(names, component.fmu, name)
            ssv[name] = ["resources/" + _unique_name(names, s, name) for s in component.ssv_sources]

        def write(temporary):
            with zipfile.ZipFile(temporary, "w", zipfile.ZIP_DEFLATED) as archive:
                archive.writestr("SystemStructure.ssd", self._xml(sources, ssv))
                for file, arcname in names.items():
                    archive.write(file, "resources/" + arcname)

        return write_file(path, write, "system archive")

    def _xml(self, sources: dict[str, str], ssv: dict[str, list[str]]) -> bytes:
        root = ET.Element(f"{{{SSD}}}SystemStructureDescription", {"version": "1.0", "name": self.name})
        system = ET.SubElement(root, f"{{{SSD}}}System", {"name": self.name})
        elements = ET.SubElement(system, f"{{{SSD}}}Elements")
        for name, component in self.components.items():
            item = ET.SubElement(elements, f"{{{SSD}}}Component",
                                 {"name": name, "source": sources[name], "type": "application/x-fmu-sharedlibrary"})
            connectors = ET.SubElement(item, f"{{{SSD}}}Connectors")
            for connector in component.connectors.values():
                node = ET.SubElement(connectors, f"{{{SSD}}}Connector", {"name": connector.name, "kind": connector.kind})
                typed = ET.SubElement(node, f"{{{SSC}}}{connector.type}")
                if connector.declared_type:
                    typed.set("name", connector.declared_type)  # refers to an ssc:Enumeration below
            if component.parameters or ssv[name]:
                bindings = ET.SubElement(item, f"{{{SSD}}}ParameterBindings")
                for source in ssv[name]:
                    ET.SubElement(bindings, f"{{{SSD}}}ParameterBinding", {"source": source})
                if component.parameters:
                    binding = ET.SubElement(bindings, f"{{{SSD}}}ParameterBinding")
                    values = ET.SubElement(binding, f"{{{SSD}}}ParameterValues")
                    values.append(parameter_set(PARAMETER_SET, component.parameters, component.connectors))
            item.extend(copy.deepcopy(component.annotations))
        connections = ET.SubElement(system, f"{{{SSD}}}Connections")
        for c in self.connections:
            node = ET.SubElement(connections, f"{{{SSD}}}Connection", {
                "startElement": c.start_component, "startConnector": c.start_connector,
                "endElement": c.end_component, "endConnector": c.end_connector,
            })
            if c.factor != 1.0 or c.offset != 0.0:
                ET.SubElement(node, f"{{{SSC}}}LinearTransformation", {"factor": repr(c.factor), "offset": repr(c.offset)})
        system.extend(copy.deepcopy(self.system_annotations))
        enumerations = {c.declared_type: c.items for component in self.components.values()
                        for c in component.connectors.values() if c.declared_type}
        if enumerations:
            node = ET.SubElement(root, f"{{{SSD}}}Enumerations")
            for name, items in enumerations.items():
                enumeration = ET.SubElement(node, f"{{{SSC}}}Enumeration", {"name": name})
                for item, value in items.items():
                    ET.SubElement(enumeration, f"{{{SSC}}}Item", {"name": item, "value": str(value)})
        # Both times, always: pyssp-standard and OMSimulator's Python API read both. A system built
        # for no particular experiment gets the FMI tools' default length, 1 s from its start (what
        # fmpy's simulate_fmu and OMSimulator take when a model names none).
        stop = self.stop_time if self.stop_time is not None else self.start_time + 1.0
        experiment = {"startTime": repr(self.start_time), "stopTime": repr(stop)}
        ET.SubElement(root, f"{{{SSD}}}DefaultExperiment", experiment).extend(copy.deepcopy(self.experiment_annotations))
        root.extend(copy.deepcopy(self.annotations))
        ET.indent(root)
        return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def write_system(system: System, path, target: str | None = None, step: float | None = None, fold: dict | None = None,
                 named: bool = True) -> Path:
    """``system`` to ``path``: an .ssp archive (the FMUs and .ssv files inside) or an .ssd file (they
    stay where they are), for ``target`` (None, "libcosim", "omsimulator"; see :mod:`.targets`),
    whose ``step`` (and ``fold``) it takes; ``named``: as for :func:`~shapefmu.fmi.ssp.values.write_ssv`."""
    path = check_output(path, "system file", named)
    options = {"target": target, "step": step, "fold": fold} if target is not None else {}
    return system.write_ssp(path, **options) if path.suffix.lower() == ".ssp" else system.write_ssd(path, **options)


def _unique_name(names: dict[Path, str], file: Path, component: str) -> str:
    """The file's name under resources/, prefixed by the component when two files share a name."""
    if file in names:
        return names[file]
    name = file.name if file.name not in names.values() else f"{component}_{file.name}"
    names[file] = name
    return name
