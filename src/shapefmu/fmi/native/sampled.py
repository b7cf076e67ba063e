"""Native C Shaper and ShapeFilter FMUs: the pythonfmu slaves' variables and design, run in C.

``build_native_fmu("Shaper" | "ShapeFilter", out_path, **start_values) -> Path`` writes an FMI 2.0
Co-Simulation FMU that needs no Python on the host: the generic FMI 2.0 layer (``c/fmi2_layer*.c``),
the sampled filters' part of it (``c/sampled_fmi2.c``, ``c/sampled_fir.c``, ``c/shaper_designs.c``)
and a generated ``model.c`` of a few dozen lines (its variables, start values and design),
packaged by ``kernel_fmu.write_native_fmu`` (sources/, binaries for every platform, documentation).

The design is made here, at build time, by the same code the pythonfmu FMU runs at initialisation
(``fmi.python.builder.designed_slave``: any kind, single and multi-mode), and stored as parameters:
``impulse_time[i]`` (s) and ``impulse_amplitude[i]`` of a Shaper, ``tap[i]`` of a ShapeFilter, with
the sampling period. They are tunable. The variables of the pythonfmu FMU keep their names, types and
start values, so an SSP can bind either FMU: a closed-form Shaper (zv, zvd, zvdd, zv_dn, mzv)
re-designs in C when kind, n, n_modes, f[i] or zeta[i] change before initialisation (as many
impulses as this FMU holds: ``impulses_per_mode ** n_modes`` of its build kind), a Shaper's ``Ts``
may change (the impulses are re-gridded), and every other design parameter keeps its build value
(setting another one is refused with fmi2Error and a message saying to rebuild).

Sampled semantics: the absolute grid t0 + k Ts of DESIGN.md ("Sampled FMUs take their samples on
the absolute grid"), as ``c/sampled_fir.c`` documents: any step size, outputs held between samples,
feed-through on the grid, at most 10^7 samples per step.
"""

from __future__ import annotations

import sys
from pathlib import Path

from shapefmu.fmi.native.kernel_fmu import ROLES, c_string, number_by_type, write_native_fmu
from shapefmu.fmi.python.builder import designed_slave
from shapefmu.fmi.python.slave_base import Variable

SOURCES = ("sampled_fmi2.c", "sampled_fir.c", "sample_clock.c", "shaper_designs.c")
HEADERS = ("sampled_model.h", "sampled_fir.h", "sample_clock.h", "shaper_designs.h")
NATIVE_NOTE = ("This FMU is the native C twin of the pythonfmu FMU of the same name: the same variables and "
               "sampled semantics, no Python needed. Its design was made at build time and is stored in its "
               "parameters (impulse_time[i] and impulse_amplitude[i], or tap[i]); sources/ holds its C code.")
# Kinds the C part re-designs, with their impulses per mode (n = the derivative order of zv_dn).
CLOSED_FORM = {"zv": lambda n: 2, "zvd": lambda n: 3, "zvdd": lambda n: 4, "zv_dn": lambda n: n + 2, "mzv": lambda n: 3}
# Bounds on what one FMU declares (each entry is a ScalarVariable of its modelDescription.xml).
MAX_IMPULSES = 4096
MAX_TAPS = 100_000


def _meaning(model: str, name: str) -> tuple[str, int]:
    """(SampledMeaning, 0-based index) of variable ``name`` (sampled_model.h)."""
    base, _, index = name.partition("[")
    i = int(index.rstrip("]")) - 1 if index else 0
    common = {"u": "MEANS_INPUT", "y": "MEANS_OUTPUT", "u0": "MEANS_REST", "Ts_used": "MEANS_PERIOD_USED",
              "impulse_time": "MEANS_IMPULSE_TIME", "impulse_amplitude": "MEANS_IMPULSE_AMPLITUDE", "tap": "MEANS_TAP"}
    shaper = {"Ts": "MEANS_PERIOD", "kind": "MEANS_KIND", "n": "MEANS_ORDER", "n_modes": "MEANS_MODES",
              "f": "MEANS_FREQUENCY", "zeta": "MEANS_DAMPING", "vtol": "MEANS_TOLERANCE"}
    meanings = {**common, **shaper} if model == "Shaper" else common
    return meanings.get(base, "MEANS_BUILD_VALUE"), i


