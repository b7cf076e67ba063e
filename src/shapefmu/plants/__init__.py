"""Plant models: linear models with named signals and physical parameters (``Plant``), the plants
of the papers (``library``), the declarative model files of ``models/`` (``loader``), the ones
that ship with shapefmu, found by name (``shipped``), plants whose parameters follow a scheduling
input (``scheduling``) and sample-by-sample runs of them (``simulation``).

Design layer: imports ``runtime`` and numpy / scipy / python-control; arrows run
loader -> library -> model, loader -> shipped, loader -> scheduling -> model, simulation -> scheduling.
The names below are imported on first use, so ``shapefmu plant list`` (``shipped``, standard library
only) starts without python-control.
"""

from shapefmu import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    "shapefmu.plants.library": ("disk_drive", "linear_synchronous_motor", "mass_spring_chain", "pendula",
                                "rigid_flexible", "sprung_masses", "ten_pendula", "transfer_function"),
    "shapefmu.plants.loader": ("KINDS", "as_plant", "describe", "load", "load_scheduled", "loads",
                               "loads_scheduled"),
    "shapefmu.plants.model": ("Mode", "Parameter", "Plant", "rigid_part"),
    "shapefmu.plants.scheduling": ("ModeCurve", "ScheduledPlant", "SchedulingInput"),
})
