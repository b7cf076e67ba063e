"""Online jerk-limited multi-axis moves whose flexible modes are left ringing less than a bound.

Design layer: imports ``shapefmu.runtime`` only (its kernel, ``runtime.jerk_planner``, is what an
FMU runs). ``plan`` is the entry; ``peers`` measures Ruckig beside it when ``ruckig`` is installed.
"""

from shapefmu.motion.planner import AxisLimits, Mode, ModeResidual, Trajectory, plan

__all__ = ["AxisLimits", "Mode", "ModeResidual", "Trajectory", "plan"]
