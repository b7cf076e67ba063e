"""Open the FMUs of a system: each file extracted once, each component the unit of its FMI version.

Beside ``units`` (FMI 2.0) and ``units3`` (FMI 3.0), so neither of those imports the other's callers.
"""

from __future__ import annotations

from pathlib import Path

from fmpy import extract, read_model_description

from shapefmu.cosim.units import ModelExchangeUnit, Unit
from shapefmu.cosim.units3 import ModelExchangeUnit3, Unit3


def load_units(components: list[tuple[str, Path]], model_exchange: set[str]) -> tuple[list[Unit], list[str]]:
    """Instantiate every (name, fmu) pair; each FMU file is extracted once and shared by its instances."""
    extracted: dict[Path, tuple[str, object]] = {}
    units, folders = [], []
    try:
        for name, fmu in components:
            fmu = Path(fmu).resolve()
            if fmu not in extracted:
                description = read_model_description(str(fmu), validate=False)
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
                units.append(me(name, fmu, folder, description))
            elif description.coSimulation is not None:
                units.append(cs(name, fmu, folder, description))
            elif description.modelExchange is not None:
                units.append(me(name, fmu, folder, description))
            else:
                raise ValueError(f"component {name!r}: {fmu.name} has neither a Co-Simulation nor a Model Exchange interface")
    except BaseException:
        for unit in units:
            unit.free()
        raise
    return units, folders

