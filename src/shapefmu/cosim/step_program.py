"""The master's per-step work for one system, generated once and run chunk by chunk.

:func:`plan` turns a :class:`~shapefmu.cosim.master.Master`'s schedule into a list of guarded
blocks of FMI calls (the order the module docstring of :mod:`.master` describes). The blocks are
rendered twice, from the same plan:

* :func:`python_chunk`: a generated Python function calling the FMUs' C functions through ctypes
  on preallocated arrays (always available; needed for Model Exchange components and algebraic
  loops, which call back into Python);
* :func:`native_chunk`: the same loop in C, compiled with the system C compiler and called once per
  chunk, so a macro step costs the FMUs' own work plus a few indirect calls instead of a dozen
  Python-level ctypes calls. Compiled with ``-ffp-contract=off`` so that ``x * f + o`` rounds as in
  Python: both renderings give bit-identical results (``tests/test_cosim.py``).

Both have the signature ``run_chunk(k0, k1, row, t0, h, t_stop, last, buf, every) -> row``: macro
steps ``k0 <= k < k1`` of ``h`` from ``t0`` (step ``last`` cut at ``t_stop``), recording every
``every``-th step into ``buf`` from ``row`` on; an FMI call worse than fmi2Warning raises
``FMUFailure`` through ``master._fail``. When an FMU asks to end the simulation in step ``k`` (FMI 2.0:
fmi2DoStep returns fmi2Discard and fmi2Terminated is true; FMI 3.0: terminateSimulation; Model
Exchange: terminateSimulation at an event), the other components still finish that macro step, and
``master._stop`` records the row at the requested time and ends the run.

Values of every FMI type travel (one array pair per family, see :mod:`.types`); strings only in the
Python loop. ``python_only_reason`` says why a system runs the Python loop.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import tempfile
from ctypes import POINTER, c_double, c_long, c_void_p
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from shapefmu.cosim.units import ModelExchangeUnit
from shapefmu.fmi.compiler import run_compiler
from shapefmu.runtime import limits


@dataclass(frozen=True)
class Guard:
    """When a block runs: every step (``every=1, ends=False, recording=False``), on steps where a
    component with step multiple ``every`` starts (``k % every == 0``) or ends
    (``(k + 1) % every == 0 or k == last``), and/or only on recording steps."""

    every: int = 1
    ends: bool = False
    recording: bool = False


# Statements: ("input", i, f, d, early, j, g, s, factor, offset)  iv_i_f[d] = (ev|ov)_j_g[s] * factor + offset
#             ("set", i, f) / ("early", i, f) / ("read", i, f)     Set<f> / Get<f> into ev_i_f / into ov_i_f
#             ("do", i, m)                                         fmi2DoStep / fmi3DoStep over dt, or min(m h, t_stop - t),
#                                                                  final (noSetFMUStatePriorToCurrentPoint true): no
#                                                                  step outside an algebraic loop is rolled back
#             ("me", i, m)                                         a Model Exchange unit's step (Python only)
#             ("inputs", i)                                        a Model Exchange unit sets its inputs (Python only)
#             ("loop", n)                                          solve algebraic loop n (Python only)
# f, g: family names (see .types); factor and offset are 1 and 0 except on Real connections.


def plan(master) -> list[tuple[Guard, list[tuple]]]:
    """The guarded blocks of one macro step of ``master``'s system, in execution order."""
    units = master.units
    index = {u.name: i for i, u in enumerate(units)}

    def inputs(i):
        out = []
        for f, d, source, g, s, factor, offset in master.connection_ops(units[i].name):
            early = s in master._early.get(source.name, {}).get(g, ((), None))[0]
            out.append(("input", i, f, d, early, index[source.name], g, s, factor, offset))
        return out

    def step(i, with_inputs):
        unit = units[i]
        out = inputs(i) if with_inputs else []
        if isinstance(unit, ModelExchangeUnit):  # its discrete inputs wait for event mode: it sets them
            out += [("inputs", i)] if any(channel.n_in for channel in unit.channels.values()) else []
        else:
            out += [("set", i, f) for f, channel in unit.channels.items() if channel.n_in]
        out += [("early", i, f) for f in master._early.get(unit.name, {})]
        out.append(("me" if isinstance(unit, ModelExchangeUnit) else "do", i, master.multiples[unit.name]))
        return out

    def read(i):
        return [("read", i, f) for f, channel in units[i].channels.items() if channel.n_out]

    blocks = []
    if master.algorithm == "jacobi":
        for i, u in enumerate(units):
            blocks.append((Guard(master.multiples[u.name]), inputs(i)))
        for i, u in enumerate(units):
            m = master.multiples[u.name]
            blocks += [(Guard(m), step(i, with_inputs=False)), (Guard(m, ends=m != 1), read(i))]
        return [(guard, body) for guard, body in blocks if body]
    loop_number = 0
    for stage in master.stages:
        if stage.is_loop:
            blocks.append((Guard(), [("loop", loop_number)]))
            loop_number += 1
            continue
        i = index[stage.components[0]]
        m = master.multiples[units[i].name]
        blocks.append((Guard(m), step(i, with_inputs=True)))
        blocks.append((Guard(m, ends=m != 1, recording=master._reads_only_to_record(stage.components[0])), read(i)))
    return [(guard, body) for guard, body in blocks if body]


