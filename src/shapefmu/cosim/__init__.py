"""Co-simulation master: SSP systems of FMI 2.0 and 3.0 FMUs stepped by fmpy underneath.

``Master(system_or_path, step, ...)`` runs a :class:`shapefmu.fmi.ssp.System` (or an .ssp/.ssd
file) by fixed macro steps (Gauss-Seidel or Jacobi), integrates Model Exchange FMUs itself, solves
algebraic loops with FMU state rollback and records chosen variables; see :mod:`.master`.
It may import ``shapefmu.fmi`` and the layers below, never ``compare`` (the experiments that run it),
``sweep`` or ``cli``.
"""

from shapefmu import lazy_exports

# Imported on first use, so that a command writing an output file (``output_files``) loads no fmpy.
__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    "shapefmu.cosim.errors": ("AlgebraicLoopError", "CosimError", "CosimInterrupted", "Termination"),
    "shapefmu.cosim.master": ("ALGORITHMS", "Master", "simulate"),
    "shapefmu.cosim.output_files": ("save_results",),
})
