"""Every FMU the tests build, built once per test session: the same arguments give the same file.

    builds                      session fixture: a Builds in a session folder
    Builds.pythonfmu(model, **start_values) -> Path        shapefmu.fmi.build_fmu
    Builds.native(model, fmi_version="2.0", clock=False, **start_values) -> Path
                                                            shapefmu.fmi.native.twins.build_native
    Builds.plant(model_file, fmi_version="2.0") -> Path    shapefmu.fmi.native.build_plant_fmu (a .toml or .py model)
    Builds.many({key: (method, args, kwargs)}) -> {key: Path}: several at once, two compiling at a time

Each FMU has a file name of its own (model-N.fmu), as hosts that extract by name expect. A native
build is three C compilations (linux64, win64, aarch64) in subprocesses, so two run side by
side; pythonfmu builds run one at a time, in the caller's thread.
"""

from __future__ import annotations

import json
import threading
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

import pytest


class Builds:
    def __init__(self, folder: Path):
        self.folder = Path(folder)
        self._futures: dict[str, Future] = {}
        self._lock = threading.Lock()
        self._pythonfmu_lock = threading.Lock()
        self._pool = ThreadPoolExecutor(2)

    def _submit(self, key: str, build) -> Future:
        with self._lock:
            if key not in self._futures:
                self._futures[key] = self._pool.submit(build, self.folder / f"{len(self._futures)}")
            return self._futures[key]

    @staticmethod
    def _key(*parts, **start_values) -> str:
        return json.dumps([parts, start_values], sort_keys=True, default=str)

    def _native_future(self, model: str, fmi_version: str = "2.0", clock: bool = False, **start_values) -> Future:
        from shapefmu.fmi.native.twins import build_native

        def build(folder):
            folder.mkdir()
            return build_native(model, folder / f"{model}-{folder.name}.fmu", fmi_version=fmi_version, clock=clock,
                                **start_values)

        return self._submit(self._key("native", model, fmi_version, clock, **start_values), build)

    def _plant_future(self, model_file, fmi_version: str = "2.0") -> Future:
        from shapefmu.fmi.native import build_plant_fmu, model_from_file

        def build(folder):
            folder.mkdir()
            return build_plant_fmu(model_from_file(str(model_file)), folder / f"{Path(model_file).stem}-{folder.name}.fmu",
                                   fmi_version=fmi_version)

        return self._submit(self._key("plant", str(Path(model_file).resolve()), fmi_version), build)

    def native(self, model: str, fmi_version: str = "2.0", clock: bool = False, **start_values) -> Path:
        return self._native_future(model, fmi_version, clock, **start_values).result()

    def plant(self, model_file, fmi_version: str = "2.0") -> Path:
        return self._plant_future(model_file, fmi_version).result()

    def pythonfmu(self, model: str, **start_values) -> Path:
        from shapefmu.fmi import build_fmu

        key = self._key("pythonfmu", model, **start_values)
        with self._pythonfmu_lock:
            with self._lock:
                done = self._futures.get(key)
            if done is None:
                folder = self.folder / f"{len(self._futures)}"
                folder.mkdir()
                done = Future()
                done.set_result(build_fmu(model, folder / f"{model}-{folder.name}.fmu", **start_values))
                with self._lock:
                    self._futures[key] = done
        return done.result()

    def many(self, jobs: dict) -> dict:
        """{key: (method name, args, kwargs)} built with the native and plant builds side by side."""
        futures = {key: getattr(self, f"_{method}_future")(*args, **kwargs)
                   for key, (method, args, kwargs) in jobs.items() if method != "pythonfmu"}
        paths = {key: self.pythonfmu(*args, **kwargs) for key, (method, args, kwargs) in jobs.items()
                 if method == "pythonfmu"}
        return {key: paths[key] if key in paths else futures[key].result() for key in jobs}

    def close(self) -> None:
        self._pool.shutdown(wait=True)


@pytest.fixture(scope="session")
def builds(tmp_path_factory):
    built = Builds(tmp_path_factory.mktemp("builds"))
    yield built
    built.close()
