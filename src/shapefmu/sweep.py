"""Robustness sweeps: one run per parameter point, mapped over a Dask cluster, one row per run.

A sweep evaluates a *target* at every point of a grid (``grid("plant.wn=3.36:3.66:10",
"plant.zeta=0.005,0.01,0.02")``) or of a seeded random sample (``random_samples``) and gathers one
row per run: the run's index, its parameters, its metrics, its ``status`` (``"ok"``, ``"error"``,
``"timeout"``, ``"non-finite"``), the error message and the run's wall time. The target is

- a co-simulation (``cosim("system.ssp", step=..., stop_time=..., record=[...])``): the SSP file
  travels to the workers as bytes in a Dask worker plugin (no shared filesystem; a worker that
  joins or restarts gets it too), each worker thread opens it into one ``shapefmu.cosim.Master``
  on its first run and reuses that master (``reset()`` between runs, no re-extraction), and the
  metrics (``residual``, ``move_time``, ``peak`` or any callable) reduce the recorded array;
- a callable ``func(parameters: dict) -> recorded array | {metric: value}``;
- with ``vectorized=True``, a closed form ``func({name: array}) -> {metric: array}`` evaluated for
  all points at once in this process (the design layer's analytic path, no Dask).

Runs go to a ``distributed.LocalCluster`` (one single-threaded worker process per core) unless a
``Client`` or a scheduler address is given. A failing run becomes a row and the sweep goes on (a
run past ``timeout`` is interrupted and its master replaced); the runs of a lost worker are
rescheduled by Dask, and a task that still fails (``retries=`` exhausted, ``KilledWorker``)
becomes error rows; rows are appended to the output file as they arrive, and ``resume=True``
skips the points that already have a row there.
"""

from __future__ import annotations

import atexit
import ctypes
import dataclasses
import fnmatch
import functools
import hashlib
import math
import os
import sys
import tempfile
import threading
import time
from collections import OrderedDict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from shapefmu.analysis import settling_time
from shapefmu.runtime.checks import check_positive
from shapefmu.sweep_store import (  # noqa: F401  (read_rows and STATUSES are part of this module's API)
    FIXED_COLUMNS,
    STATUSES,
    Store,
    as_array,
    columns,
    metric_names_in_file,
    read_rows,
)

try:
    from distributed import WorkerPlugin
except ImportError:  # the analytic path, the metrics and the output files work without Dask
    WorkerPlugin = object


# ---------------------------------------------------------------------------------------------
# Parameter points


@dataclass(frozen=True, eq=False)
class Points:
    """Parameter points of a sweep: ``values[i, j]`` is parameter ``names[j]`` of run ``i``."""

    names: tuple[str, ...]
    values: np.ndarray

    def __post_init__(self):
        values = np.array(self.values, dtype=float, ndmin=2)
        names = tuple(self.names)
        if values.ndim != 2 or values.shape[1] != len(names) or not names:
            raise ValueError(f"values must have shape (n, {len(names)}) for parameters {names}, got {values.shape}")
        if len(set(names)) != len(names) or set(names) & set(FIXED_COLUMNS):
            raise ValueError(f"parameter names must be distinct and not one of {FIXED_COLUMNS}, got {names}")
        if not np.all(np.isfinite(values)):
            raise ValueError("parameter values must be finite")
        values.setflags(write=False)
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "values", values)

    def __len__(self) -> int:
        return self.values.shape[0]

    def parameters(self, i: int) -> dict[str, float]:
        return dict(zip(self.names, map(float, self.values[i])))


def parse_vary(text: str) -> tuple[str, np.ndarray]:
    """``"name=start:stop:n"`` (n points from start to stop, ends included) or ``"name=v1,v2,..."``."""
    name, sep, spec = text.partition("=")
    name = name.strip()
    if not sep or not name or not spec.strip():
        raise ValueError(f"--vary must be NAME=START:STOP:N or NAME=V1,V2,..., got {text!r}")
    try:
        if ":" in spec:
            start, stop, count = spec.split(":")
            n = int(count)
            if n < 1:
                raise ValueError(f"the number of points of {name} must be >= 1, got {n} in {text!r}")
            values = np.linspace(float(start), float(stop), n)
        else:
            values = np.array([float(v) for v in spec.split(",")])
    except ValueError as error:
        if "must be >= 1" in str(error):
            raise
        raise ValueError(f"--vary must be NAME=START:STOP:N or NAME=V1,V2,..., got {text!r}") from None
    if not np.all(np.isfinite(values)):
        raise ValueError(f"values of {name} must be finite, got {text!r}")
    return name, values


