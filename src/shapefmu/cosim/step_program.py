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
``FMUFailure`` through ``master._fail``.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
from ctypes import POINTER, c_double, c_long, c_void_p
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from shapefmu.cosim.units import ModelExchangeUnit

CALLS = ("fmi2SetReal", "fmi2GetReal", "fmi2DoStep")


@dataclass(frozen=True)
class Guard:
    """When a block runs: every step (``every=1, ends=False, recording=False``), on steps where a
    component with step multiple ``every`` starts (``k % every == 0``) or ends
    (``(k + 1) % every == 0 or k == last``), and/or only on recording steps."""

    every: int = 1
    ends: bool = False
    recording: bool = False


# Statements: ("input", i, d, early, j, s, factor, offset)   iv_i[d] = (ev|ov)_j[s] * factor + offset
#             ("set", i) / ("early", i) / ("read", i)          fmi2SetReal / fmi2GetReal into ev_i / into ov_i
#             ("do", i, m)                                      fmi2DoStep over dt, or min(m h, t_stop - t)
#             ("me", i, m)                                      a Model Exchange unit's step (Python only)
#             ("loop", n)                                       solve algebraic loop n (Python only)


def plan(master) -> list[tuple[Guard, list[tuple]]]:
    """The guarded blocks of one macro step of ``master``'s system, in execution order."""
    units = master.units
    index = {u.name: i for i, u in enumerate(units)}

    def inputs(i):
        out = []
        for d, source, s, f, o in master._ops[units[i].name]:
            early = source.name in master._early and s in master._early[source.name][0]
            out.append(("input", i, d, early, index[source.name], s, f, o))
        return out

    def step(i, with_inputs):
        unit = units[i]
        out = inputs(i) if with_inputs else []
        if unit.n_in:
            out.append(("set", i))
        if unit.name in master._early:
            out.append(("early", i))
        out.append(("me" if isinstance(unit, ModelExchangeUnit) else "do", i, master.multiples[unit.name]))
        return out

    def read(i):
        return [("read", i)] if units[i].n_out else []

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


# ------------------------------------------------------------------------------------------------
# Python


