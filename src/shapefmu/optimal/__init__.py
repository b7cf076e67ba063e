"""Time-optimal rest-to-rest moves of a linear plant under |u| <= u_max, and shaped moves beside them;
the minimum time of a jerk-limited move with residual-vibration bounds (``jerk_limited_optimum``).

Design layer: may import shapefmu.plants, .shapers, .analysis, .runtime and numpy, scipy, casadi,
mpmath; never shapefmu.fmi, .cosim, .cli or .sweep.
"""

# The modules import one way only: comparison and certificate -> solution -> refinement and
# transcription -> moves (certificate also reads refinement's and transcription's helpers); jerk_limited
# (the jerk-limited move with vibration bounds) stands alone.
from shapefmu.optimal.certificate import OptimalityCheck, check_optimality
from shapefmu.optimal.comparison import (Move, MoveComparison, compare_moves, optimal_report, plot_comparison,
                                         rigid_bang_bang)
from shapefmu.optimal.jerk_limited import AxisOptimum, JerkOptimum, axis_optimum, jerk_limited_optimum
from shapefmu.optimal.moves import Command, check_controllable, residual_after_move, rest_state, simulate
from shapefmu.optimal.refinement import refine, refine_exact
from shapefmu.optimal.solution import TimeOptimalSolution, refine_transcription, time_optimal
from shapefmu.optimal.transcription import Transcription, lp_transcription, transcribe

__all__ = [
    "AxisOptimum",
    "Command",
    "JerkOptimum",
    "axis_optimum",
    "jerk_limited_optimum",
    "Move",
    "MoveComparison",
    "OptimalityCheck",
    "TimeOptimalSolution",
    "Transcription",
    "check_controllable",
    "check_optimality",
    "compare_moves",
    "lp_transcription",
    "optimal_report",
    "plot_comparison",
    "refine",
    "refine_exact",
    "refine_transcription",
    "residual_after_move",
    "rest_state",
    "rigid_bang_bang",
    "simulate",
    "time_optimal",
    "transcribe",
]
