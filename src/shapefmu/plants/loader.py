"""Plant model files: declarative, tool-neutral TOML read with the standard library's ``tomllib``.

A file names a ``kind`` (one constructor of ``shapefmu.plants.library``), its ``parameters`` each
with a value and a unit, its ``inputs`` (unit and optional actuator limit ``max``) and its
``outputs`` (unit), in the order the kind defines them::

    name = "disk_drive"
    kind = "rigid_flexible"
    [parameters]
    b2 = { value = 2.7e3, unit = "1/(V*s^2)" }
    f = { value = [2.0e3, 3.0e3], unit = "Hz" }
    ...
    [inputs]
    voltage = { unit = "V", max = 11.0 }
    [outputs]
    position = { unit = "rad" }

An optional ``[scheduling]`` table declares an input on which parameters depend (an added mass, a
rope length): ``load_scheduled`` reads such a file as a ``ScheduledPlant`` (``plants.scheduling``),
``load`` as the plant at the input's start value.

The plant-FMU generator reads the same files, so nothing here is specific to Python beyond the
constructors the kinds map to.
"""

from __future__ import annotations

import functools
import math
import os
import re
import tomllib
from dataclasses import dataclass

import control

from shapefmu.plants import library, shipped
from shapefmu.runtime.checks import check_text, parse_nested, read_text_file
from shapefmu.plants.model import Parameter, Plant
from shapefmu.plants.scheduling import ScheduledPlant, SchedulingInput


@dataclass(frozen=True)
class ParameterSpec:
    """A parameter of a kind: whether it is a list, required, and the units it may be given in
    with their factor to the unit the constructor takes (None: any non-empty unit is accepted).

    Examples
    --------
    >>> PARAMETER_SPECS["rigid_flexible"]["f"].units  # a frequency in Hz or rad/s, to rad/s
    {'Hz': 6.283185307179586, 'rad/s': 1.0}
    """

    array: bool
    required: bool = True
    units: dict | None = None


# Names in a model file (the plant, its signals) become C identifiers, FMI variable names and file
# names in the plant-FMU generator, so they are identifiers and nothing else.
IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")

_FREQUENCY = {"Hz": 2.0 * math.pi, "rad/s": 1.0}
_LENGTH = {"m": 1.0, "in": library.INCH, "mm": 1e-3}

# Per kind: its parameters' specs, name -> ParameterSpec (also read by the plant-FMU generator,
# shapefmu.fmi.native, to convert model-file units).
PARAMETER_SPECS = {
    "rigid_flexible": {
        "b2": ParameterSpec(False),
        "f": ParameterSpec(True, units=_FREQUENCY),
        "zeta": ParameterSpec(True, units={"1": 1.0}),
        "b4": ParameterSpec(True),
        "rigid_damping": ParameterSpec(False, required=False, units={"1/s": 1.0}),
    },
    # Paper 002, Sec. I and Fig. 5: back EMF damps the rigid body by Kt^2/(R J).
    "voice_coil_flexible": {
        "b2": ParameterSpec(False),
        "Kt": ParameterSpec(False, units={"N*m/A": 1.0}),
        "R": ParameterSpec(False, units={"ohm": 1.0}),
        "J": ParameterSpec(False, units={"kg*m^2": 1.0}),
        "f": ParameterSpec(True, units=_FREQUENCY),
        "zeta": ParameterSpec(True, units={"1": 1.0}),
        "b4": ParameterSpec(True),
    },
    "transfer_function": {"num": ParameterSpec(True), "den": ParameterSpec(True)},
    "pendula": {
        "lengths": ParameterSpec(True, units=_LENGTH),
        "g": ParameterSpec(False, required=False, units={"m/s^2": 1.0}),
        "zeta": ParameterSpec(False, required=False, units={"1": 1.0}),
    },
    "mass_spring_chain": {
        "masses": ParameterSpec(True, units={"kg": 1.0}),
        "springs": ParameterSpec(True, units={"N/m": 1.0}),
        "dampers": ParameterSpec(True, required=False, units={"N*s/m": 1.0}),
    },
    "sprung_masses": {
        "masses": ParameterSpec(True, units={"kg": 1.0, "g": 1e-3}),
        "stiffnesses": ParameterSpec(True, units={"N/m": 1.0}),
        "dampers": ParameterSpec(True, required=False, units={"N*s/m": 1.0}),
    },
}
KINDS = tuple(PARAMETER_SPECS)