def python_chunk(master, blocks):
    """The plan as a generated Python function (see the module docstring)."""
    env = {"fail": master._fail, "solve_loop": master._solve_loop, "min": min}
    for i, u in enumerate(master.units):
        env.update({f"c{i}": u.c, f"set{i}": u.set_real, f"get{i}": u.get_real, f"do{i}": u.do_step,
                    f"ivr{i}": u.in_vr, f"iv{i}": u.in_val, f"ovr{i}": u.out_vr, f"ov{i}": u.out_val,
                    f"nin{i}": u.n_in_arg, f"nout{i}": u.n_out_arg, f"ta{i}": u.time_arg, f"ha{i}": u.step_arg,
                    f"unit{i}": u})
        if u.name in master._early:
            env[f"ev{i}"] = master._early[u.name][1]

    def statement(op):
        kind, i = op[0], op[1]
        if kind == "input":
            _, i, d, early, j, s, f, o = op
            return [f"iv{i}[{d}] = {'ev' if early else 'ov'}{j}[{s}]" + ("" if f == 1.0 else f" * {f!r}")
                    + ("" if o == 0.0 else f" + {o!r}")]
        if kind == "set":
            return [f"if (status := set{i}(c{i}, ivr{i}, nin{i}, iv{i})) > 1: fail({i}, 'fmi2SetReal', t, status)"]
        if kind == "early":
            return [f"if (status := get{i}(c{i}, ovr{i}, nout{i}, ev{i})) > 1: fail({i}, 'fmi2GetReal', t, status)"]
        if kind == "read":
            return [f"if (status := get{i}(c{i}, ovr{i}, nout{i}, ov{i})) > 1: fail({i}, 'fmi2GetReal', t + dt, status)"]
        if kind == "loop":
            return [f"solve_loop({i}, t, dt)"]
        m = op[2]
        h = "dt" if m == 1 else f"min({m!r} * h, t_stop - t)"
        if kind == "me":
            return [f"unit{i}.step(t, {h})"]
        return [f"ta{i}.value = t", f"ha{i}.value = {h}",
                f"if (status := do{i}(c{i}, ta{i}, ha{i}, 0)) > 1: fail({i}, 'fmi2DoStep', t, status)"]

    lines = ["def run_chunk(k0, k1, row, t0, h, t_stop, last, buf, every):",
             "    for k in range(k0, k1):",
             "        t = t0 + k * h",
             "        dt = h if k != last else t_stop - t"]
    for guard, body in blocks:
        condition = _condition(guard, python=True)
        indent = "        " if condition is None else "            "
        if condition is not None:
            lines.append(f"        if {condition}:")
        lines += [indent + line for op in body for line in statement(op)]
    index = {u.name: i for i, u in enumerate(master.units)}
    recorded = ", ".join(f"ov{index[c]}[{s}]" for c, s in master._record_sources)
    lines += ["        if (k + 1) % every == 0 or k == last:",
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


class _Unit(ctypes.Structure):
    """Per component: the instance, its three FMI functions and its value arrays (see ``_C_TYPES``)."""

    _fields_ = [("c", c_void_p), ("set", c_void_p), ("get", c_void_p), ("do_step", c_void_p),
                ("ivr", c_void_p), ("iv", c_void_p), ("nin", ctypes.c_size_t),
                ("ovr", c_void_p), ("ov", c_void_p), ("nout", ctypes.c_size_t), ("ev", c_void_p)]


_C_TYPES = """#include <math.h>
#include <stddef.h>
typedef int (*set_real_t)(void *, const unsigned int *, size_t, const double *);
typedef int (*get_real_t)(void *, const unsigned int *, size_t, double *);
typedef int (*do_step_t)(void *, double, double, int);
typedef struct {
    void *c; set_real_t set; get_real_t get; do_step_t do_step;
    const unsigned int *ivr; double *iv; size_t nin;
    const unsigned int *ovr; double *ov; size_t nout; double *ev;
} unit_t;
/* On a failed call: failure[0] = component, failure[1] = call (index into CALLS),
   failure[2] = status, *failure_time = the time it was called for; returns -1. */
#define FAIL(I, CALL, T, STATUS) do { failure[0] = (I); failure[1] = (CALL); failure[2] = (STATUS); \\
    *failure_time = (T); return -1; } while (0)
"""


def native_chunk(master, blocks):
    """The plan as a compiled C loop, or None where it cannot be: a Model Exchange component or an
    algebraic loop in the system (both run Python), or no C compiler on the machine."""
    if any(op[0] in ("me", "loop") for _, body in blocks for op in body):
        return None
    compiler = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if not compiler:
        return None
    source = _c_source(master, blocks)
    library = _compile(compiler, source)
    if library is None:
        return None
    function = library.run_chunk
    function.restype = c_long
    function.argtypes = [POINTER(_Unit), c_long, c_long, c_long, c_double, c_double, c_double, c_long,
                         c_void_p, c_long, POINTER(c_long), POINTER(c_double)]
    units = (_Unit * len(master.units))()
    for i, u in enumerate(master.units):
        early = master._early.get(u.name)
        units[i] = _Unit(u.c.value, _address(u.set_real), _address(u.get_real), _address(u.do_step),
                         ctypes.addressof(u.in_vr), ctypes.addressof(u.in_val), u.n_in,
                         ctypes.addressof(u.out_vr), ctypes.addressof(u.out_val), u.n_out,
                         ctypes.addressof(early[1]) if early else None)
    failure, failure_time = (c_long * 3)(), c_double()
    keep = (library, units, master.units)  # alive as long as the chunk function

    def run_chunk(k0, k1, row, t0, h, t_stop, last, buf, every):
        if not (buf.flags.c_contiguous and all(buf.dtype[name] == np.float64 for name in buf.dtype.names)):
            raise ValueError("the record buffer must be a contiguous array of float64 fields")
        result = function(keep[1], k0, k1, row, t0, h, t_stop, last, buf.ctypes.data, every, failure, failure_time)
        if result < 0:
            master._fail(failure[0], CALLS[failure[1]], failure_time.value, failure[2])
        return result

    return run_chunk


def _address(function) -> int:
    return ctypes.cast(function, c_void_p).value


def _c_source(master, blocks) -> str:
    def statement(op):
        kind, i = op[0], op[1]
        u = f"u[{i}]"
        if kind == "input":
            _, i, d, early, j, s, f, o = op
            value = f"u[{j}].{'ev' if early else 'ov'}[{s}]" + ("" if f == 1.0 else f" * {f!r}") + ("" if o == 0.0 else f" + {o!r}")
            return [f"u[{i}].iv[{d}] = {value};"]
        if kind == "set":
            return [f"if ((status = {u}.set({u}.c, {u}.ivr, {u}.nin, {u}.iv)) > 1) FAIL({i}, 0, t, status);"]
        if kind == "early":
            return [f"if ((status = {u}.get({u}.c, {u}.ovr, {u}.nout, {u}.ev)) > 1) FAIL({i}, 1, t, status);"]
        if kind == "read":
            return [f"if ((status = {u}.get({u}.c, {u}.ovr, {u}.nout, {u}.ov)) > 1) FAIL({i}, 1, t + dt, status);"]
        m = op[2]
        h = "dt" if m == 1 else f"fmin({m!r} * h, t_stop - t)"  # Python's min: both finite, no NaN
        return [f"if ((status = {u}.do_step({u}.c, t, {h}, 0)) > 1) FAIL({i}, 2, t, status);"]

    index = {u.name: i for i, u in enumerate(master.units)}
    columns = 1 + len(master._record_sources)
    lines = [_C_TYPES,
             "long run_chunk(unit_t *u, long k0, long k1, long row, double t0, double h, double t_stop, long last,",
             "               double *buf, long every, long *failure, double *failure_time) {",
             "    int status;",
             "    (void)status;",
             "    for (long k = k0; k < k1; k++) {",
             "        double t = t0 + (double)k * h;",
             "        double dt = k != last ? h : t_stop - t;"]
    for guard, body in blocks:
        condition = _condition(guard, python=False)
        indent = "        " if condition is None else "            "
        if condition is not None:
            lines.append(f"        if ({condition}) {{")
        lines += [indent + line for op in body for line in statement(op)]
        if condition is not None:
            lines.append("        }")
    lines += ["        if ((k + 1) % every == 0 || k == last) {",
              f"            double *record = buf + row * {columns};",
              "            record[0] = t + dt;"]
    lines += [f"            record[{n + 1}] = u[{index[c]}].ov[{s}];" for n, (c, s) in enumerate(master._record_sources)]
    lines += ["            row++;", "        }", "    }", "    return row;", "}", ""]
    return "\n".join(lines)


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
            if subprocess.run(command, capture_output=True).returncode != 0:
                return None
            _COMPILED[key] = ctypes.CDLL(str(library))
    return _COMPILED[key]
