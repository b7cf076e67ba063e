"""Native C Shaper and ShapeFilter FMUs: the kinds' variables and design, run in C.

``build_native_fmu("Shaper" | "ShapeFilter", out_path, **start_values) -> Path`` writes an FMI 2.0
Co-Simulation FMU that needs no Python on the host: the generic FMI 2.0 layer (``c/fmi2_layer*.c``),
the sampled filters' model part (``c/sampled_part.c``, ``c/sampled_fir.c``, ``c/shaper_designs.c``)
and a generated ``model.c`` of a few dozen lines (its variables, start values and design),
packaged by ``kernel_fmu.write_native_fmu`` (sources/, binaries for every platform, documentation).

The design is made here, at build time, by the same code the pythonfmu FMU runs at initialisation
(the kind's model, ``shapefmu.fmi.kinds``: any shaper kind, single and multi-mode), and stored as parameters:
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

from shapefmu.fmi.kinds import designed
from shapefmu.fmi.kinds.interface import Variable, parameter
from shapefmu.fmi.native.kernel_fmu import number_by_type, table_fields, variable_rows, write_native_fmu
from shapefmu.runtime.shaper_designs import CLOSED_FORM

SOURCES = ("sampled_part.c", "sampled_fir.c", "sample_clock.c", "shaper_designs.c")
HEADERS = ("sampled_model.h", "sampled_fir.h", "sample_clock.h", "shaper_designs.h")
NATIVE_NOTE = ("This FMU is the native C twin of the pythonfmu FMU of the same name: the same variables and "
               "sampled semantics, no Python needed. Its design was made at build time and is stored in its "
               "parameters (impulse_time[i] and impulse_amplitude[i], or tap[i]); sources/ holds its C code.")
# Bounds on what one FMU declares (each entry is a ScalarVariable of its modelDescription.xml).
MAX_IMPULSES = 4096
MAX_TAPS = 100_000


def _meaning(model: str, name: str) -> str:
    """The SampledMeaning of variable ``name`` (sampled_model.h)."""
    base = name.partition("[")[0]
    common = {"u": "MEANS_INPUT", "y": "MEANS_OUTPUT", "u0": "MEANS_REST", "Ts_used": "MEANS_PERIOD_USED",
              "impulse_time": "MEANS_IMPULSE_TIME", "impulse_amplitude": "MEANS_IMPULSE_AMPLITUDE", "tap": "MEANS_TAP"}
    shaper = {"Ts": "MEANS_PERIOD", "kind": "MEANS_KIND", "n": "MEANS_ORDER", "n_modes": "MEANS_MODES",
              "f": "MEANS_FREQUENCY", "zeta": "MEANS_DAMPING", "vtol": "MEANS_TOLERANCE"}
    meanings = {**common, **shaper} if model == "Shaper" else common
    return meanings.get(base, "MEANS_BUILD_VALUE")


def _design_variables(model) -> tuple[list[Variable], dict, int, bool]:
    """The design parameters to add (impulses or taps), their values, the capacity and whether the
    Shaper's kind re-designs in C."""
    values, extra = {}, []

    def add(name, unit, description, value):
        extra.append(parameter(name, float(value), description, unit, variability="tunable"))
        values[name] = float(value)

    if model.interface.name == "Shaper":
        times, amplitudes = model.design
        kind, closed = model.values["kind"], model.values["kind"] in CLOSED_FORM
        capacity = CLOSED_FORM[kind](model.values["n"]) ** model.values["n_modes"] if closed else len(times)
        if capacity > MAX_IMPULSES:
            raise ValueError(f"a native {kind} shaper for {model.values['n_modes']} modes holds {capacity} impulses; "
                             f"at most {MAX_IMPULSES}")
        padding = capacity - len(times)  # unused entries of a closed-form shaper: amplitude 0 at t = 0
        for i, t in enumerate([*times, *[0.0] * padding], 1):
            add(f"impulse_time[{i}]", "s", f"time of impulse {i} (tunable; re-designed in C for closed-form kinds)", t)
        for i, a in enumerate([*amplitudes, *[0.0] * padding], 1):
            add(f"impulse_amplitude[{i}]", "1", f"amplitude of impulse {i} (tunable)", a)
        return extra, values, capacity, closed
    taps = model.taps
    if len(taps) > MAX_TAPS:
        raise ValueError(f"a native shape filter holds at most {MAX_TAPS} taps, this design has {len(taps)}: "
                         f"use a longer Ts")
    for i, w in enumerate(taps, 1):
        add(f"tap[{i}]", "1", f"tap {i} of the FIR filter, at delay {i - 1} samples (tunable)", w)
    return extra, values, len(taps), False


def _model_c(model, variables, values, guid, capacity, closed, feedthrough) -> str:
    name = model.interface.name
    body = variable_rows(variables, values, lambda variable: _meaning(name, variable))
    return f"""/* Model part of the native {name} FMU, generated by shapefmu.fmi.native.sampled: do not edit.
 * Its variables by value reference, their start values and the design made at build time. */
#include "sampled_model.h"

static const VariableRow rows[] = {{
{body}
}};

const SampledModel sampled_model = {{
    {int(name == "Shaper")}, {int(closed)}, {int(feedthrough)}, {max_modes(model)},
    {capacity}, {repr(float(model.values.get("Ts_used", 0.0)))},
    {{{table_fields(variables, guid)}, rows}}
}};
"""


def max_modes(model) -> int:
    """How many f[i], zeta[i] pairs the kind declares."""
    return sum(1 for v in model.interface.variables if v.name.startswith("f["))


def build_native_fmu(name: str, out_path, *, fmi_version: str = "2.0", clock: bool = False, **start_values) -> Path:
    """Build the native ``name`` ("Shaper" or "ShapeFilter") FMU with ``start_values`` to ``out_path``."""
    if name not in ("Shaper", "ShapeFilter"):
        raise ValueError(f"name must be Shaper or ShapeFilter, got {name!r}")
    model = designed(name, start_values)
    extra, values, capacity, closed = _design_variables(model)
    values.update(model.values)
    numbered = number_by_type([*model.interface.variables, *extra])
    dependencies = {"y": ["u"]} if name == "Shaper" else model.output_dependencies()
    feedthrough = "u" in dependencies["y"]
    about = f"{sys.modules[type(model).__module__].__doc__}\n\n{NATIVE_NOTE}"
    return write_native_fmu(name, out_path, model, numbered, values, dependencies, SOURCES, HEADERS,
                            lambda guid: _model_c(model, numbered, values, guid, capacity, closed, feedthrough), about,
                            fmi_version=fmi_version, clock=clock)



def build_native_shaper(out_path, *, fmi_version: str = "2.0", clock: bool = False, **start_values) -> Path:
    """The native Shaper FMU (``build_native_fmu("Shaper", ...)``)."""
    return build_native_fmu("Shaper", out_path, fmi_version=fmi_version, clock=clock, **start_values)


def build_native_shape_filter(out_path, *, fmi_version: str = "2.0", clock: bool = False, **start_values) -> Path:
    """The native ShapeFilter FMU (``build_native_fmu("ShapeFilter", ...)``)."""
    return build_native_fmu("ShapeFilter", out_path, fmi_version=fmi_version, clock=clock, **start_values)
