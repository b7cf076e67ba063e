"""Runs on a worker: one run under the sweep's timeout, and a batch of runs as rows (what a Dask
task of the sweep executes)."""

from __future__ import annotations

import ctypes
import math
import threading
import time
from collections.abc import Mapping

from shapefmu.sweep.metrics import Metric
from shapefmu.sweep.store import FIXED_COLUMNS
from shapefmu.sweep.target import _OPENED, Cosim, _run_cosim


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
