"""A folder of FMUs built on demand for ``shapefmu compare`` and the examples, rebuilt when what they
are built from changes."""

from __future__ import annotations

import functools
import hashlib
import json
from pathlib import Path

import numpy as np

from shapefmu.compare.plant import measured_plant
from shapefmu.files import write_text


class FMUCache:
    """A folder of FMUs built on demand: the slaves with default start values (parameters are bound
    per system) and measured plants. A file is rebuilt when its fingerprint (the slave's bundled
    sources, or the plant's matrices) differs from the one recorded in ``fingerprints.json``.
    With ``native`` the slaves are their native C twins (``shapefmu.fmi.native.twins``), in the
    subfolder ``native/``; with ``fmi_version`` "3.0" the twins and the plants are FMI 3.0 FMUs, in
    ``native3/``."""

    def __init__(self, directory, native: bool = False, fmi_version: str = "2.0"):
        if fmi_version != "2.0" and not native:
            raise ValueError(f"fmi_version {fmi_version} needs native: the pythonfmu FMUs are FMI 2.0 only")
        self.native, self.fmi_version = native, fmi_version
        # the slaves' subfolder; FMI 3.0 plants go with the FMI 3.0 slaves, FMI 2.0 ones at the top
        self.folder = "native3/" if fmi_version == "3.0" else "native/" if native else ""
        self.plant_folder = "native3/" if fmi_version == "3.0" else ""
        self.directory = Path(directory)
        self.directory.mkdir(parents=True, exist_ok=True)
        self._names: dict[Path, str] = {}  # slave FMU -> the model it is
        self._stamps_path = self.directory / "fingerprints.json"
        try:
            self._stamps = json.loads(self._stamps_path.read_text())
        except (OSError, ValueError):
            self._stamps = {}

    def _cached(self, file_name: str, fingerprint: str, build) -> Path:
        path = self.directory / file_name
        if not (path.is_file() and self._stamps.get(file_name) == fingerprint):
            path.parent.mkdir(exist_ok=True)
            build(path)
            self._stamps[file_name] = fingerprint
            write_text(self._stamps_path, json.dumps(self._stamps, indent=1, sort_keys=True), "FMU cache stamps")
        return path

    def slave(self, name: str, **start_values) -> Path:
        """``<name>.fmu`` for a kind of ``shapefmu.fmi.kinds`` (e.g. "Shaper", "STOSController");
        with ``start_values``, a copy with those baked in, ``<name>_<digest>.fmu``."""
        from shapefmu.fmi.python.builder import build_fmu, bundled_sources, package_name

        fingerprint = package_name(bundled_sources(name))
        build = build_fmu
        if self.native:
            from shapefmu.fmi.native.twins import build_native, fingerprint as native_fingerprint

            fingerprint += native_fingerprint(name)
            build = functools.partial(build_native, fmi_version=self.fmi_version)
        file_name = f"{self.folder}{name}.fmu"
        if start_values:
            baked = json.dumps(start_values, sort_keys=True)
            file_name = file_name.replace(".fmu", f"_{hashlib.sha256(baked.encode()).hexdigest()[:12]}.fmu")
            fingerprint += baked
        path = self._cached(file_name, fingerprint, lambda path: build(name, path, **elements(start_values)))
        self._names[path.resolve()] = name
        return path

    def model_of(self, fmu: Path) -> str | None:
        """The model name of a slave FMU this cache built, None for any other FMU (a plant)."""
        return self._names.get(Path(fmu).resolve())

    def plant(self, plant) -> Path:
        """The measured plant FMU (``measured_plant``) of a Plant or model file, e.g. DiskDriveMeasured.fmu."""
        from shapefmu.fmi.native import build_plant_fmu, fmu_file_name
        from shapefmu.plants import as_plant

        plant = as_plant(plant)
        digest = hashlib.sha256(b"".join(np.ascontiguousarray(m).tobytes() for m in (plant.A, plant.B)))
        digest.update(repr((plant.name, plant.inputs)).encode())
        model = measured_plant(plant)
        return self._cached(self.plant_folder + fmu_file_name(model.name), digest.hexdigest(),
                            lambda path: build_plant_fmu(model, path, fmi_version=self.fmi_version))


def elements(values: dict) -> dict:
    """``values`` with each array value (an FMI 3.0 array parameter, a list) as its elements
    ``name[1]``, ``name[2]``, ...: the start values a twin is built from name elements."""
    flat = {}
    for name, value in values.items():
        if isinstance(value, (list, tuple)):
            flat.update({f"{name}[{i}]": item for i, item in enumerate(value, start=1)})
        else:
            flat[name] = value
    return flat