def _build(kind: str, p: dict, name: str, input_name: str, u_max) -> Plant:
    if kind in ("rigid_flexible", "voice_coil_flexible"):
        lengths = {len(p["f"]), len(p["zeta"]), len(p["b4"])}
        if len(lengths) != 1:
            raise ValueError(f"parameters f, zeta and b4 must have one entry per mode, got lengths "
                             f"{len(p['f'])}, {len(p['zeta'])}, {len(p['b4'])}")
        damping = p["Kt"] ** 2 / (p["R"] * p["J"]) if kind == "voice_coil_flexible" else p.get("rigid_damping", 0.0)
        plant = library.rigid_flexible(p["b2"], list(zip(p["f"], p["zeta"], p["b4"])), damping, u_max=u_max,
                                       name=name, input_name=input_name)
        return plant
    if kind == "transfer_function":
        return library.transfer_function(p["num"], p["den"], name=name, input_name=input_name)
    if kind == "pendula":
        return library.pendula(p["lengths"], p.get("g", library.STANDARD_GRAVITY), p.get("zeta", 0.0), name=name)
    if kind == "sprung_masses":
        return library.sprung_masses(p["masses"], p["stiffnesses"], p.get("dampers"), name=name)
    return library.mass_spring_chain(p["masses"], p["springs"], p.get("dampers"), name=name)


def _finite(value, where):
    # An integer too large for a double (TOML integers have any size in tomllib) is not finite either.
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(_as_float(value)):
        raise ValueError(f"{where} must be a finite number, got {_shown(value)}")
    return float(value)


def _as_float(value) -> float:
    try:
        return float(value)
    except OverflowError:
        return math.inf


