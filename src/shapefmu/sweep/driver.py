"""The sweep itself: ``sweep()`` maps a target over the points on a Dask cluster (client, batches,
retries, timeouts, progress) or, vectorized, over all points at once in this process.

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
skips the points that already have a row there (``retry_failed=True``: except those whose row is an
error or a timeout). When the sweep ends the file is written anew with one row per point.
"""

from __future__ import annotations

import dataclasses
import math
import os
import sys
import time
from collections.abc import Mapping

import numpy as np

from shapefmu.cosim.output_files import output_lock
from shapefmu.files import check_output
from shapefmu.runtime import limits
from shapefmu.runtime.checks import check_positive
from shapefmu.sweep.metrics import _metric_list
from shapefmu.sweep.points import Points, _points
from shapefmu.sweep.runs import _run_batch
from shapefmu.sweep.store import FIXED_COLUMNS, Store, as_array, columns, metric_names_in_file
from shapefmu.sweep.target import Cosim, _SystemFile


# Statuses of a resumed row that ``retry_failed`` runs again: the run did not give its answer.
RETRIED_STATUSES = ("error", "timeout")


class SweepRows(np.ndarray):
    """A sweep's rows (a numpy structured array), knowing how many were resumed from its output file."""

    resumed = 0
    resumed_failed = 0


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

    def announce(self, text: str) -> None:
        """One line before the work starts (the cluster's start, which takes seconds)."""
        if self.enabled:
            self.stream.write(f"sweep: {text}\n")
            self.stream.flush()

    def close(self):
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()


# ---------------------------------------------------------------------------------------------
# The sweep


def check_workers(n_workers, name: str = "n_workers"):
    """``n_workers`` if None or a count of local worker processes this machine can run: an integer
    >= 1 and at most ``limits.MAX_WORKERS_PER_CORE`` per core (``name`` says what the caller called it)."""
    if n_workers is None:
        return None
    if isinstance(n_workers, bool) or not isinstance(n_workers, int) or n_workers < 1:
        raise ValueError(f"{name} must be an integer >= 1 (worker processes of the local cluster), got {n_workers!r}")
    cores = os.cpu_count() or 1
    if n_workers > limits.MAX_WORKERS_PER_CORE * cores:
        raise ValueError(f"{name} must be at most {limits.MAX_WORKERS_PER_CORE * cores} worker processes on this "
                         f"machine's {cores} core(s) (shapefmu.runtime.limits.MAX_WORKERS_PER_CORE = "
                         f"{limits.MAX_WORKERS_PER_CORE}), got {n_workers}; a cluster takes a scheduler address")
    return n_workers


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
        try:  # a wrong address times out; a server that is no Dask scheduler fails the handshake in
            # whatever way its bytes make Dask's protocol fail (a MemoryError for an HTTP server)
            return Client(client, timeout=SCHEDULER_TIMEOUT), None, True
        except Exception as error:  # noqa: BLE001 -- any failure here means: no scheduler at that address
            raise ValueError(f"scheduler {client!r}: no Dask scheduler answered within {SCHEDULER_TIMEOUT} s "
                             f"({type(error).__name__}: {str(error)[:200]})") from None
    if isinstance(client, Client):
        return client, None, False
    raise ValueError(f"client must be None, a scheduler address such as 'tcp://host:8786' or a distributed.Client, "
                     f"got {client!r}")


SCHEDULER_TIMEOUT = 10  # s: a scheduler that answers at all answers in well under a second


def _batches(todo: list[int], points: Points, size: int):
    for start in range(0, len(todo), size):
        yield [(i, tuple(map(float, points.values[i]))) for i in todo[start:start + size]]


