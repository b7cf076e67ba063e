"""Package a native C twin of an FMU kind: the one place that turns a model part into an archive.

A native twin (the Shaper and ShapeFilter of ``sampled``, the EKF tuner of ``ekf_tuner``, ...) is
the generic FMI layer of its version (``c/fmi2_layer*.c`` or ``c/fmi3_layer*.c``), the model part's
own C files and a generated ``model.c`` (its variables' start values and what was designed at build
time). Its modelDescription.xml is written from the kind's interface (``shapefmu.fmi.kinds``), the
one the pythonfmu FMU declares, so an SSP can bind either FMU.

``write_native_fmu`` copies the C files into ``sources/``, derives the GUID from all of them (the
generated file included, written first without the GUID), writes ``buildDescription.xml``, compiles
every platform's binary (``compile.build_binaries``), the model description and the documentation,
and zips the archive.
"""

from __future__ import annotations

import hashlib
import sys
import tempfile
import uuid
from pathlib import Path

from shapefmu import __version__
from shapefmu.fmi.description import ModelDescription, fmi3, now, write
from shapefmu.fmi.documentation import add_documentation
from shapefmu.fmi.kinds import designed
from shapefmu.fmi.native.compile import build_binaries, build_description, copy_c_files, write_layer, zip_fmu
from shapefmu.runtime.shaper_designs import CLOSED_FORM

MODEL_SOURCE = "model.c"
TYPE_ORDER = ("Real", "Integer", "Boolean", "String")
CATEGORIES = (("logStatusError", "Errors: bad parameters, non-finite inputs, calls out of order"),
              ("logAll", "Everything else (debug logging)"))
ROLES = {("parameter", "fixed"): "ROLE_PARAMETER_FIXED", ("parameter", "tunable"): "ROLE_PARAMETER_TUNABLE",
         ("input", "continuous"): "ROLE_INPUT", ("output", "continuous"): "ROLE_COMPUTED"}


def number_by_type(variables) -> list:
    """``variables`` in the order the generic layer indexes values (model.h): Real, Integer,
    Boolean, String, each in declaration order; value reference = position."""
    return sorted(variables, key=lambda v: TYPE_ORDER.index(v.type))


def designed_twin(name: str, start_values: dict):
    """(model, variables, values) of the native twin of kind ``name`` with ``start_values``: the kind's
    model designed at build time, its variables numbered by type (``number_by_type``) and their values
    (name -> value) after the design."""
    model = designed(name, start_values)
    return model, number_by_type(model.interface.variables), dict(model.values)


def c_string(text: str) -> str:
    """A C string literal of ``text``: printable ASCII without quotes or backslashes only."""
    if len(text) > 63 or any(not (32 <= ord(c) < 127) or c in '"\\' for c in text):
        raise ValueError(f"a string parameter must be at most 63 printable ASCII characters without quotes or "
                         f"backslashes, got {text!r}")
    return f'"{text}"'


def c_doubles(name: str, values) -> str:
    """A static const double array ``name`` of ``values``, each exact (repr), four to a line."""
    rows = ",\n    ".join(", ".join(repr(float(v)) for v in values[i:i + 4]) for i in range(0, len(values), 4))
    return f"static const double {name}[] = {{\n    {rows or '0.0'}\n}};"


def variable_rows(variables, values: dict, meaning_of) -> str:
    """The C rows of a VariableTable (``c/model.h``): each of the numbered ``variables`` with its role,
    its meaning ``meaning_of(name)`` (an enumerator of the model part) and its start value from ``values``."""
    rows = []
    for var in variables:
        value = values[var.name]
        start, string = ("0.0", c_string(value)) if var.type == "String" else (repr(float(value)), "NULL")
        rows.append(f'    {{"{var.name}", {ROLES[(var.causality, var.variability)]}, {meaning_of(var.name)}, {start}, '
                    f'{string}}},')
    return "\n".join(rows)


def table_fields(variables, guid: str) -> str:
    """The GUID and the counts of a VariableTable (``c/model.h``) of the numbered ``variables``."""
    return f'"{guid}", ' + ", ".join(str(sum(v.type == t for v in variables)) for t in TYPE_ORDER)


def twin_variables_c(table: str, variables, values: dict, meaning_of, guid: str) -> str:
    """C of the VariableTable ``table`` of a twin's model part (``c/model.h``, ``c/twin_variables.h``)."""
    return (f"static const VariableRow {table}_rows[] = {{\n{variable_rows(variables, values, meaning_of)}\n}};\n\n"
            f"const VariableTable {table} = {{{table_fields(variables, guid)}, {table}_rows}};\n")


def closed_form_only(name: str, values: dict, max_order: int = 62) -> None:
    """Refuse the start ``values`` of a twin ``name`` that re-designs in C while it runs: its ``kind``
    must be one c/shaper_designs.c designs in closed form, its ``n`` at most ``max_order`` (64 impulses)."""
    if values["kind"] not in CLOSED_FORM:
        raise ValueError(f"kind must be one of {', '.join(CLOSED_FORM)} for the native {name} (it re-designs in C, in "
                         f"closed form), got {values['kind']!r}; the pythonfmu {name} takes every kind")
    if values["n"] > max_order:
        raise ValueError(f"n must be an integer in [0, {max_order}] for the native {name}, got {values['n']}")