def _shown(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else f"{text[:40]}... ({len(text)} characters)"


def _identifier(value, where) -> str:
    """A name that becomes a C identifier, an FMI variable name and a file name: [A-Za-z_][A-Za-z0-9_]*."""
    if not isinstance(value, str) or not IDENTIFIER.fullmatch(value):
        raise ValueError(f"{where} must be an identifier ([A-Za-z_][A-Za-z0-9_]*, e.g. disk_drive), "
                         f"got {_shown(value)}")
    return value


def _parameter(raw, spec: ParameterSpec, where: str) -> Parameter:
    """The parameter as written in the file (``_converted`` gives it in the constructor's units)."""
    if not isinstance(raw, dict) or "value" not in raw:
        raise ValueError(f"{where} must be a table {{ value = ..., unit = \"...\" }}, got {raw!r}")
    extra = set(raw) - {"value", "unit", "description"}
    if extra:
        raise ValueError(f"{where} has unknown field(s) {sorted(extra)}; allowed: value, unit, description")
    if "description" in raw:
        check_text(raw["description"], f"{where}.description")
    unit = raw.get("unit")
    if not isinstance(unit, str) or not unit.strip():
        raise ValueError(f"{where}.unit is missing: every parameter needs a unit"
                         + (f" (one of {sorted(spec.units)})" if spec.units else ""))
    if spec.units is not None and unit not in spec.units:
        raise ValueError(f"{where}.unit must be one of {sorted(spec.units)}, got {unit!r}")
    check_text(unit, f"{where}.unit")
    value = raw["value"]
    if spec.array:
        if not isinstance(value, list) or not value:
            raise ValueError(f"{where}.value must be a non-empty list of numbers, got {value!r}")
        return Parameter(tuple(_finite(v, f"{where}.value[{i}]") for i, v in enumerate(value)), unit)
    return Parameter(_finite(value, f"{where}.value"), unit)


def _signals(data, key, count, source):
    table = data.get(key)
    if not isinstance(table, dict) or not table:
        raise ValueError(f"{source}: [{key}] must be a table naming the {key} with their units")
    for signal, fields in table.items():
        _identifier(signal, f"{source}: the name of {key}.{signal}")
        if not isinstance(fields, dict) or not isinstance(fields.get("unit"), str) or not fields["unit"].strip():
            raise ValueError(f"{source}: {key}.{signal}.unit is missing: every signal needs a unit")
        check_text(fields["unit"], f"{source}: {key}.{signal}.unit")
        if "description" in fields:
            check_text(fields["description"], f"{source}: {key}.{signal}.description")
        extra = set(fields) - {"unit", "max", "description"}
        if extra or (key == "outputs" and "max" in fields):
            allowed = "unit, max, description" if key == "inputs" else "unit, description"
            raise ValueError(f"{source}: {key}.{signal} has unknown field(s) {sorted(extra | ({'max'} & set(fields)))}; "
                             f"allowed: {allowed}")
    if count is not None and len(table) != count:
        raise ValueError(f"{source}: [{key}] lists {len(table)} signal(s) {list(table)}, the kind defines {count}")
    return table


def _read(text: str, source: str):
    """(the plant at the scheduling start value, the ScheduledPlant or None) of a model file's text."""
    try:
        data = parse_nested(tomllib.loads, text, source)
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"{source}: not valid TOML: {error}") from None
    allowed = {"name", "kind", "description", "source", "parameters", "inputs", "outputs", "scheduling"}
    extra = set(data) - allowed
    if extra:
        raise ValueError(f"{source}: unknown top-level field(s) {sorted(extra)}; allowed: {sorted(allowed)}")
    kind = data.get("kind")
    if not isinstance(kind, str) or kind not in PARAMETER_SPECS:
        raise ValueError(f"{source}: kind must be one of {list(PARAMETER_SPECS)}, got {_shown(kind)}")
    name = _identifier(data.get("name", os.path.splitext(os.path.basename(source))[0]), f"{source}: name")
    for key in ("description", "source"):
        if key in data:
            check_text(data[key], f"{source}: {key}")
    specs = PARAMETER_SPECS[kind]
    raw_parameters = data.get("parameters")
    if not isinstance(raw_parameters, dict):
        raise ValueError(f"{source}: [parameters] table is missing")
    unknown = set(raw_parameters) - set(specs)
    if unknown:
        raise ValueError(f"{source}: unknown parameter(s) {sorted(unknown)} for kind {kind!r}; "
                         f"allowed: {sorted(specs)}")
    missing = [key for key, spec in specs.items() if spec.required and key not in raw_parameters]
    if missing:
        raise ValueError(f"{source}: missing parameter(s) {missing} for kind {kind!r}")
    written = {key: _parameter(raw, specs[key], f"{source}: parameters.{key}") for key, raw in raw_parameters.items()}

    inputs = _signals(data, "inputs", 1, source)
    input_name = next(iter(inputs))
    u_max = inputs[input_name].get("max")
    if u_max is not None:
        u_max = _finite(u_max, f"{source}: inputs.{input_name}.max")
        if u_max <= 0:
            raise ValueError(f"{source}: inputs.{input_name}.max must be > 0, got {u_max!r}")
    build = functools.partial(_assemble, kind=kind, name=name, input_name=input_name, u_max=u_max, data=data,
                              source=source)
    plant = build(written, where="parameters")
    if "scheduling" not in data:
        return plant, None
    scheduling = _scheduling(data["scheduling"], written, (input_name, *plant.outputs), source)
    for end in (scheduling.minimum, scheduling.maximum):  # affine laws: valid at both ends is valid between
        build(scheduling.parameters_at(written, end), where=f"parameters at {scheduling.name} = {end:g}")
    return plant, ScheduledPlant(plant, scheduling, functools.partial(build, where="parameters"))


def _assemble(written: dict, *, kind, name, input_name, u_max, data, source, where) -> Plant:
    """The plant of ``kind`` with the parameters as ``written`` in the file (converted to the
    constructor's units), named as the file names its signals."""
    specs = PARAMETER_SPECS[kind]
    values = {key: _converted(parameter, specs[key]) for key, parameter in written.items()}
    try:
        plant = _build(kind, values, name, input_name, u_max)
    except ValueError as error:
        raise ValueError(f"{source}: {where}: {error}") from None
    outputs = _signals(data, "outputs", len(plant.outputs), source)
    return Plant(plant.A, plant.B, plant.C, plant.D, inputs=(input_name,), outputs=tuple(outputs),
                 states=plant.states, parameters=written,
                 limits={input_name: u_max} if u_max is not None else {}, name=name, kind=kind)


def _converted(parameter: Parameter, spec: ParameterSpec):
    factor = spec.units[parameter.unit] if spec.units is not None else 1.0
    if isinstance(parameter.value, tuple):
        return tuple(factor * v for v in parameter.value)
    return factor * parameter.value


_SCHEDULING_FIELDS = {"name", "unit", "min", "max", "start", "description", "per_unit"}


