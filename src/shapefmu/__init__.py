"""shapefmu: vibration-suppressing commands and controllers for flexible machines, as FMI 2.0/3.0 FMUs.

The main API is here, imported on first use (PEP 562), so ``import shapefmu`` and the command line
load no numpy until a name is used::

    import shapefmu
    shaper = shapefmu.zvd(2 * math.pi * 40.0, 0.05)          # omega in rad/s (40 Hz), zeta
    shapefmu.residual_vibration(shaper, 2 * math.pi * 42.0, 0.05)
    shapefmu.build_fmu("Shaper", "fmus/Shaper.fmu", kind="zvd", **{"f[1]": 40.0})
    with shapefmu.Master("system.ssp", 1e-4) as master:
        results = master.run(1.0)

Layers, lowest first; a module imports only its own layer and those below (DESIGN.md;
``tests/test_layers.py`` enforces it, and that no two modules import each other):

- ``runtime``: per-sample kernels, Python standard library only (copied into every FMU);
- the design layer: ``shapers``, ``analysis``, ``estimation``, ``stos``, ``optimal``, ``plants``,
  ``plots``, ``identification`` (numpy / scipy / casadi / python-control);
- ``fmi``: FMUs (``fmi.python`` pythonfmu FMUs, ``fmi.native`` C FMUs) and SSP files (``fmi.ssp``);
- ``cosim``: the co-simulation master;
- ``sweep``, ``cli``: experiments (Dask sweeps; the command line, a module per command group).
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"


def lazy_exports(package: str, exports: dict[str, tuple[str, ...]]):
    """``(__getattr__, __dir__, __all__)`` for a package whose public names live in modules imported
    on first use (PEP 562): ``exports`` maps a module to the names taken from it."""
    where = {name: module for module, names in exports.items() for name in names}

    def __getattr__(name: str):
        if name not in where:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(where[name]), name)
        globals_of_package = importlib.import_module(package).__dict__
        globals_of_package[name] = value  # found directly from now on
        return value

    def __dir__():
        return sorted({*importlib.import_module(package).__dict__, *where})

    return __getattr__, __dir__, sorted(where)


__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    "shapefmu.shapers": ("design", "zv", "zvd", "zvdd", "zv_dn", "mzv", "um_zv", "ei", "ei2", "ei3", "simultaneous",
                         "convolve_modes", "hanning_filter", "blackman_filter", "time_frequency_profile",
                         "ImpulseShaper", "SampledShaper"),
    "shapefmu.analysis": ("residual_vibration", "sensitivity", "insensitivity"),
    "shapefmu.estimation": ("estimate_mode", "EKFTunedShaper"),
    "shapefmu.plants": ("Plant", "load", "as_plant"),
    "shapefmu.optimal": ("time_optimal",),
    "shapefmu.stos": ("stos_law", "simulate_stos"),
    "shapefmu.identification": ("identify", "recommend", "read_recording"),
    "shapefmu.fmi.python.builder": ("build_fmu",),
    "shapefmu.fmi.native": ("build_plant_fmu",),
    "shapefmu.fmi.ssp": ("System", "read_ssp"),
    "shapefmu.cosim": ("Master",),
})
