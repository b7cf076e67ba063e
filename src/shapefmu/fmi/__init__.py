"""FMI packaging: everything that turns a design into an FMU or a system of FMUs.

It knows FMI and nothing about the mathematics beyond calling ``shapefmu.runtime``; it may import
the design layer and ``runtime/``, never ``cosim``, ``sweep`` or ``cli``. Three rooms:

- ``fmi.python``: pythonfmu FMUs — the slave classes (``slaves/``), their common base, the builder
  that bundles ``runtime/`` into each FMU, and the C front end (``shim/``) that loads Python;
- ``fmi.native``: native C FMUs — the one hand-written generic FMI 2.0 layer (``c/``), the
  plant-FMU generator that emits only a model part for it, and the native Shaper and ShapeFilter
  (``fmi.native.sampled``), linux64 and win64;
- ``fmi.ssp``: SSP system descriptions (``.ssd`` / ``.ssp``) read and written.

``build_fmu`` / ``build_all`` turn the slaves registered in ``shapefmu.fmi.python.slaves`` into FMUs.
"""

from shapefmu.fmi.python.builder import build_all, build_fmu

__all__ = ["build_all", "build_fmu"]