def grid(*specs) -> Points:
    """The Cartesian product of the specs (the first varies slowest); a spec is a ``parse_vary``
    string or a ``(name, values)`` pair."""
    if not specs:
        raise ValueError("a grid needs at least one spec such as 'plant.wn=3.36:3.66:10'")
    axes = [parse_vary(s) if isinstance(s, str) else (str(s[0]), np.asarray(s[1], dtype=float).ravel()) for s in specs]
    names = tuple(name for name, _ in axes)
    mesh = np.meshgrid(*(values for _, values in axes), indexing="ij")
    return Points(names, np.stack([m.ravel() for m in mesh], axis=1))


def parse_range(text: str) -> tuple[str, float, float]:
    """``"name=low:high"`` -> (name, low, high) with low < high."""
    name, sep, spec = text.partition("=")
    try:
        low, high = (float(v) for v in spec.split(":"))
    except ValueError:
        raise ValueError(f"a sampling range must be NAME=LOW:HIGH, got {text!r}") from None
    if not sep or not name.strip() or not (math.isfinite(low) and math.isfinite(high) and low < high):
        raise ValueError(f"a sampling range must be NAME=LOW:HIGH with finite LOW < HIGH, got {text!r}")
    return name.strip(), low, high


def random_samples(n: int, ranges, seed: int = 0) -> Points:
    """``n`` points drawn uniformly from ``ranges`` ({name: (low, high)} or ``"name=low:high"``
    strings) with ``numpy.random.default_rng(seed)``: the same seed gives the same points."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n must be an integer >= 1, got {n!r}")
    items = [parse_range(r) for r in ranges] if not isinstance(ranges, Mapping) else [
        (str(k), float(v[0]), float(v[1])) for k, v in ranges.items()]
    if not items:
        raise ValueError("random_samples needs at least one range")
    for name, low, high in items:
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise ValueError(f"range of {name} must be finite with low < high, got ({low}, {high})")
    rng = np.random.default_rng(seed)
    low = np.array([lo for _, lo, _ in items])
    high = np.array([hi for _, _, hi in items])
    return Points(tuple(name for name, _, _ in items), low + (high - low) * rng.random((n, len(items))))


# ---------------------------------------------------------------------------------------------
# Metrics on a recorded run (a structured array with "time" and one field per variable)


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


# ---------------------------------------------------------------------------------------------
# Targets and the worker side


@dataclass(frozen=True)
class Cosim:
    """A co-simulation target: an SSP file shipped as bytes, opened on each worker by ``opener``
    (``shapefmu.cosim.Master`` by default, called as ``opener(path, step, algorithm=...,
    record=[...])``), and run with ``.run(stop_time, parameters=...)`` after ``.reset()``."""

    file_name: str
    digest: str
    key: str
    step: float
    stop_time: float
    record: tuple[str, ...]
    algorithm: str | None = None
    opener: Callable | None = None
    data: bytes = field(default=b"", repr=False)


def cosim(system, *, step: float, stop_time: float, record: Sequence[str], algorithm: str | None = None,
          opener: Callable | None = None) -> Cosim:
    """A co-simulation target for ``sweep``: ``system`` (an ``.ssp`` path; an ``.ssd`` path, whose
    FMUs are found from its own folder; or a ``shapefmu.fmi.ssp.System``) is read into the bytes of
    one ``.ssp`` archive, FMUs included, that travel to the workers."""
    if isinstance(system, str) or hasattr(system, "__fspath__"):
        path = Path(system)
        if not path.is_file() or path.suffix.lower() not in (".ssp", ".ssd"):
            raise ValueError(f"system must be an existing system file (.ssp or .ssd), got {str(path)!r}")
        if path.suffix.lower() == ".ssd":
            from shapefmu.fmi.ssp import read_ssp

            # An .ssd names its FMUs by paths a worker may not have: pack them into an archive.
            system = read_ssp(path)
    if hasattr(system, "write_ssp"):
        with tempfile.TemporaryDirectory(prefix="shapefmu-sweep-") as directory:
            path = Path(system.write_ssp(Path(directory) / f"{getattr(system, 'name', 'system')}.ssp"))
            data, file_name = path.read_bytes(), path.name
    elif isinstance(system, str) or hasattr(system, "__fspath__"):
        data, file_name = path.read_bytes(), path.name
    else:
        raise ValueError(f"system must be an .ssp or .ssd path or a shapefmu.fmi.ssp.System, got {type(system).__name__}")
    step = check_positive(step, "step")
    stop_time = check_positive(stop_time, "stop_time")
    record = (record,) if isinstance(record, str) else tuple(record)
    if not record:
        raise ValueError("record must name at least one variable, e.g. 'plant.theta_1'")
    digest = hashlib.sha256(data).hexdigest()[:20]
    opener_name = "" if opener is None else f"{opener.__module__}.{opener.__qualname__}"
    key = f"{digest}:{opener_name}:{step!r}:{algorithm}:{','.join(record)}"
    return Cosim(file_name, digest, key, step, stop_time, record, algorithm, opener, data)


def _open_master(path, step, *, algorithm=None, record=()):
    from shapefmu.cosim import Master

    options = {"record": list(record)}
    if algorithm is not None:
        options["algorithm"] = algorithm
    return Master(path, step, **options)


class _SystemFile(WorkerPlugin):
    """Writes a sweep's system file into a worker's local directory, once per worker process.

    Dask runs a registered plugin on every worker, including those that join or are restarted
    later, so the file reaches every process that may run the sweep without a shared filesystem.
    """

    def __init__(self, cosim_target: Cosim):
        self.digest, self.file_name, self.data = cosim_target.digest, cosim_target.file_name, cosim_target.data
        self.name = f"shapefmu-sweep-{self.digest}"

    def setup(self, worker):
        directory = os.path.join(worker.local_directory, self.name)
        os.makedirs(directory, exist_ok=True)
        path = os.path.join(directory, self.file_name)
        with open(path, "wb") as file:
            file.write(self.data)
        _FILES[self.digest] = path


# This worker process's system files by content digest (written by _SystemFile).
_FILES: dict[str, str] = {}

# Systems kept open per worker thread; the least recently used beyond this is closed.
_MASTERS_PER_THREAD = 4


class _Opened:
    """The masters this worker process has opened, one per (target, thread): a master is not
    shared between threads, and is opened once and reset between runs. They are closed when the
    worker process exits."""

    def __init__(self):
        self.local = threading.local()
        self.all = []
        self.lock = threading.Lock()

    def masters(self) -> OrderedDict:
        return self.local.__dict__.setdefault("masters", OrderedDict())

    def get(self, target: Cosim):
        masters = self.masters()
        if target.key in masters:
            masters.move_to_end(target.key)
            return masters[target.key], True
        while len(masters) >= _MASTERS_PER_THREAD:  # a long-lived cluster serves many sweeps
            _close_quietly(masters.popitem(last=False)[1])
        if target.digest not in _FILES:
            raise RuntimeError(f"{target.file_name} was not delivered to this worker process (no sweep plugin ran)")
        opener = target.opener or _open_master
        master = opener(_FILES[target.digest], target.step, algorithm=target.algorithm, record=list(target.record))
        with self.lock:
            if not self.all:
                atexit.register(self.close)
            self.all.append(master)
        masters[target.key] = master
        return master, False

    def drop(self, target: Cosim):
        master = self.masters().pop(target.key, None)
        if master is not None:
            _close_quietly(master)

    def forget(self, target: Cosim):
        """Drop a master whose run was interrupted at an arbitrary point (inside a Python FMU,
        possibly): it is not reset and run again, as that can hang; the next run opens a new one,
        and this one's FMUs are freed when it is garbage-collected."""
        master = self.masters().pop(target.key, None)
        with self.lock:
            self.all = [m for m in self.all if m is not master]

    def close(self):
        with self.lock:
            for master in self.all:
                _close_quietly(master)
            self.all.clear()