def _scheduling(raw, written: dict, signals, source) -> SchedulingInput:
    """The [scheduling] table (see ``shapefmu.plants.scheduling``), checked against the parameters."""
    where = f"{source}: scheduling"
    if not isinstance(raw, dict):
        raise ValueError(f"{where} must be a table with fields {sorted(_SCHEDULING_FIELDS)}")
    extra = set(raw) - _SCHEDULING_FIELDS
    if extra:
        raise ValueError(f"{where} has unknown field(s) {sorted(extra)}; allowed: {sorted(_SCHEDULING_FIELDS)}")
    name = _identifier(raw.get("name"), f"{where}.name")
    if name in signals:
        raise ValueError(f"{where}.name {name!r} is already a signal of the plant ({', '.join(signals)})")
    unit = raw.get("unit")
    if not isinstance(unit, str) or not unit.strip():
        raise ValueError(f"{where}.unit is missing: the scheduling input needs a unit")
    check_text(unit, f"{where}.unit")
    if "description" in raw:
        check_text(raw["description"], f"{where}.description")
    low, high = (_finite(raw.get(key), f"{where}.{key}") for key in ("min", "max"))
    if not low < high:
        raise ValueError(f"{where}: min must be < max, got min {low!r} and max {high!r}")
    start = _finite(raw.get("start", low), f"{where}.start")
    if not low <= start <= high:
        raise ValueError(f"{where}.start must be in [min, max] = [{low:g}, {high:g}], got {start!r}")
    per_unit = raw.get("per_unit")
    if not isinstance(per_unit, dict) or not per_unit:
        raise ValueError(f"{where}.per_unit must be a table naming the parameters that depend on {name} "
                         f"(e.g. per_unit = {{ masses = [1.0] }})")
    rates = {}
    for key, rate in per_unit.items():
        if key not in written:
            raise ValueError(f"{where}.per_unit.{key}: no such parameter in [parameters]; "
                             f"parameters: {sorted(written)}")
        value = written[key].value
        if isinstance(value, tuple):
            if not isinstance(rate, list) or len(rate) != len(value):
                raise ValueError(f"{where}.per_unit.{key} must be a list of {len(value)} numbers, one per entry of "
                                 f"parameters.{key}, got {_shown(rate)}")
            rates[key] = tuple(_finite(r, f"{where}.per_unit.{key}[{i}]") for i, r in enumerate(rate))
        else:
            rates[key] = _finite(rate, f"{where}.per_unit.{key}")
    return SchedulingInput(name, unit, low, high, start, rates, raw.get("description", ""))


def loads(text: str, source: str = "<string>") -> Plant:
    """Parse a plant model from TOML text; ``source`` names the file in error messages. A model with a
    scheduling input is read as the plant at its start value (``loads_scheduled`` for the rest).

    Examples
    --------
    >>> text = '''
    ... kind = "rigid_flexible"
    ... [parameters]
    ... b2 = { value = 2.0, unit = "1/(N*s^2)" }
    ... f = { value = [5.0], unit = "Hz" }
    ... zeta = { value = [0.02], unit = "1" }
    ... b4 = { value = [-2.0], unit = "1/(N*s^2)" }
    ... [inputs]
    ... force = { unit = "N", max = 1.0 }
    ... [outputs]
    ... x = { unit = "m" }
    ... deflection = { unit = "m" }
    ... '''
    >>> plant = loads(text, "example.toml")
    >>> plant.name, plant.inputs, dict(plant.limits), round(plant.flexible_modes()[0][0] / 6.283185307179586, 9)
    ('example', ('force',), {'force': 1.0}, 5.0)
    """
    return _read(text, source)[0]


def loads_scheduled(text: str, source: str = "<string>") -> ScheduledPlant:
    """Parse a plant model that declares a [scheduling] table (``shapefmu.plants.scheduling``).

    Examples
    --------
    >>> text = '''
    ... kind = "sprung_masses"
    ... [parameters]
    ... masses = { value = [1.0], unit = "kg" }
    ... stiffnesses = { value = [400.0], unit = "N/m" }
    ... [inputs]
    ... acceleration = { unit = "m/s^2" }
    ... [outputs]
    ... carriage = { unit = "m" }
    ... deflection = { unit = "m" }
    ... acceleration_1 = { unit = "m/s^2" }
    ... [scheduling]
    ... name = "added_mass"
    ... unit = "kg"
    ... min = 0.0
    ... max = 3.0
    ... per_unit = { masses = [1.0] }
    ... '''
    >>> plant = loads_scheduled(text, "example.toml")
    >>> [round(w, 9) for w, _ in plant.flexible_modes_at(3.0)]  # sqrt(400 / (1 + 3)) rad/s
    [10.0]
    """
    scheduled = _read(text, source)[1]
    if scheduled is None:
        raise ValueError(f"{source}: declares no [scheduling] table: its parameters depend on no input")
    return scheduled


