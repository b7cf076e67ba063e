"""``shapefmu compare``: one plant, every candidate command, run as SSP systems of FMUs by the master.

An experiment above the master (DESIGN.md's top floor, beside ``sweep/``): ``candidates`` (the
comparison and its results), ``systems`` (each candidate's SSP system), ``cache`` (the FMUs, built on
demand), ``plant`` (the plant with its velocity measured), ``metrics`` (one rule for every run) and
``plot``. See :mod:`shapefmu.compare.candidates` for what each candidate is.
"""

from shapefmu.compare.cache import FMUCache, elements
from shapefmu.compare.candidates import CANDIDATES, CandidateRun, Comparison, compare
from shapefmu.compare.metrics import MoveMetrics, move_metrics
from shapefmu.compare.plant import measured_plant
from shapefmu.compare.plot import plot_compare
from shapefmu.compare.systems import stos_system

__all__ = ["CANDIDATES", "CandidateRun", "Comparison", "FMUCache", "MoveMetrics", "compare", "elements",
           "measured_plant", "move_metrics", "plot_compare", "stos_system"]