def _close_quietly(master):
    try:
        master.close()
    except Exception:  # noqa: BLE001 - a master that failed mid-run may not close cleanly; it is dropped anyway
        pass


_OPENED = _Opened()


def _run_cosim(target: Cosim, parameters: dict):
    master, used = _OPENED.get(target)
    if used:
        try:
            master.reset()
        except Exception:  # noqa: BLE001 - a master left broken by a failed run is reopened once
            _OPENED.drop(target)
            master, _ = _OPENED.get(target)
    return master.run(target.stop_time, parameters=parameters)


class RunTimeout(Exception):
    """Raised inside a run that exceeded the sweep's timeout."""


def _raise_in_thread(thread_id: int, exception) -> None:
    ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(thread_id),
                                               None if exception is None else ctypes.py_object(exception))


def _call_with_timeout(func, timeout):
    """func(), interrupted by RunTimeout after ``timeout`` s.

    The exception is raised asynchronously in the running thread, so it lands at the next Python
    bytecode: between the master's steps, not inside one FMU call (a step that never returns
    keeps its worker busy). If it lands inside a Python FMU, whose wrapper turns it into an FMU
    error, the run is still a timeout. Disarming under the lock and clearing a not-yet-delivered
    exception makes the outcome either func's result or RunTimeout, never a stray exception later.
    """
    if timeout is None:
        return func()
    thread_id = threading.get_ident()
    lock = threading.Lock()
    armed, fired = [True], [False]

    def fire():
        with lock:
            if armed[0]:
                fired[0] = True
                _raise_in_thread(thread_id, RunTimeout)

    timer = threading.Timer(timeout, fire)
    timer.daemon = True
    timer.start()
    try:
        result = func()
    except BaseException:
        if fired[0]:
            raise RunTimeout from None
        raise
    finally:
        with lock:
            armed[0] = False
            _raise_in_thread(thread_id, None)
        timer.cancel()
    if fired[0]:
        # Interrupted inside code that swallowed the exception (a C callback): the run is not trusted.
        raise RunTimeout
    return result


