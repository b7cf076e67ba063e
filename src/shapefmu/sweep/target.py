"""The co-simulation target of a sweep and its worker side: the system file shipped to the workers
in a Dask worker plugin, and the masters each worker process opens once and reuses."""

from __future__ import annotations

import atexit
import hashlib
import os
import tempfile
import threading
from collections import OrderedDict
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from shapefmu.files import write_bytes
from shapefmu.runtime.checks import check_positive, check_size

try:
    from distributed import WorkerPlugin
except ImportError:  # the analytic path, the metrics and the output files work without Dask
    WorkerPlugin = object


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
    # the master's own bound, checked before any run is sent out (a denormal step: inf steps)
    check_size(stop_time / step, "MAX_MACRO_STEPS", f"a run to {stop_time!r} s by steps of {step!r} s takes",
               "macro steps", "take a longer step or a shorter run")
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
        write_bytes(path, self.data, "system file")
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
