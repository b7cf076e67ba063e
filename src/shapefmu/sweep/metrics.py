"""Metrics on a recorded run (a structured array with "time" and one field per variable)."""

from __future__ import annotations

import fnmatch
import functools
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from shapefmu.analysis import settling_time
from shapefmu.runtime.checks import check_positive


@dataclass(frozen=True)
class Metric:
    """A named function of a recorded run returning one float."""

    name: str
    function: Callable

    def __call__(self, record) -> float:
        return float(self.function(record))


def _fields(record, patterns) -> list[str]:
    names = [n for n in record.dtype.names if n != "time"]
    chosen = [n for p in patterns for n in names if fnmatch.fnmatchcase(n, p)]
    if not chosen:
        raise ValueError(f"no recorded variable matches {list(patterns)}; recorded: {names}")
    return list(dict.fromkeys(chosen))


def move_end(record, command: str) -> float:
    """The time the command comes to rest: the sample after its last non-zero value (a sampled
    command holds each value until the next sample)."""
    u = np.asarray(record[command], dtype=float)
    moving = np.flatnonzero(u != 0.0)
    if moving.size == 0:
        return float(record["time"][0])
    if moving[-1] == u.size - 1:
        raise ValueError(f"command {command!r} is still non-zero at the end of the record (t = {record['time'][-1]:g})")
    return float(record["time"][moving[-1] + 1])


def _residual(record, outputs, after, command, final):
    t = np.asarray(record["time"], dtype=float)
    start = after if after is not None else move_end(record, command)
    window = t >= start - 1e-9 * max(1.0, abs(start))
    if not np.any(window):
        raise ValueError(f"the record ends at t = {t[-1]:g}, before the residual window starting at {start:g}")
    return max(float(np.max(np.abs(np.asarray(record[n], dtype=float)[window] - final)))
               for n in _fields(record, outputs))


def residual(outputs, *, after: float | None = None, command: str | None = None, final: float = 0.0,
             name: str = "residual") -> Metric:
    """Largest |y - final| of the ``outputs`` (names or fnmatch patterns such as ``"plant.theta_*"``)
    from the end of the move on: from ``after`` (s) if given, else from ``move_end(command)``."""
    if after is None and command is None:
        raise ValueError("residual needs after= (s) or command= (the variable whose rest ends the move)")
    outputs = (outputs,) if isinstance(outputs, str) else tuple(outputs)
    return Metric(name, functools.partial(_residual, outputs=outputs, after=after, command=command, final=float(final)))


def _move_time(record, output, target, tolerance):
    return settling_time(record["time"], record[output], tolerance, final=target)


def move_time(output: str, *, target: float, tolerance: float, name: str = "move_time") -> Metric:
    """First time after which |output - target| <= tolerance until the end of the record
    (``analysis.settling_time``); ``inf`` (status "non-finite") if it never settles."""
    tolerance = check_positive(tolerance, "tolerance")
    return Metric(name, functools.partial(_move_time, output=output, target=float(target), tolerance=tolerance))


def _peak(record, command):
    return np.max(np.abs(np.asarray(record[command], dtype=float)))


def peak(command: str, *, name: str = "peak") -> Metric:
    """Largest |command| over the run."""
    return Metric(name, functools.partial(_peak, command=command))


NAMED_METRICS = {"residual": residual, "move_time": move_time, "peak": peak}


def named_metrics(names: Sequence[str], *, outputs: Sequence[str] = (), command: str | None = None,
                  after: float | None = None, position: str | None = None, target: float | None = None,
                  tolerance: float | None = None) -> tuple[list[Metric], list[str]]:
    """The metrics of ``shapefmu sweep --metric NAME`` from their shared options, and the
    variables they read (what the master must record; patterns are left out)."""
    metrics, variables = [], []
    for name in dict.fromkeys(names):
        if name == "residual":
            if not outputs:
                raise ValueError("--metric residual needs --outputs (the vibrating variables, e.g. 'plant.theta_*')")
            metrics.append(residual(outputs, after=after, command=None if after is not None else command))
            variables += [o for o in outputs if not any(ch in o for ch in "*?[")]
            if after is None:
                variables.append(command)
        elif name == "move_time":
            if position is None or target is None or tolerance is None:
                raise ValueError("--metric move_time needs --position, --target and --tolerance")
            metrics.append(move_time(position, target=target, tolerance=tolerance))
            variables.append(position)
        elif name == "peak":
            metrics.append(peak(command))
            variables.append(command)
        else:
            raise ValueError(f"--metric must be one of {list(NAMED_METRICS)}, got {name!r}")
        if None in variables:
            raise ValueError(f"--metric {name} needs --command (the command variable, e.g. 'shaper.y')")
    return metrics, list(dict.fromkeys(variables))


def _metric_list(metrics) -> list[Metric]:
    if metrics is None:
        return []
    if isinstance(metrics, Mapping):
        items = [Metric(str(k), v) for k, v in metrics.items()]
    else:
        items = [m if isinstance(m, Metric) else Metric(getattr(m, "__name__", ""), m) for m in metrics]
    for m in items:
        if isinstance(m.function, str) or not callable(m.function):
            raise ValueError(f"a metric must be a Metric or a callable of the recorded run, got {m.function!r}; "
                             f"build named metrics with {', '.join(NAMED_METRICS)}(...)")
    names = [m.name for m in items]
    if any(not n or n == "<lambda>" for n in names) or len(set(names)) != len(names):
        raise ValueError(f"metrics need distinct names (pass a mapping {{name: callable}}), got {names}")
    return items