def _evaluate(target, parameters, metrics: list[Metric], timeout):
    """Metrics of one run, or raises."""
    if isinstance(target, Cosim):
        result = _call_with_timeout(lambda: _run_cosim(target, parameters), timeout)
    else:
        result = _call_with_timeout(lambda: target(parameters), timeout)
    if isinstance(result, Mapping):
        if metrics:
            raise ValueError("the target returned metric values; metrics= applies only to recorded arrays")
        return {str(k): float(v) for k, v in result.items()}
    if not metrics:
        raise ValueError("the target returned a recorded array; pass metrics= to reduce it to numbers")
    return {m.name: m(result) for m in metrics}


def _run_batch(target, batch, names, metrics, timeout) -> list[dict]:
    """Rows of a batch of runs; every failure of a run is caught and becomes its row."""
    rows = []
    for run, values in batch:
        parameters = dict(zip(names, values))
        start = time.perf_counter()
        row = {"run": run, **parameters, "status": "ok", "error": ""}
        try:
            row.update(_evaluate(target, parameters, metrics, timeout))
            if not all(math.isfinite(v) for k, v in row.items() if k not in FIXED_COLUMNS and k not in parameters):
                row["status"] = "non-finite"
        except RunTimeout:
            row.update(status="timeout", error=f"run exceeded the timeout of {timeout:g} s")
            if isinstance(target, Cosim):
                _OPENED.forget(target)
        except Exception as error:  # noqa: BLE001 - a failing run is a row, the sweep goes on
            row.update(status="error", error=f"{type(error).__name__}: {error}")
        row["wall_time"] = time.perf_counter() - start
        rows.append(row)
    return rows


# ---------------------------------------------------------------------------------------------
# Progress on stderr


class _Progress:
    def __init__(self, total: int, done: int, enabled: bool, stream=None):
        self.total, self.done, self.failed = total, done, 0
        self.enabled = enabled
        self.stream = stream or sys.stderr
        self.start = time.perf_counter()
        self.first = done
        self.last_print = 0.0

    def update(self, rows):
        self.done += len(rows)
        self.failed += sum(r["status"] != "ok" for r in rows)
        now = time.perf_counter()
        if self.enabled and (now - self.last_print > 0.25 or self.done == self.total):
            self.last_print = now
            elapsed = now - self.start
            rate = (self.done - self.first) / elapsed if elapsed > 0 else 0.0
            left = f", ~{(self.total - self.done) / rate:.0f} s left" if rate > 0 and self.done < self.total else ""
            width = 30
            bar = "#" * int(width * self.done / max(self.total, 1))
            self.stream.write(f"\rsweep [{bar:<{width}}] {self.done}/{self.total} runs, {self.failed} not ok, "
                              f"{elapsed:.1f} s{left}   ")
            self.stream.flush()

    def close(self):
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()


# ---------------------------------------------------------------------------------------------
# The sweep


