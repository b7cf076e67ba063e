"""shapefmu: vibration-suppressing commands and controllers for flexible machines, as FMI 2.0 FMUs.

Layers, lowest first; a module imports only its own layer and those below (DESIGN.md;
``tests/test_layers.py`` enforces it, and that no two modules import each other):

- ``runtime``: per-sample kernels, Python standard library only (copied into every FMU);
- the design layer: ``shapers``, ``analysis``, ``estimation``, ``stos``, ``optimal``, ``plants``,
  ``plots`` (numpy / scipy / casadi / python-control);
- ``fmi``: FMUs (``fmi.python`` pythonfmu FMUs, ``fmi.native`` C FMUs) and SSP files (``fmi.ssp``);
- ``cosim``: the co-simulation master;
- ``sweep``, ``cli``: experiments (Dask sweeps; the command line, a module per command group).
"""

__version__ = "0.1.0"