def write_table_twin(name: str, out_path, designed, header: str, table: str, meanings: dict, sources, headers,
                     note: str, fmi_version: str = "2.0", clock: bool = False) -> Path:
    """Write the native twin ``name`` whose generated model.c is its variable table alone (every parameter
    is used by the C at the exit of initialisation): ``designed`` is ``designed_twin``'s (model,
    variables, values); ``table`` the VariableTable the part's ``header`` declares, whose enumerators are
    ``meanings`` (variable name -> enumerator, every variable); ``note`` what the documentation adds
    about the native FMU."""
    model, variables, values = designed
    if sorted(v.name for v in variables) != sorted(meanings):
        raise RuntimeError(f"the {name}'s variables {[v.name for v in variables]} are not those c/{header} knows: "
                           f"{list(meanings)}")

    def model_c(guid):
        return f"""/* Model part of the native {name} FMU, generated by shapefmu.fmi.native: do not edit.
 * Its variables by value reference and their start values. */
#include "{header}"

{twin_variables_c(table, variables, values, meanings.get, guid)}"""

    about = f"{sys.modules[type(model).__module__].__doc__}\n\n{note}"
    return write_native_fmu(name, out_path, model, variables, values, model.output_dependencies(), sources, headers,
                            model_c, about, fmi_version=fmi_version, clock=clock)


def clock_interval(name: str, values: dict, fmi_version: str) -> float:
    """The interval of the input clock of twin ``name`` built with ``--clock``: its sample period
    (a ShapeFilter's Ts_used, which adjust_Ts may have moved off Ts, else Ts)."""
    if fmi_version != "3.0":
        raise ValueError(f"--clock needs --fmi-version 3.0 (clocks are FMI 3.0's), got --fmi-version {fmi_version}")
    period = values.get("Ts_used", values.get("Ts"))
    if period is None:
        raise ValueError(f"--clock: the {name} FMU has no sample period Ts for its clock to tick at (it is not sampled)")
    return float(period)


def write_native_fmu(name: str, out_path, model, variables, values: dict, dependencies: dict, c_sources,
                     c_headers, model_c, about: str, log_categories=CATEGORIES, fmi_version: str = "2.0",
                     clock: bool = False) -> Path:
    """Write the native FMU ``name`` to ``out_path`` and return the path.

    ``model`` is the kind's designed model (its interface's description and its DefaultExperiment);
    ``variables`` the numbered variables (``number_by_type``) with their ``values`` (name -> value:
    start values of the non-outputs, the outputs' values after the design); ``dependencies`` maps each
    output to the inputs it feeds through from; ``c_sources`` and ``c_headers`` the model part's files
    of ``fmi/native/c`` (the generic layer is added here); ``model_c(guid)`` the text of the generated
    model.c; ``about`` the documentation's account of what the FMU does; ``fmi_version`` "2.0" or "3.0"
    picks the generic layer and the model description writer (FMI 3.0: array parameters); ``clock``
    (FMI 3.0) declares the periodic input clock of the sample period Ts (``c/fmi3_layer_clock.c``).
    """
    out_path = Path(out_path)
    interval = clock_interval(name, values, fmi_version) if clock else 0.0
    with tempfile.TemporaryDirectory(prefix="shapefmu_native_") as tmp:
        root = Path(tmp)
        sources = root / "sources"
        sources.mkdir()
        copy_c_files(sources, (*c_sources, *c_headers))
        # once each: the FMI 3.0 layer has the sample clock a sampled model part lists too
        c_files = list(dict.fromkeys([*write_layer(sources, fmi_version, interval), *c_sources, MODEL_SOURCE]))
        digest = hashlib.md5(model_c("").encode())
        for file in sorted(p.name for p in sources.iterdir()):
            digest.update((sources / file).read_bytes())
        guid = "{" + str(uuid.UUID(digest.hexdigest())) + "}"
        (sources / MODEL_SOURCE).write_text(model_c(guid), encoding="utf-8")
        (sources / "buildDescription.xml").write_text(build_description(name, c_files), encoding="utf-8")
        note = build_binaries(root, name, c_files, f"native {name}", fmi_version)
        if note:
            print(note, file=sys.stderr)
        description = ModelDescription(
            model_name=name, identifier=name, guid=guid,
            description=f"{model.interface.description} (native C, designed at build time)",
            generation_tool=f"shapefmu {__version__} native C generator",
            variables=tuple(v.with_start(None if v.causality == "output" else values[v.name]) for v in variables),
            dependencies=dependencies, log_categories=log_categories, generation_date=now(),
            experiment=model.experiment(), source_files=tuple(c_files) if fmi_version == "2.0" else (),
            clock_interval=interval)
        (root / "modelDescription.xml").write_text(write(description, fmi_version), encoding="utf-8")
        if fmi_version == "3.0":
            (root / "terminalsAndIcons").mkdir()
            (root / "terminalsAndIcons" / "terminalsAndIcons.xml").write_text(
                fmi3.terminals_and_icons(model.interface.command_in, model.interface.command_out), encoding="utf-8")
        add_documentation(root, about, model.picture())
        zip_fmu(root, out_path)
    return out_path