def _points(points) -> Points:
    if isinstance(points, Points):
        return points
    if isinstance(points, str):
        return grid(points)
    if isinstance(points, Mapping):
        return grid(*points.items())
    if isinstance(points, Sequence) and points:
        return grid(*points)
    raise ValueError("points must be a Points (grid(...) or random_samples(...)), a spec string such as "
                     f"'plant.wn=3.36:3.66:10', a list of them or a {{name: values}} mapping, got {points!r}")


def _open_client(client, n_workers):
    """(client, cluster to close or None, whether we opened the client)."""
    from distributed import Client, LocalCluster

    if client is None:
        workers = n_workers or os.cpu_count() or 1
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0")
        return Client(cluster), cluster, True
    if n_workers is not None:
        raise ValueError(f"n_workers applies to the default local cluster only, got n_workers={n_workers} with "
                         f"client={client!r}")
    if isinstance(client, str):
        return Client(client), None, True
    if isinstance(client, Client):
        return client, None, False
    raise ValueError(f"client must be None, a scheduler address such as 'tcp://host:8786' or a distributed.Client, "
                     f"got {client!r}")


def _batches(todo: list[int], points: Points, size: int):
    for start in range(0, len(todo), size):
        yield [(i, tuple(map(float, points.values[i]))) for i in todo[start:start + size]]


def sweep(target, points, *, metrics=None, out=None, client=None, n_workers: int | None = None,
          timeout: float | None = None, resume: bool = True, progress: bool = True, batch_size: int | None = None,
          retries: int = 2, vectorized: bool = False) -> np.ndarray:
    """Run ``target`` at every point and return one row per point as a structured array.

    Parameters
    ----------
    target : Cosim, callable
        ``cosim(...)``, or ``func(parameters: dict)`` returning a recorded structured array
        (reduced by ``metrics``) or a mapping of metric values; with ``vectorized=True``,
        ``func({name: array})`` returning ``{metric: array}`` for all points at once.
    points : Points, str, list of str, mapping
        ``grid(...)``, ``random_samples(...)`` or what ``grid`` takes.
    metrics : list of Metric or callables, or {name: callable}
        Reductions of a recorded run (``residual``, ``move_time``, ``peak`` or your own).
    out : path, optional
        ``.csv`` (rows appended as they arrive) or ``.parquet``.
    client : None, str or distributed.Client
        None starts a ``LocalCluster`` of ``n_workers`` (default: one per core) single-threaded
        worker processes for this sweep; a scheduler address or a client uses that cluster.
    timeout : float, optional
        Seconds a run may take before it is interrupted and recorded as "timeout".
    resume : bool
        Keep the rows already in ``out`` and run only the points without one.
    batch_size : int, optional
        Runs per Dask task (default: about ten tasks per worker, at most 20 runs each).
    retries : int
        Dask resubmissions of a task that raised (on top of the rescheduling of a lost worker's tasks).

    Returns
    -------
    numpy structured array with fields ``run``, the parameters, the metrics, ``status``,
    ``error`` and ``wall_time`` (s), in the order of ``points``.
    """
    points = _points(points)
    metric_list = _metric_list(metrics)
    if timeout is not None:
        timeout = check_positive(timeout, "timeout")
    if batch_size is not None and (isinstance(batch_size, bool) or not isinstance(batch_size, int) or batch_size < 1):
        raise ValueError(f"batch_size must be an integer >= 1, got {batch_size!r}")
    if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
        raise ValueError(f"retries must be an integer >= 0, got {retries!r}")
    if not isinstance(target, Cosim) and not callable(target):
        raise ValueError(f"target must be cosim(...) or a callable, got {type(target).__name__}; "
                         "for a system file use cosim(path, step=..., stop_time=..., record=[...])")
    if vectorized:
        if isinstance(target, Cosim) or metric_list:
            raise ValueError("vectorized=True takes a callable returning {metric: array}, without metrics=")
        return _sweep_vectorized(target, points, out)
    return _sweep_distributed(target, points, metric_list, out, client, n_workers, timeout, resume, progress,
                              batch_size, retries)


