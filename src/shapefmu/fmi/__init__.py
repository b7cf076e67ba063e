"""FMI packaging: pythonfmu slaves and their builder, the plant-FMU generator, SSP files.

This layer knows FMI and nothing about the mathematics beyond calling ``shapefmu.runtime``.
``build_fmu`` / ``build_all`` turn the slaves registered in ``shapefmu.fmi.slaves`` into FMUs.
"""

from shapefmu.fmi.builder import build_all, build_fmu

__all__ = ["build_all", "build_fmu"]