def _design_variables(slave) -> tuple[list[Variable], dict, int, bool]:
    """The design parameters to add (impulses or taps), their values, the capacity and whether the
    Shaper's kind re-designs in C."""
    values, extra = {}, []

    def add(name, unit, description, value):
        extra.append(Variable(name, 0, "Real", "parameter", "tunable", float(value), unit, description))
        values[name] = float(value)

    if slave.model_name == "Shaper":
        times, amplitudes = slave.design
        kind, closed = slave.values["kind"], slave.values["kind"] in CLOSED_FORM
        capacity = CLOSED_FORM[kind](slave.values["n"]) ** slave.values["n_modes"] if closed else len(times)
        if capacity > MAX_IMPULSES:
            raise ValueError(f"a native {kind} shaper for {slave.values['n_modes']} modes holds {capacity} impulses; "
                             f"at most {MAX_IMPULSES}")
        padding = capacity - len(times)  # unused entries of a closed-form shaper: amplitude 0 at t = 0
        for i, t in enumerate([*times, *[0.0] * padding], 1):
            add(f"impulse_time[{i}]", "s", f"time of impulse {i} (tunable; re-designed in C for closed-form kinds)", t)
        for i, a in enumerate([*amplitudes, *[0.0] * padding], 1):
            add(f"impulse_amplitude[{i}]", "1", f"amplitude of impulse {i} (tunable)", a)
        return extra, values, capacity, closed
    taps = slave.taps
    if len(taps) > MAX_TAPS:
        raise ValueError(f"a native shape filter holds at most {MAX_TAPS} taps, this design has {len(taps)}: "
                         f"use a longer Ts")
    for i, w in enumerate(taps, 1):
        add(f"tap[{i}]", "1", f"tap {i} of the FIR filter, at delay {i - 1} samples (tunable)", w)
    return extra, values, len(taps), False


def _model_c(slave, variables, values, guid, capacity, closed, feedthrough) -> str:
    rows = []
    for var in variables:
        meaning, index = _meaning(slave.model_name, var.name)
        value = values.get(var.name, 0.0)
        start, string = ("0.0", c_string(value)) if var.type == "String" else (repr(float(value)), "NULL")
        role = ROLES[(var.causality, var.variability)]
        rows.append(f'    {{"{var.name}", {role}, {meaning}, {index}, {start}, {string}}},')
    counts = [sum(v.type == t for v in variables) for t in ("Real", "Integer", "Boolean", "String")]
    body = "\n".join(rows)
    return f"""/* Model part of the native {slave.model_name} FMU, generated by shapefmu.fmi.native.sampled: do not edit.
 * Its variables by value reference, their start values and the design made at build time. */
#include "sampled_model.h"

static const SampledVariable variables[] = {{
{body}
}};

const SampledModel sampled_model = {{
    "{guid}", {int(slave.model_name == "Shaper")}, {int(closed)}, {int(feedthrough)}, {slave_max_modes(slave)},
    {capacity}, {repr(float(slave.values.get("Ts_used", 0.0)))},
    {counts[0]}, {counts[1]}, {counts[2]}, {counts[3]}, variables
}};
"""


def slave_max_modes(slave) -> int:
    """How many f[i], zeta[i] pairs the slave declares."""
    return sum(1 for v in slave.variables if v.name.startswith("f["))


def build_native_fmu(name: str, out_path, *, fmi_version: str = "2.0", clock: bool = False, **start_values) -> Path:
    """Build the native ``name`` ("Shaper" or "ShapeFilter") FMU with ``start_values`` to ``out_path``."""
    if name not in ("Shaper", "ShapeFilter"):
        raise ValueError(f"name must be Shaper or ShapeFilter, got {name!r}")
    slave = designed_slave(name, start_values)
    extra, values, capacity, closed = _design_variables(slave)
    values.update(slave.values)
    numbered = number_by_type([*slave.variables, *extra])
    dependencies = {"y": ["u"]} if name == "Shaper" else slave.output_dependencies()
    feedthrough = "u" in dependencies["y"]
    about = f"{sys.modules[type(slave).__module__].__doc__}\n\n{NATIVE_NOTE}"
    return write_native_fmu(name, out_path, slave, numbered, values, dependencies, SOURCES, HEADERS,
                            lambda guid: _model_c(slave, numbered, values, guid, capacity, closed, feedthrough), about,
                            fmi_version=fmi_version, clock=clock)



def build_native_shaper(out_path, *, fmi_version: str = "2.0", clock: bool = False, **start_values) -> Path:
    """The native Shaper FMU (``build_native_fmu("Shaper", ...)``)."""
    return build_native_fmu("Shaper", out_path, fmi_version=fmi_version, clock=clock, **start_values)


def build_native_shape_filter(out_path, *, fmi_version: str = "2.0", clock: bool = False, **start_values) -> Path:
    """The native ShapeFilter FMU (``build_native_fmu("ShapeFilter", ...)``)."""
    return build_native_fmu("ShapeFilter", out_path, fmi_version=fmi_version, clock=clock, **start_values)
