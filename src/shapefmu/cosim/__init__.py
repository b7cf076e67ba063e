"""Co-simulation master: SSP systems of FMI 2.0 and 3.0 FMUs stepped by fmpy underneath.

``Master(system_or_path, step, ...)`` runs a :class:`shapefmu.fmi.ssp.System` (or an .ssp/.ssd
file) by fixed macro steps (Gauss-Seidel or Jacobi), integrates Model Exchange FMUs itself, solves
algebraic loops with FMU state rollback and records chosen variables; see :mod:`.master`.
It may import ``shapefmu.fmi`` and the layers below, never ``compare`` (the experiments that run it),
``sweep`` or ``cli``.
"""

from shapefmu.cosim.errors import AlgebraicLoopError, CosimError, CosimInterrupted, Termination
from shapefmu.cosim.master import ALGORITHMS, Master, simulate
from shapefmu.cosim.output_files import save_results

__all__ = ["ALGORITHMS", "AlgebraicLoopError", "CosimError", "CosimInterrupted", "Master", "Termination", "save_results", "simulate"]
