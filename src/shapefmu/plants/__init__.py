"""Plant models: linear models with named signals and physical parameters (``Plant``), the plants
of the papers (``library``), the declarative model files of ``models/`` (``loader``), the ones
that ship with shapefmu, found by name (``shipped``), plants whose parameters follow a scheduling
input (``scheduling``) and sample-by-sample runs of them (``simulation``).

Design layer: imports ``runtime`` and numpy / scipy / python-control; arrows run
loader -> library -> model, loader -> shipped, loader -> scheduling -> model, simulation -> scheduling.
"""

from shapefmu.plants.library import (
    disk_drive,
    linear_synchronous_motor,
    mass_spring_chain,
    pendula,
    rigid_flexible,
    sprung_masses,
    ten_pendula,
    transfer_function,
)
from shapefmu.plants.loader import KINDS, as_plant, describe, load, load_scheduled, loads, loads_scheduled
from shapefmu.plants.model import Mode, Parameter, Plant, rigid_part
from shapefmu.plants.scheduling import ModeCurve, ScheduledPlant, SchedulingInput

__all__ = [
    "KINDS",
    "Mode",
    "ModeCurve",
    "Parameter",
    "Plant",
    "ScheduledPlant",
    "SchedulingInput",
    "as_plant",
    "describe",
    "disk_drive",
    "linear_synchronous_motor",
    "load",
    "load_scheduled",
    "loads",
    "loads_scheduled",
    "mass_spring_chain",
    "pendula",
    "rigid_flexible",
    "rigid_part",
    "sprung_masses",
    "ten_pendula",
    "transfer_function",
]