def _sweep_vectorized(func, points: Points, out) -> np.ndarray:
    start = time.perf_counter()
    result = func({n: points.values[:, j] for j, n in enumerate(points.names)})
    elapsed = time.perf_counter() - start
    if not isinstance(result, Mapping) or not result:
        raise ValueError(f"a vectorized target must return a non-empty {{metric: array}}, got {type(result).__name__}")
    values = {str(k): np.broadcast_to(np.asarray(v, dtype=float), (len(points),)) for k, v in result.items()}
    rows = []
    for i in range(len(points)):
        metric_values = {k: float(v[i]) for k, v in values.items()}
        finite = all(math.isfinite(v) for v in metric_values.values())
        rows.append({"run": i, **points.parameters(i), **metric_values, "status": "ok" if finite else "non-finite",
                     "error": "", "wall_time": elapsed / len(points)})
    header = columns(points.names, list(values))
    if out is not None:
        store = Store(out, header, resume=False)
        store.append(rows)
        store.close(rows)
    return as_array(rows, header)


def _sweep_distributed(target, points, metric_list, out, client, n_workers, timeout, resume, progress,
                       batch_size, retries):
    key_of = {tuple(map(float, points.values[i])): i for i in range(len(points))}
    store = None
    rows_by_run: dict[int, dict] = {}
    metric_names = [m.name for m in metric_list]
    if not metric_names and out is not None and resume:
        # A target returning {metric: value}: its metrics are known from the file being resumed.
        metric_names = metric_names_in_file(out, points.names)
    other_points = []  # rows of the output file for points outside this sweep: kept in the file
    if out is not None and metric_names:
        store = Store(out, columns(points.names, metric_names), resume)
        for row in store.done:
            i = key_of.get(tuple(row[n] for n in points.names))
            if i is not None:
                rows_by_run[i] = {**row, "run": i}
            else:
                other_points.append(row)
    todo = [i for i in range(len(points)) if i not in rows_by_run]
    meter = _Progress(len(points), len(rows_by_run), progress)
    c, cluster, opened = _open_client(client, n_workers) if todo else (None, None, False)
    try:
        unwritten = []  # rows that arrived before the metric names were known
        for rows in _run_on_cluster(c, target, points, todo, metric_list, timeout, batch_size, retries):
            meter.update(rows)
            if not metric_names:
                # A target returning {metric: value}: its first result names the metrics.
                unwritten += rows
                metric_names = list(dict.fromkeys(k for r in rows for k in r
                                                  if k not in FIXED_COLUMNS and k not in points.names))
                if not metric_names:
                    continue
                rows, unwritten = unwritten, []
                if out is not None:
                    store = Store(out, columns(points.names, metric_names), resume=False)
            rows = [_complete(r, points.names, metric_names) for r in rows]
            for row in rows:
                rows_by_run[row["run"]] = row
            if store is not None:
                store.append(rows)
        for row in unwritten:  # no run returned metrics
            rows_by_run[row["run"]] = _complete(row, points.names, metric_names)
        if unwritten and out is not None:
            store = Store(out, columns(points.names, metric_names), resume=False)
            store.append([rows_by_run[r["run"]] for r in unwritten])
    finally:
        meter.close()
        if opened:
            c.close()
        if cluster is not None:
            cluster.close()
        if store is not None:
            store.file.close()
    ordered = [rows_by_run[i] for i in range(len(points))]
    header = columns(points.names, metric_names)
    if store is not None:
        store.close(ordered + other_points)
    return as_array(ordered, header)