def _condition(guard: Guard, python: bool) -> str | None:
    both, either = (" and ", " or ") if python else (" && ", " || ")
    parts = []
    if guard.every != 1:
        m = guard.every
        parts.append(f"((k + 1) % {m} == 0{either}k == last)" if guard.ends else f"k % {m} == 0")
    if guard.recording:
        parts.append(f"((k + 1) % every == 0{either}k == last)")
    return both.join(parts) or None


def _guarded(blocks, statement, python: bool) -> list[str]:
    """The loop body's lines: every block's statements under its guard (an ``if`` in Python or in C)."""
    lines = []
    for guard, body in blocks:
        condition = _condition(guard, python=python)
        indent = "        " if condition is None else "            "
        if condition is not None:
            lines.append(f"        if {condition}:" if python else f"        if ({condition}) {{")
        lines += [indent + line for op in body for line in statement(op)]
        if condition is not None and not python:
            lines.append("        }")
    return lines


def _value(op, python: bool) -> str:
    """The right-hand side of an input statement."""
    _, i, f, d, early, j, g, s, factor, offset = op
    value = f"{'ev' if early else 'ov'}{j}_{g}[{s}]" + ("" if factor == 1.0 else f" * {factor!r}") + ("" if offset == 0.0 else f" + {offset!r}")
    return value


# ------------------------------------------------------------------------------------------------
# Python


