"""Plant models: linear models with named signals and physical parameters (``Plant``), the plants
of the papers (``library``), the declarative model files of ``models/`` (``loader``) and the ones
that ship with shapefmu, found by name (``shipped``).

Design layer: imports ``runtime`` and numpy / scipy / python-control; arrows run
loader -> library -> model, loader -> shipped. The names below are imported on first use, so
``shapefmu plant list`` (``shipped``, standard library only) starts without python-control.
"""

from shapefmu import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    "shapefmu.plants.library": ("disk_drive", "linear_synchronous_motor", "mass_spring_chain", "pendula",
                                "rigid_flexible", "ten_pendula", "transfer_function"),
    "shapefmu.plants.loader": ("KINDS", "as_plant", "describe", "load", "loads"),
    "shapefmu.plants.model": ("Mode", "Parameter", "Plant", "rigid_part"),
})
