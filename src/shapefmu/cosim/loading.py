"""Open the FMUs of a system: each file extracted once, each component the unit of its FMI version.

Beside ``units`` (FMI 2.0) and ``units3`` (FMI 3.0), so neither of those imports the other's callers.
A binary that is missing or cannot be loaded (a library it needs is absent: a libgfortran, a
runtime of the exporting tool) is refused naming the component, the file and what the loader said.
"""

from __future__ import annotations

import os
from pathlib import Path

import fmpy
from fmpy import extract, read_model_description

from shapefmu.cosim.types import array_size
from shapefmu.cosim.units import ModelExchangeUnit, Unit
from shapefmu.cosim.units3 import ModelExchangeUnit3, Unit3
from shapefmu.runtime import limits


def _check_arrays(name: str, fmu: Path, description) -> None:
    """Refuse an array the master could not hold before anything is allocated (limits.MAX_ARRAY_ELEMENTS)."""
    for variable in description.modelVariables:
        size = array_size(variable)
        if size is not None and size > limits.MAX_ARRAY_ELEMENTS:
            raise ValueError(f"component {name!r}: {fmu.name} declares {variable.name} an array of {size:,} elements, "
                             f"more than the {limits.MAX_ARRAY_ELEMENTS:,} the master takes "
                             f"(shapefmu.runtime.limits.MAX_ARRAY_ELEMENTS)")


def load_units(components: list[tuple[str, Path]], model_exchange: set[str]) -> tuple[list[Unit], list[str]]:
    """Instantiate every (name, fmu) pair; each FMU file is extracted once and shared by its instances."""
    extracted: dict[Path, tuple[str, object]] = {}
    units, folders = [], []
    try:
        for name, fmu in components:
            fmu = Path(fmu).resolve()
            if fmu not in extracted:
                description = read_model_description(str(fmu), validate=False)
                _check_arrays(name, fmu, description)
                folder = extract(str(fmu))
                folders.append(folder)
                extracted[fmu] = (folder, description)
            folder, description = extracted[fmu]
            if description.fmiVersion == "2.0":
                cs, me = Unit, ModelExchangeUnit
            elif description.fmiVersion.startswith("3."):
                cs, me = Unit3, ModelExchangeUnit3
            else:
                raise ValueError(f"component {name!r}: {fmu.name} is FMI {description.fmiVersion}; the master runs FMI 2.0 and 3.0")
            if name in model_exchange:
                if description.modelExchange is None:
                    raise ValueError(f"component {name!r}: {fmu.name} has no Model Exchange interface")
                kind = me
            elif description.coSimulation is not None:
                kind = cs
            elif description.modelExchange is not None:
                kind = me
            else:
                raise ValueError(f"component {name!r}: {fmu.name} has neither a Co-Simulation nor a Model Exchange interface")
            units.append(_load(kind, name, fmu, folder, description))
    except BaseException:
        for unit in units:
            unit.free()
        raise
    return units, folders


def _load(kind: type[Unit], name: str, fmu: Path, folder: str, description) -> Unit:
    """``kind(name, fmu, folder, description)``, its binary checked first, and the working directory
    kept: fmpy changes into the binary's folder to load it and stays there when loading fails."""
    interface = description.modelExchange if kind.interface == "ModelExchange" else description.coSimulation
    platform = fmpy.platform_tuple if kind.fmi3 else fmpy.platform
    binary = f"binaries/{platform}/{interface.modelIdentifier}{fmpy.sharedLibraryExtension}"
    if not (Path(folder) / binary).is_file():
        found = sorted(str(path.relative_to(folder)) for path in (Path(folder) / "binaries").rglob("*") if path.is_file())
        raise ValueError(f"component {name!r} ({fmu.name}): no {binary} in the FMU "
                         f"(its binaries: {', '.join(found) or 'none'})")
    here = os.getcwd()
    try:
        return kind(name, fmu, folder, description)
    except ValueError:
        raise
    except Exception as error:  # fmpy's: "Failed to load shared library <path>. <the loader's message>", ...
        prefix = f"Failed to load shared library {Path(folder) / binary}. "
        if str(error).startswith(prefix):
            raise ValueError(f"component {name!r} ({fmu.name}): {binary} cannot be loaded: "
                             f"{str(error)[len(prefix):]}") from None
        raise ValueError(f"component {name!r} ({fmu.name}): {error}") from None
    finally:
        os.chdir(here)