def python_chunk(master, blocks):
    """The plan as a generated Python function (see the module docstring)."""
    env = {"fail": master._fail, "solve_loop": master._solve_loop, "stop": master._stop, "min": min}
    for i, u in enumerate(master.units):
        env.update({f"c{i}": u.c, f"do{i}": u.do_step, f"ta{i}": u.time_arg, f"ha{i}": u.step_arg, f"unit{i}": u})
        for f, ch in u.channels.items():
            env.update({f"set{i}_{f}": ch.setter, f"get{i}_{f}": ch.getter, f"ivr{i}_{f}": ch.in_vr, f"iv{i}_{f}": ch.in_val,
                        f"ovr{i}_{f}": ch.out_vr, f"ov{i}_{f}": ch.out_val, f"nin{i}_{f}": ch.n_in_arg, f"nout{i}_{f}": ch.n_out_arg,
                        f"nvrin{i}_{f}": ch.nvr_in_arg, f"nvrout{i}_{f}": ch.nvr_out_arg})
        for f, (_, early) in master._early.get(u.name, {}).items():
            env[f"ev{i}_{f}"] = early

    def statement(op):
        kind, i = op[0], op[1]
        unit = master.units[i]
        if kind == "input":
            return [f"iv{i}_{op[2]}[{op[3]}] = {_value(op, python=True)}"]
        if kind in ("set", "early", "read"):
            f = op[2]
            call = f"{unit.prefix}{'Set' if kind == 'set' else 'Get'}{f}"
            # value references, their number, the values; FMI 3.0 adds the number of values (nValues),
            # more than the references' where an array contributes its elements
            arrays = {"set": (f"ivr{i}_{f}", f"nvrin{i}_{f}", f"iv{i}_{f}"), "early": (f"ovr{i}_{f}", f"nvrout{i}_{f}", f"ev{i}_{f}"),
                      "read": (f"ovr{i}_{f}", f"nvrout{i}_{f}", f"ov{i}_{f}")}[kind]
            extra = (f", nin{i}_{f}" if kind == "set" else f", nout{i}_{f}") if unit.fmi3 else ""
            function = f"set{i}_{f}" if kind == "set" else f"get{i}_{f}"
            when = "t + dt" if kind == "read" else "t"
            return [f"if (status := {function}(c{i}, {', '.join(arrays)}{extra})) > 1: fail({i}, {call!r}, {when}, status)"]
        if kind == "loop":
            return [f"solve_loop({i}, t, dt)"]
        if kind == "inputs":
            return [f"unit{i}.set_inputs()"]
        m = op[2]
        h = "dt" if m == 1 else f"min({m!r} * h, t_stop - t)"
        if kind == "me" or unit.fmi3:
            return [f"if unit{i}.step(t, {h}): stopping = True"]
        return [f"ta{i}.value = t", f"ha{i}.value = {h}",
                f"if (status := do{i}(c{i}, ta{i}, ha{i}, 1)) > 1 and unit{i}.stop_or_fail(t, {h}, status): stopping = True"]

    lines = ["def run_chunk(k0, k1, row, t0, h, t_stop, last, buf, every):",
             "    stopping = False",
             "    for k in range(k0, k1):",
             "        t = t0 + k * h",
             "        dt = h if k != last else t_stop - t"]
    lines += _guarded(blocks, statement, python=True)
    index = {u.name: i for i, u in enumerate(master.units)}
    recorded = ", ".join(f"(ov{index[c]}_{f}[{s}] or b'').decode(errors='replace')" if f == "String" else f"ov{index[c]}_{f}[{s}]"
                         for c, f, s in master._record_sources)
    lines += ["        if stopping:",
              "            return stop(row, buf, k)",
              "        if (k + 1) % every == 0 or k == last:",
              f"            buf[row] = (t + dt, {recorded})" if recorded else "            buf[row] = (t + dt,)",
              "            row += 1",
              "    return row"]
    namespace = dict(env)
    exec(compile("\n".join(lines), f"<shapefmu master for {master.system.name}>", "exec"), namespace)  # noqa: S102
    return namespace["run_chunk"]


# ------------------------------------------------------------------------------------------------
# C

# Shared libraries compiled in this process, by the hash of their source.
_COMPILED: dict[str, ctypes.CDLL] = {}

_C_HEADER = """#include <math.h>
#include <stddef.h>
#include <string.h>
typedef int (*set2_t)(void *, const unsigned int *, size_t, const void *);
typedef int (*get2_t)(void *, const unsigned int *, size_t, void *);
typedef int (*set3_t)(void *, const unsigned int *, size_t, const void *, size_t);
typedef int (*get3_t)(void *, const unsigned int *, size_t, void *, size_t);
typedef int (*do2_t)(void *, double, double, int);
typedef int (*do3_t)(void *, double, double, _Bool, _Bool *, _Bool *, _Bool *, double *);
/* On a failed call: failure[0] = component, failure[1] = call (index into calls), failure[2] = status,
   *failure_time = the time it was called for; returns -1. */
#define FAIL(I, CALL, T, STATUS) do { failure[0] = (I); failure[1] = (CALL); failure[2] = (STATUS); \\
    *failure_time = (T); return -1; } while (0)
/* A recorded value into the row at byte offset OFF (memcpy: fields of a packed row need not be aligned). */
#define PUT(TYPE, OFF, VALUE) do { TYPE value_ = (VALUE); memcpy(record + (OFF), &value_, sizeof value_); } while (0)
"""

