"""Read SSP 1.0 systems: an ``.ssp`` archive or an ``.ssd`` file (with its ``.ssv`` bindings) into a
:class:`~shapefmu.fmi.ssp.system.System`, every element checked against the FMUs it names."""

from __future__ import annotations

import atexit
import copy
import shutil
import tempfile
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

from shapefmu.fmi.archives import extract_system
from shapefmu.fmi.ssp.connectors import fmu_connectors, resolve
from shapefmu.fmi.ssp.system import Component, Connection, System, check_component_name
from shapefmu.fmi.ssp.values import TYPES, child, children, local, parameter_values, read_ssv
from shapefmu.runtime.checks import check_finite


def read_ssp(path, fmu_folder=None) -> System:
    """Read an .ssp archive or an .ssd file (or a folder holding SystemStructure.ssd) into a System.

    The members of an archive that the system uses are extracted, within the size limits, to a
    temporary folder that lives as long as the process (see :mod:`shapefmu.fmi.archives`).
    ``fmu_folder``: take each component's FMU from that folder by its file name instead of where its
    source points (a shipped example system runs with the FMUs ``shapefmu build`` wrote to ./fmus).
    """
    path = Path(path)
    if not path.exists():
        raise ValueError(f"SSP file not found: {path}")
    if path.is_dir():
        if not (path / "SystemStructure.ssd").is_file():
            raise ValueError(f"{path} is a directory without a SystemStructure.ssd; give an .ssp or .ssd file")
        path = path / "SystemStructure.ssd"
    if zipfile.is_zipfile(path):
        folder = Path(tempfile.mkdtemp(prefix=f"shapefmu_ssp_{path.stem}_"))
        _TEMPORARY_FOLDERS.append(folder)
        ssd = extract_system(path, folder)
        return _read_ssd(ssd, origin=f"{path}!SystemStructure.ssd", fmu_folder=fmu_folder)
    return _read_ssd(path, origin=str(path), fmu_folder=fmu_folder)


_TEMPORARY_FOLDERS: list[Path] = []


def _remove_temporary_folders() -> None:
    for folder in _TEMPORARY_FOLDERS:
        shutil.rmtree(folder, ignore_errors=True)


atexit.register(_remove_temporary_folders)