def sweep(target, points, *, metrics=None, out=None, client=None, n_workers: int | None = None,
          timeout: float | None = None, resume: bool = True, progress: bool = True, batch_size: int | None = None,
          retries: int = 2, vectorized: bool = False, retry_failed: bool = False) -> SweepRows:
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
    retry_failed : bool
        With ``resume``, run again the points whose row in ``out`` is an "error" or a "timeout" (a
        "non-finite" result is the run's answer, and is kept); the new row replaces the old one.
    batch_size : int, optional
        Runs per Dask task (default: about ten tasks per worker, at most 20 runs each).
    retries : int
        Dask resubmissions of a task that raised (on top of the rescheduling of a lost worker's tasks).

    Returns
    -------
    SweepRows
        A numpy structured array with fields ``run``, the parameters, the metrics, ``status``,
        ``error`` and ``wall_time`` (s), in the order of ``points``; ``rows.resumed`` of them were
        read from ``out`` rather than run (``rows.resumed_failed`` of those an "error" or a "timeout").
    """
    points = _points(points)
    metric_list = _metric_list(metrics)
    if timeout is not None:
        timeout = check_positive(timeout, "timeout")
    check_workers(n_workers)
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
        return _sweep_vectorized(target, points, out).view(SweepRows)
    return _sweep_distributed(target, points, metric_list, out, client, n_workers, timeout, resume, progress,
                              batch_size, retries, retry_failed)


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
        with output_lock(out):
            Store(out, header, resume=False).close(rows)
    return as_array(rows, header)


def _sweep_distributed(target, points, metric_list, out, client, n_workers, timeout, resume, progress,
                       batch_size, retries, retry_failed):
    """One writer of ``out`` at a time (``output_lock``): a second sweep on the file is refused."""
    if out is None:
        return _sweep_into(target, points, metric_list, None, client, n_workers, timeout, resume, progress,
                           batch_size, retries, retry_failed)
    check_output(out, "sweep output")
    with output_lock(out):
        return _sweep_into(target, points, metric_list, out, client, n_workers, timeout, resume, progress,
                           batch_size, retries, retry_failed)


def _sweep_into(target, points, metric_list, out, client, n_workers, timeout, resume, progress,
                batch_size, retries, retry_failed):
    key_of = {tuple(map(float, points.values[i])): i for i in range(len(points))}
    store = None
    rows_by_run: dict[int, dict] = {}
    metric_names = [m.name for m in metric_list]
    if not metric_names and out is not None and resume:
        # A target returning {metric: value}: its metrics are known from the file being resumed.
        metric_names = metric_names_in_file(out, points.names)
    other_points = {}  # rows of the output file for points outside this sweep: kept in the file
    if out is not None and metric_names:
        store = Store(out, columns(points.names, metric_names), resume)
        for row in store.done:  # in file order: a point's later row (a retried run) replaces its earlier one
            key = tuple(row[n] for n in points.names)
            if key in key_of:
                rows_by_run[key_of[key]] = {**row, "run": key_of[key]}
            else:
                other_points[key] = row
    if retry_failed:
        for i in [i for i, row in rows_by_run.items() if row["status"] in RETRIED_STATUSES]:
            del rows_by_run[i]
    resumed = dict(rows_by_run)
    todo = [i for i in range(len(points)) if i not in rows_by_run]
    meter = _Progress(len(points), len(rows_by_run), progress)
    if todo and client is None:
        meter.announce(f"starting a local Dask cluster of {n_workers or os.cpu_count() or 1} worker processes "
                       f"for {len(todo)} runs (the first takes a while: each worker imports shapefmu and opens the system)")
    elif todo and isinstance(client, str):
        meter.announce(f"connecting to the Dask scheduler at {client} for {len(todo)} runs")
    c, cluster, opened = _open_client(client, n_workers) if todo else (None, None, False)
    if store is not None:
        store.open()  # the file changes only now: every check passed and the cluster answers
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
        if store is not None and store.file is not None:
            store.file.close()
    ordered = [rows_by_run[i] for i in range(len(points))]
    header = columns(points.names, metric_names)
    if store is not None:
        store.close(ordered + list(other_points.values()))
    rows = as_array(ordered, header).view(SweepRows)
    rows.resumed = len(resumed)
    rows.resumed_failed = sum(row["status"] in RETRIED_STATUSES for row in resumed.values())
    return rows


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