# numpy dtype of a recorded column -> C type it is stored as.
_RECORD_C = {"f8": "double", "f4": "float", "i1": "signed char", "u1": "unsigned char", "i2": "short",
             "u2": "unsigned short", "i4": "int", "u4": "unsigned int", "i8": "long long", "u8": "unsigned long long",
             "?": "unsigned char"}


# gcc's time on the one generated function grows faster than its length (600 components: 8.6 s at
# -O2, where 128 take well under a second): a larger system runs the Python loop, which starts at once.
MAX_COMPILED_COMPONENTS = 128


def python_only_reason(master, blocks) -> str | None:
    """Why the plan cannot run as a compiled C loop, or None if it can."""
    if len(master.units) > MAX_COMPILED_COMPONENTS:
        return (f"the system has {len(master.units)} components, more than the {MAX_COMPILED_COMPONENTS} whose "
                f"step loop compiles in about a second")
    values = len(master._record_sources) + sum(len(master.connection_ops(unit.name)) for unit in master.units)
    if values > limits.MAX_COMPILED_VALUES:
        return (f"the system moves and records {values:,} values a step, more than the {limits.MAX_COMPILED_VALUES:,} "
                f"whose step loop compiles in about a second (shapefmu.runtime.limits.MAX_COMPILED_VALUES)")
    for _, body in blocks:
        for op in body:
            if op[0] == "me":
                return f"component {master.units[op[1]].name!r} runs as Model Exchange (integrated in Python)"
            if op[0] == "loop":
                return f"the algebraic loop through {', '.join(master._loops[op[1]].loop_variables)} is solved in Python"
    for unit in master.units:
        if getattr(unit, "clocks", None):
            return f"component {unit.name!r} has clocks, which the master ticks in Python"
    for c in master.system.connections:
        family = master._unit[c.end_component].slots(c.end_connector, inputs=True)[0]
        if master._unit[c.end_component].channels[family].family.c_type is None:
            return f"connection {c.start} -> {c.end} joins {family} variables, which the compiled loop does not move"
    for reference, (component, family, _) in zip(master.record, master._record_sources):
        if master._unit[component].channels[family].family.c_type is None:
            return f"recorded {reference} is a {family} variable, which the compiled loop does not move"
    compiler = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if not compiler:
        return "no C compiler (set CC or install gcc)"
    return None


def native_chunk(master, blocks):
    """The plan as a compiled C loop, or None where it cannot be (``python_only_reason`` says why;
    a failed compilation sets ``master.loop_reason``)."""
    if python_only_reason(master, blocks):
        return None
    compiler = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    pointers, names = _pointer_table(master)
    source, calls = _c_source(master, blocks, names, buffer_dtype(master))
    library = _compile(compiler, source)
    if library is None:
        master.loop_reason = "compiling the step loop failed"
        return None
    function = library.run_chunk
    function.restype = c_long
    function.argtypes = [c_void_p, c_long, c_long, c_long, c_double, c_double, c_double, c_long, c_void_p, c_long,
                         POINTER(c_long), POINTER(c_double), POINTER(c_long), POINTER(c_double), POINTER(c_long)]
    table = (c_void_p * len(pointers))(*pointers)
    n = len(master.units)
    failure, failure_time = (c_long * 3)(), c_double()
    pending, pending_time, stop_step = (c_long * n)(), (c_double * n)(), (c_long * 1)()
    dtype = buffer_dtype(master)
    keep = (library, table, master.units)  # alive as long as the chunk function

    def run_chunk(k0, k1, row, t0, h, t_stop, last, buf, every):
        if not (buf.flags.c_contiguous and buf.dtype == dtype):
            raise ValueError(f"the record buffer must be a contiguous array of dtype {dtype}")
        stop_step[0] = -1
        result = function(keep[1], k0, k1, row, t0, h, t_stop, last, buf.ctypes.data, every, failure, failure_time,
                          pending, pending_time, stop_step)
        if result < 0:
            master._fail(failure[0], calls[failure[1]], failure_time.value, failure[2])
        if stop_step[0] >= 0:
            k = stop_step[0]
            t = t0 + k * h
            dt = h if k != last else t_stop - t
            for i, unit in enumerate(master.units):
                if pending[i] == 1:
                    unit.stop_or_fail(t, pending_time[i] - t if unit.fmi3 else dt, 2)
                elif pending[i] == 2:
                    unit.terminated_at = pending_time[i]
                    unit.termination_call = "fmi3DoStep set terminateSimulation"
                pending[i] = 0
            return master._stop(result, buf, k)
        return result

    return run_chunk


