"""Issue 36's example: a 10 mm move (v 0.3 m/s, a 5 m/s^2, j 2000 m/s^3) of an axis carrying a 40 Hz
mode (zeta 0.05), by Ruckig, by Ruckig followed by a ZV shaper, and by the planner of shapefmu.motion
(bound: 1 % of Ruckig's residual). Plots position, acceleration and the mode's deflection of each to
examples/figures/motion_40hz.png and prints the durations and residuals.

The deflection is integrated here independently of the planner (scipy's lsim of
y'' + 2 zeta w y' + w^2 y = -a on the acceleration sampled every 10 us).
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy.signal import lsim  # noqa: E402

from shapefmu.motion import AxisLimits, plan  # noqa: E402
from shapefmu.runtime.jerk_profiles import Phases  # noqa: E402
from shapefmu.runtime.jerk_vibration import convolve_jerk, padded  # noqa: E402
from shapefmu.runtime.shaper_designs import design_impulses  # noqa: E402

HZ, ZETA = 40.0, 0.05
FIGURE = Path(__file__).parent / "figures" / "motion_40hz.png"


def moves():
    ours = plan([0.0], [0.01], [AxisLimits(0.3, 5.0, 2000.0)], [(HZ, ZETA)], vtol=0.01)
    # Without modes the planner's move is the rigid time-optimal one, Ruckig's (tests/test_motion_rigid.py).
    rigid = plan([0.0], [0.01], [AxisLimits(0.3, 5.0, 2000.0)])
    (start, durations, jerks), = rigid.phases
    rigid_phases = Phases(*start, list(durations), list(jerks))
    times, amplitudes = design_impulses("zv", [(2 * math.pi * HZ, ZETA)])
    shaped = convolve_jerk(rigid_phases, times, amplitudes)
    (start, durations, jerks), = ours.phases
    return {"Ruckig": rigid_phases, "Ruckig + ZV": shaped, "shapefmu.motion": Phases(*start, list(durations), list(jerks))}, ours


def deflection(phases, t):
    w = 2 * math.pi * HZ
    a = np.array([phases.state(x)[2] for x in t])
    _, y, _ = lsim(([-1.0], [1.0, 2 * ZETA * w, w * w]), a, t)
    return a, np.array([phases.state(x)[0] for x in t]), y


def main():
    found, ours = moves()
    end = 0.16
    t = np.arange(0.0, end, 1e-5)
    figure, axes = plt.subplots(3, 1, sharex=True, figsize=(8, 8))
    for name, phases in found.items():
        a, p, y = deflection(padded(phases, end), t)
        after = t >= phases.duration
        residual = np.max(np.abs(y[after])) if after.any() else float("nan")
        print(f"{name:16} {1e3 * phases.duration:8.3f} ms   residual deflection after the move {1e6 * residual:8.3f} um")
        label = f"{name} ({1e3 * phases.duration:.2f} ms)"
        axes[0].plot(t * 1e3, p * 1e3, label=label)
        axes[1].plot(t * 1e3, a, label=label)
        axes[2].plot(t * 1e3, y * 1e6, label=label)
    axes[0].set_ylabel("position [mm]")
    axes[1].set_ylabel("acceleration [m/s$^2$]")
    axes[2].set_ylabel("40 Hz mode deflection [um]")
    axes[2].set_xlabel("time [ms]")
    axes[0].legend(fontsize="small")
    axes[0].set_title("10 mm at 0.3 m/s, 5 m/s$^2$, 2000 m/s$^3$; 40 Hz mode, zeta 0.05; bound 1 %")
    figure.tight_layout()
    FIGURE.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(FIGURE, dpi=110)
    print(f"planner: {ours.method}, computed in {1e3 * ours.compute_seconds:.0f} ms (Python kernel); figure {FIGURE}")


if __name__ == "__main__":
    main()