def load_scheduled(path) -> ScheduledPlant:
    """Read a model file with a scheduling input, or the shipped model of that name (``printer_bed``).

    Examples
    --------
    >>> import math
    >>> bed = load_scheduled("printer_bed")  # 1 kg at 30 Hz, zeta 0.05, gaining up to 300 g
    >>> [(round(w / (2 * math.pi), 4), round(z, 5)) for w, z in bed.flexible_modes_at(300.0)]
    [(26.3117, 0.04385)]

    30 / sqrt(1.3) = 26.3117 Hz and 0.05 / sqrt(1.3) = 0.04385: the damper stays, the mass grows.
    """
    path = os.fspath(shipped.find(path, (".toml",)))
    return loads_scheduled(read_text_file(path, "plant model"), source=path)


def load(path) -> Plant:
    """Read a plant model file (``models/*.toml``), or the shipped model of that name (``disk_drive``).

    Examples
    --------
    >>> plant = load("disk_drive")  # the shipped models/disk_drive.toml
    >>> plant.kind, plant.n_states, plant.parameters["f"]
    ('rigid_flexible', 6, Parameter(value=(2000.0, 3000.0), unit='Hz'))
    """
    path = os.fspath(shipped.find(path, (".toml",)))
    return loads(read_text_file(path, "plant model"), source=path)


def as_plant(system) -> Plant:
    """A ``Plant`` from a plant, a python-control LTI, or a path to a model file.

    Examples
    --------
    >>> import control
    >>> as_plant(control.tf([1.0], [1.0, 0.0, 100.0])).n_states  # a python-control LTI
    2
    >>> as_plant("disk_drive").name  # a model file, or a shipped model's name
    'disk_drive'
    """
    if isinstance(system, Plant):
        return system
    if isinstance(system, (control.StateSpace, control.TransferFunction)):
        return Plant.from_lti(system)
    if isinstance(system, str) or hasattr(system, "__fspath__"):
        return load(system)
    raise ValueError(f"expected a Plant, a python-control LTI or a model file path, got {type(system).__name__}")


def describe(path_or_plant) -> str:
    """The text of ``shapefmu plant show FILE``: the plant's signals, parameters and modes (of a model
    file with a scheduling input: at its start value, then the input and the lowest mode along it).

    Examples
    --------
    >>> for line in describe("disk_drive").splitlines()[:3]:
    ...     print(line)
    plant disk_drive (kind rigid_flexible), 6 states
      input  voltage  |u| <= 11
      outputs position, deflection_1, deflection_2
    """
    scheduled = None
    if isinstance(path_or_plant, str) or hasattr(path_or_plant, "__fspath__"):
        path = os.fspath(shipped.find(path_or_plant, (".toml",)))
        plant, scheduled = _read(read_text_file(path, "plant model"), path)
    else:
        plant = as_plant(path_or_plant)
    lines = [f"plant {plant.name} (kind {plant.kind}), {plant.n_states} states"]
    for signal in plant.inputs:
        limit = plant.limits.get(signal)
        lines.append(f"  input  {signal}" + (f"  |u| <= {limit:g}" if limit is not None else ""))
    lines.append("  outputs " + ", ".join(plant.outputs))
    for key, parameter in plant.parameters.items():
        value = parameter.value
        text = ", ".join(f"{v:g}" for v in value) if isinstance(value, tuple) else f"{value:g}"
        lines.append(f"  {key} = {text} [{parameter.unit}]")
    lines.append(f"  {'f [Hz]':>12} {'omega [rad/s]':>14} {'zeta':>8} {'participation':>14}  pole")
    for mode in plant.modes():
        zeta = "-" if math.isnan(mode.zeta) else f"{mode.zeta:.4g}"
        lines.append(f"  {mode.hz:12.6g} {mode.omega:14.6g} {zeta:>8} {mode.participation:14.4g}  "
                     f"{mode.pole.real:.6g}{mode.pole.imag:+.6g}j")
    if scheduled is not None:
        lines.extend(scheduled.describe())
    return "\n".join(lines)