def buffer_dtype(master) -> np.dtype:
    """The record buffer's dtype: time, then one typed column per recorded variable (packed)."""
    return np.dtype([("time", "f8")] + [(name, master._unit[c].channels[f].family.record)
                                        for name, (c, f, _) in zip(master.record, master._record_sources)])


def _pointer_table(master) -> tuple[list[int], list[dict[str, int]]]:
    """Every pointer the C loop needs, in one array; ``names[i][key]`` is an entry's index."""
    pointers, names = [], []
    for u in master.units:
        entries = {"c": u.c.value, "do": _address(u.do_step)}
        for f, ch in u.channels.items():
            entries.update({f"set_{f}": _address(ch.setter) if ch.n_in else None,
                            f"get_{f}": _address(ch.getter) if ch.n_out else None,
                            f"ivr_{f}": ctypes.addressof(ch.in_vr), f"iv_{f}": ctypes.addressof(ch.in_val),
                            f"ovr_{f}": ctypes.addressof(ch.out_vr), f"ov_{f}": ctypes.addressof(ch.out_val)})
        for f, (_, early) in master._early.get(u.name, {}).items():
            entries[f"ev_{f}"] = ctypes.addressof(early)
        names.append({key: len(pointers) + n for n, key in enumerate(entries)})
        pointers += list(entries.values())
    return pointers, names


def _address(function) -> int | None:
    return ctypes.cast(function, c_void_p).value if function is not None else None


