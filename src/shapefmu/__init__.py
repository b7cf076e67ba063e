"""shapefmu: vibration-suppressing commands and controllers for flexible machines, as FMI 2.0 FMUs.

Layers (each imports only the layers below it, see DESIGN.md):

- ``runtime``: per-sample kernels, Python standard library only (copied into every FMU);
- ``shapers``, ``analysis``: the design layer (numpy / scipy);
- ``cli``: the command line.
"""

__version__ = "0.1.0"
