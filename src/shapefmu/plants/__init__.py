"""Plant models: linear models with named signals and physical parameters (``Plant``), the plants
of the papers (``library``), the declarative model files of ``models/`` (``loader``) and the ones
that ship with shapefmu, found by name (``shipped``).

Design layer: imports ``runtime`` and numpy / scipy / python-control; arrows run
loader -> library -> model, loader -> shipped.
"""

from shapefmu.plants.library import (
    disk_drive,
    linear_synchronous_motor,
    mass_spring_chain,
    pendula,
    rigid_flexible,
    ten_pendula,
    transfer_function,
)
from shapefmu.plants.loader import KINDS, as_plant, describe, load, loads
from shapefmu.plants.model import Mode, Parameter, Plant, rigid_part

__all__ = [
    "KINDS",
    "Mode",
    "Parameter",
    "Plant",
    "as_plant",
    "describe",
    "disk_drive",
    "linear_synchronous_motor",
    "load",
    "loads",
    "mass_spring_chain",
    "pendula",
    "rigid_flexible",
    "rigid_part",
    "ten_pendula",
    "transfer_function",
]
