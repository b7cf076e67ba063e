"""FMI packaging: everything that turns a design into an FMU or a system of FMUs.

It knows FMI and nothing about the mathematics beyond calling ``shapefmu.runtime``; it may import
the design layer and ``runtime/``, never ``cosim``, ``compare``, ``sweep`` or ``cli``. Its rooms:

- ``fmi.kinds``: every FMU kind declared once, its interface (variables, units, descriptions,
  start values) and its model (what it computes with ``runtime/``);
- ``fmi.description``: one model description per built FMU and one writer per FMI version;
- ``fmi.python``: pythonfmu FMUs — the slave that runs a kind's model, the builder that bundles it
  with ``runtime/`` into each FMU, and the C front end (``shim/``) that loads Python;
- ``fmi.native``: native C FMUs — the generic FMI layers (``c/``), the plant-FMU generator that emits
  only a model part for them, and the native twins of the kinds (``fmi.native.twins``);
- ``fmi.ssp``: SSP system descriptions (``.ssd`` / ``.ssp``) read and written.

``build_fmu`` / ``build_all`` turn the kinds of ``shapefmu.fmi.kinds`` into pythonfmu FMUs.
"""

from shapefmu.fmi.python.builder import build_all, build_fmu

__all__ = ["build_all", "build_fmu"]