def _run_on_cluster(c, target, points, todo, metric_list, timeout, batch_size, retries):
    """Yield the rows of the points ``todo`` batch by batch, as they finish on the cluster."""
    from distributed import as_completed

    if not todo:
        return
    workers = max(1, sum(w["nthreads"] for w in c.scheduler_info()["workers"].values()))
    size = batch_size or max(1, min(20, len(todo) // (10 * workers)))
    plugin = None
    if isinstance(target, Cosim):
        plugin = _SystemFile(target)
        c.register_plugin(plugin, name=plugin.name)
        target = dataclasses.replace(target, data=b"")  # the bytes travel once per worker, in the plugin
    batches = _batches(todo, points, size)
    in_flight = as_completed()
    futures = {}

    def submit(batch):
        if batch is not None:
            future = c.submit(_run_batch, target, batch, points.names, metric_list, timeout, retries=retries,
                              pure=False)
            futures[future] = batch
            in_flight.add(future)

    try:
        # Bound the tasks in flight, so a million-point sweep does not sit in the scheduler at once.
        for _ in range(4 * workers):
            submit(next(batches, None))
        for future in in_flight:
            batch = futures.pop(future)
            try:
                rows = future.result()
            except Exception as error:  # noqa: BLE001 - e.g. KilledWorker: the batch's runs become rows
                rows = [{"run": i, **dict(zip(points.names, v)), "status": "error",
                         "error": f"{type(error).__name__}: {error}", "wall_time": math.nan} for i, v in batch]
            submit(next(batches, None))
            yield rows
    finally:
        if plugin is not None and c.status == "running":
            c.unregister_worker_plugin(plugin.name)


def _complete(row: dict, names, metric_names) -> dict:
    """The row with exactly the sweep's columns: NaN for a metric a failed run has no value of; a
    metric the target returned that the sweep does not know is an error of that run."""
    extra = set(row) - set(columns(names, metric_names))
    complete = {c: row.get(c, math.nan) for c in columns(names, metric_names)}
    if extra and complete["status"] == "ok":
        complete.update(status="error", error=f"ValueError: the target returned metrics {sorted(extra)} besides the "
                                              f"sweep's {metric_names}")
    return complete


# ---------------------------------------------------------------------------------------------
# The robustness map


def plot_map(rows: np.ndarray, metric: str, path, x: str, y: str | None = None) -> Path:
    """Plot ``metric`` against the parameter ``x`` (and ``y``) of a sweep's rows; save it as PNG.

    Points sharing (x, y) but differing in other parameters show their worst (largest) value: the
    map answers "how bad can it get here". Two parameters on a full grid give a colour map, scattered
    samples a coloured scatter; points with a run that is not "ok" are marked with a red x.
    """
    available = [n for n in rows.dtype.names if n not in FIXED_COLUMNS]
    for name, what in ((metric, "metric"), (x, "x"), (y, "y")):
        if name is not None and name not in available:
            raise ValueError(f"{what} must be one of the sweep's columns {available}, got {name!r}")
    from shapefmu.plots import plt, save_figure  # pyplot as shapefmu.plots set it up: the Agg backend

    axes = [a for a in (x, y) if a is not None]
    ok = rows["status"] == "ok"
    keys = np.stack([rows[a] for a in axes], axis=1)
    unique, inverse = np.unique(keys, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    worst = np.full(len(unique), -np.inf)
    np.maximum.at(worst, inverse[ok], rows[metric][ok])
    worst[np.isinf(worst)] = np.nan
    failed = np.zeros(len(unique), dtype=bool)
    failed[inverse[~ok]] = True
    fig, ax = plt.subplots(figsize=(7, 4.6))
    if y is None:
        ax.plot(unique[:, 0], worst, marker=".")
        ax.set_ylabel(metric)
        marks = np.zeros(int(failed.sum()))
    else:
        xs, ys = np.unique(unique[:, 0]), np.unique(unique[:, 1])
        if xs.size * ys.size == len(unique) and xs.size > 1 and ys.size > 1:
            image = ax.pcolormesh(xs, ys, worst.reshape(xs.size, ys.size).T, shading="nearest")
        else:
            image = ax.scatter(unique[:, 0], unique[:, 1], c=worst, s=16)
        fig.colorbar(image, ax=ax, label=metric)
        ax.set_ylabel(y)
        marks = unique[failed, 1]
    if np.any(failed):
        ax.plot(unique[failed, 0], marks, "rx", label="run not ok")
        ax.legend()
    ax.set_xlabel(x)
    ax.set_title(f"{metric}: worst over {len(rows)} runs")
    return save_figure(fig, path)


def summary(rows: np.ndarray, metrics: Sequence[str]) -> str:
    """Counts per status and the range of each metric over the "ok" runs."""
    counts = ", ".join(f"{int(np.sum(rows['status'] == s))} {s}" for s in STATUSES if np.any(rows["status"] == s))
    lines = [f"{len(rows)} runs: {counts}"]
    ok = rows[rows["status"] == "ok"]
    for name in metrics:
        if ok.size:
            worst = ok[np.argmax(ok[name])]
            at = ", ".join(f"{n} = {worst[n]:.6g}" for n in rows.dtype.names
                           if n not in FIXED_COLUMNS and n not in metrics)
            lines.append(f"{name}: min {ok[name].min():.6g}, max {ok[name].max():.6g} (at {at})")
    failed = rows[rows["status"] != "ok"]
    for row in failed[:5]:
        lines.append(f"run {row['run']}: {row['status']}: {row['error']}")
    if failed.size > 5:
        lines.append(f"... and {failed.size - 5} more runs not ok")
    return "\n".join(lines)