def _read_ssd(ssd: Path, origin: str, fmu_folder=None) -> System:
    try:
        root = ET.parse(ssd).getroot()
    except ET.ParseError as error:
        raise ValueError(f"{origin}: not valid XML: {error}") from None
    if local(root.tag) != "SystemStructureDescription":
        raise ValueError(f"{origin}: root element must be ssd:SystemStructureDescription, got {local(root.tag)}")
    node = child(root, "System")
    if node is None:
        raise ValueError(f"{origin}: no ssd:System element")
    system = System(node.get("name") or root.get("name") or "system")
    system.origin = origin
    base = ssd.parent
    elements = child(node, "Elements")
    for item in elements if elements is not None else []:
        if local(item.tag) != "Component":  # a nested ssd:System, an ssd:SignalDictionaryReference
            raise ValueError(f"{origin}: {local(item.tag)} {item.get('name')!r} in the Elements of system "
                             f"{system.name!r} is a nested element, which shapefmu does not run; flatten the "
                             f"system into components and connections")
    for item in children(elements, "Component") if elements is not None else []:
        name = item.get("name")
        source = item.get("source")
        where = f"{origin}: Component {name!r}"
        if not name or not source:
            raise ValueError(f"{where}: needs both a name and a source")
        check_component_name(name, f"{where}: its name")
        if name in system.components:
            raise ValueError(f"{where}: a component of that name already exists")
        fmu = (base / source if fmu_folder is None else Path(fmu_folder) / Path(source).name).resolve()
        if not fmu.is_file():
            looked = base if fmu_folder is None else Path(fmu_folder).resolve()
            raise ValueError(f"{where}: FMU file not found: {source} (looked in {looked})")
        connectors = fmu_connectors(fmu)
        declared = child(item, "Connectors")
        for connector in children(declared, "Connector") if declared is not None else []:
            cname = connector.get("name")
            try:  # an array's element (u[2]) is a connector too, as SSP tools declare FMI 2.0 array elements
                variable = resolve(connectors, name, cname or "")[0]
            except ValueError:
                raise ValueError(f"{where}: Connector {cname!r} is not a variable of {source}") from None
            typed = next((local(c.tag) for c in connector if local(c.tag) in TYPES), None)
            if typed is not None and typed != variable.type:
                raise ValueError(f"{where}: Connector {cname!r} is declared {typed} but the FMU has {variable.type}")
            kind = connector.get("kind")
            if kind is not None and kind != variable.kind and kind != "parameter":
                raise ValueError(f"{where}: Connector {cname!r} is declared {kind} but the FMU has {variable.kind}")
        component = Component(name, fmu, source, connectors)
        component.annotations = [copy.deepcopy(a) for a in item if local(a.tag) == "Annotations"]
        bindings = child(item, "ParameterBindings")
        for binding in children(bindings, "ParameterBinding") if bindings is not None else []:
            _read_binding(system, component, binding, base, where)
        system.components[name] = component
    system_bindings = child(node, "ParameterBindings")
    for binding in children(system_bindings, "ParameterBinding") if system_bindings is not None else []:
        _read_binding(system, None, binding, base, f"{origin}: System {system.name!r}")
    connections = child(node, "Connections")
    seen = {}
    for index, item in enumerate(children(connections, "Connection") if connections is not None else [], 1):
        where = f"{origin}: Connection {index}"
        start_component, end_component = item.get("startElement"), item.get("endElement")
        if not start_component or not end_component:
            raise ValueError(f"{where}: connections to the system's own connectors are not supported "
                             f"(startElement={start_component!r}, endElement={end_component!r})")
        factor, offset = 1.0, 0.0
        transformation = child(item, "LinearTransformation")
        if transformation is not None:
            factor = check_finite(transformation.get("factor", 1.0), f"{where}: LinearTransformation factor")
            offset = check_finite(transformation.get("offset", 0.0), f"{where}: LinearTransformation offset")
        for other in item:
            if local(other.tag) in ("MapTransformation", "BooleanMappingTransformation", "IntegerMappingTransformation"):
                raise ValueError(f"{where}: {local(other.tag)} is not supported (only LinearTransformation)")
        connection = Connection(start_component, item.get("startConnector", ""), end_component,
                                item.get("endConnector", ""), factor, offset)
        system._check_connection(connection, f"{where} ({connection.start} -> {connection.end})", seen)
        system.connections.append(connection)
    experiment = child(root, "DefaultExperiment")
    if experiment is not None:
        system.start_time = check_finite(experiment.get("startTime", 0.0), f"{origin}: DefaultExperiment startTime")
        if experiment.get("stopTime") is not None:
            system.stop_time = check_finite(experiment.get("stopTime"), f"{origin}: DefaultExperiment stopTime")
        system.experiment_annotations = [copy.deepcopy(a) for a in experiment if local(a.tag) == "Annotations"]
    system.annotations = [copy.deepcopy(a) for a in root if local(a.tag) == "Annotations"]
    system.system_annotations = [copy.deepcopy(a) for a in node if local(a.tag) == "Annotations"]
    return system


def _read_binding(system: System, component: Component | None, binding: ET.Element, base: Path, where: str) -> None:
    """Apply one ssd:ParameterBinding; a system-level binding's names are ``component.variable``."""
    if child(binding, "ParameterMapping") is not None:
        raise ValueError(f"{where}: ParameterMapping is not supported; bind the FMU's variable names directly")
    prefix = binding.get("prefix", "")
    source = binding.get("source")
    if source is not None:
        ssv = (base / source).resolve()
        if not ssv.is_file():
            raise ValueError(f"{where}: ParameterBinding source not found: {source} (looked in {base})")
        values = read_ssv(ssv)
    else:
        inline = child(binding, "ParameterValues")
        parameter_set = child(inline, "ParameterSet") if inline is not None else None
        if parameter_set is None:
            raise ValueError(f"{where}: ParameterBinding has neither a source nor inline ssv:ParameterSet values")
        values = parameter_values(parameter_set, where)
        ssv = None
    for name, value in values.items():
        name = name[len(prefix):] if prefix and name.startswith(prefix) else name
        target = component
        if target is None:
            component_name, _, name = name.partition(".")
            target = system.components.get(component_name)
            if target is None or not name:
                raise ValueError(f"{where}: parameter binding names unknown component in {component_name + '.' + name!r}")
        target.parameters.update(system._checked_parameters(target, {name: value}, where))
    if ssv is not None and component is not None:
        # Keep the file reference so the system is written back with the same binding; its values
        # were merged above in file order, and parameter_values() re-reads them in the same order.
        component.ssv_sources.append(ssv)
        for name in values:
            component.parameters.pop(name[len(prefix):] if prefix and name.startswith(prefix) else name, None)