def _c_source(master, blocks, names, dtype) -> tuple[str, list[str]]:
    """The C source of the plan and the names of the FMI calls its FAIL indices refer to."""
    calls: list[str] = []

    def call_index(name: str) -> int:
        if name not in calls:
            calls.append(name)
        return calls.index(name)

    declarations = []
    for i, u in enumerate(master.units):
        v = "3" if u.fmi3 else "2"
        declarations += [f"    void *c{i} = P[{names[i]['c']}];", f"    do{v}_t do{i} = (do{v}_t)P[{names[i]['do']}];"]
        for f, ch in u.channels.items():
            t = ch.family.c_type
            declarations += [f"    const unsigned int *ivr{i}_{f} = P[{names[i][f'ivr_{f}']}];",
                             f"    {t} *iv{i}_{f} = P[{names[i][f'iv_{f}']}];",
                             f"    const unsigned int *ovr{i}_{f} = P[{names[i][f'ovr_{f}']}];",
                             f"    {t} *ov{i}_{f} = P[{names[i][f'ov_{f}']}];",
                             f"    set{v}_t set{i}_{f} = (set{v}_t)P[{names[i][f'set_{f}']}];",
                             f"    get{v}_t get{i}_{f} = (get{v}_t)P[{names[i][f'get_{f}']}];"]
            if f in master._early.get(u.name, {}):
                declarations.append(f"    {t} *ev{i}_{f} = P[{names[i][f'ev_{f}']}];")
        if u.fmi3:
            declarations.append(f"    _Bool event{i}, terminate{i}, early{i}; double last{i};")

    def statement(op):
        kind, i = op[0], op[1]
        u = master.units[i]
        if kind == "input":
            target = u.channels[op[2]].family.c_type
            return [f"iv{i}_{op[2]}[{op[3]}] = ({target})({_value(op, python=False)});"]
        if kind in ("set", "early", "read"):
            f = op[2]
            ch = u.channels[f]
            # nvr value references; FMI 3.0 adds nValues, an array's elements each (see .units)
            nvr, count = (ch.nvr_in, ch.n_in) if kind == "set" else (ch.nvr_out, ch.n_out)
            arrays = {"set": f"ivr{i}_{f}, {nvr}, iv{i}_{f}", "early": f"ovr{i}_{f}, {nvr}, ev{i}_{f}",
                      "read": f"ovr{i}_{f}, {nvr}, ov{i}_{f}"}[kind]
            extra = f", {count}" if u.fmi3 else ""
            function = f"set{i}_{f}" if kind == "set" else f"get{i}_{f}"
            index = call_index(f"{u.prefix}{'Set' if kind == 'set' else 'Get'}{f}")
            when = "t + dt" if kind == "read" else "t"
            return [f"if ((status = {function}(c{i}, {arrays}{extra})) > 1) FAIL({i}, {index}, {when}, status);"]
        m = op[2]
        h = "dt" if m == 1 else f"fmin({m!r} * h, t_stop - t)"  # Python's min: both finite, no NaN
        index = call_index(f"{u.prefix}DoStep")
        if u.fmi3:
            return [f"{{ const double hs = {h};",
                    f"  status = do{i}(c{i}, t, hs, 1, &event{i}, &terminate{i}, &early{i}, &last{i});",
                    f"  if (status > 1 && !(status == 2 && terminate{i})) FAIL({i}, {index}, t, status);",
                    f"  if (terminate{i}) {{ pending[{i}] = 2; pending_time[{i}] = (last{i} >= t && last{i} <= t + hs) ? last{i} : t + hs; stop = 1; }} }}"]
        # fmi2Discard may be a termination request: Python asks fmi2GetBooleanStatus after the step.
        return [f"{{ const double hs = {h};",
                f"  if ((status = do{i}(c{i}, t, hs, 1)) > 1) {{ if (status != 2) FAIL({i}, {index}, t, status);",
                f"    pending[{i}] = 1; pending_time[{i}] = t + hs; stop = 1; }} }}"]

    index = {u.name: i for i, u in enumerate(master.units)}
    lines = [_C_HEADER,
             "long run_chunk(void **P, long k0, long k1, long row, double t0, double h, double t_stop, long last,",
             "               char *buf, long every, long *failure, double *failure_time, long *pending,",
             "               double *pending_time, long *stop_step) {",
             "    int status;",
             "    (void)status;",
             *declarations,
             "    for (long k = k0; k < k1; k++) {",
             "        double t = t0 + (double)k * h;",
             "        double dt = k != last ? h : t_stop - t;",
             "        int stop = 0;"]
    lines += _guarded(blocks, statement, python=False)
    lines += ["        if (stop) { *stop_step = k; return row; }",
              "        if ((k + 1) % every == 0 || k == last) {",
              f"            char *record = buf + row * {dtype.itemsize}L;",
              "            PUT(double, 0, t + dt);"]
    for n, (c, f, s) in enumerate(master._record_sources):
        field = dtype.names[n + 1]
        kind = dtype.fields[field][0].str[1:] if dtype.fields[field][0].char != "?" else "?"
        value = f"ov{index[c]}_{f}[{s}]"
        lines.append(f"            PUT({_RECORD_C[kind]}, {dtype.fields[field][1]}, {value + ' != 0' if kind == '?' else value});")
    lines += ["            row++;", "        }", "    }", "    return row;", "}", ""]
    return "\n".join(lines), calls


def _compile(compiler: str, source: str):
    """The shared library of ``source``, compiled once per process (None if compiling fails)."""
    key = hashlib.sha256(source.encode()).hexdigest()[:20]
    if key not in _COMPILED:
        # The files go as soon as the library is loaded: a loaded library needs no file on Linux.
        with tempfile.TemporaryDirectory(prefix="shapefmu-master-") as directory:
            c_file, library = Path(directory) / "step.c", Path(directory) / f"step_{key}.so"
            c_file.write_text(source)
            # -ffp-contract=off: no fused multiply-add, so x * f + o rounds as Python rounds it.
            command = [compiler, "-O2", "-shared", "-fPIC", "-ffp-contract=off", "-o", str(library), str(c_file), "-lm"]
            if run_compiler(command).returncode != 0:
                return None
            _COMPILED[key] = ctypes.CDLL(str(library))
    return _COMPILED[key]
