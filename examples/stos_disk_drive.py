"""Paper 002 (La-orpacharapan & Pao): STOS closed-loop seeks on the disk drive of Table I.

A 0.1 rad seek (t1 = 1.8 ms, longer than both shapers, the paper's assumption) sampled at
Ts = 1 us on the exact plant (2.0 and 3.0 kHz modes, zeta = 0.01): the convolution and
simultaneous STOS laws beside the unshaped rigid bang-bang and the CasADi time-optimal move of the
full plant; then the robustness runs at Ts = 20 us (+-5 % mode error, a 10 % torque step mid-move,
a set-point change mid-move). Writes results/stos_disk_drive.png (like Fig. 6).

    .venv/bin/python examples/stos_disk_drive.py
"""

from pathlib import Path

from shapefmu.optimal import time_optimal
from shapefmu.plants import library
from shapefmu.stos import plot_stos, rigid_bang_bang_residual, simulate_stos, step, stos_law, with_mode_error

X = 0.1  # rad
TS = 1e-6  # s
TS_COARSE = 20e-6  # s
BAND = 1e-5  # move time: |x_r - X| <= 1e-5 X from then on


def main():
    plant = library.disk_drive()
    optimal = time_optimal(plant, X)
    rigid_T, rigid_residual = rigid_bang_bang_residual(plant, X, TS)
    print(f"disk drive, seek of {X} rad, |u| <= {library.DISK_DRIVE_U} V, Ts = {TS:g} s")
    print(f"{'move':<28} {'time [ms]':>10} {'/ optimal':>10} {'bound [ms]':>11} {'x_f1 left':>10} {'x_f2 left':>10} "
          f"{'/ rigid BB':>10}")
    print(f"{'rigid bang-bang (eq. 2)':<28} {1e3 * rigid_T:10.5f} {rigid_T / optimal.T:10.5f} {'':>11} "
          f"{rigid_residual[0]:10.3e} {rigid_residual[1]:10.3e} {1.0:10.3g}")
    print(f"{'time-optimal, full (CasADi)':<28} {1e3 * optimal.T:10.5f} {1.0:10.5f} {'':>11} {0.0:10.3g} {0.0:10.3g} "
          f"{0.0:10.3g}")
    runs = {}
    for kind in ("convolution", "simultaneous"):
        law = stos_law(plant, kind, Ts=TS)
        run = simulate_stos(plant, law, X, TS, 2 * rigid_T + 2e-3, tolerance=BAND)
        m = run.metrics
        bound = rigid_T + law.shaper.duration + 2 * TS
        ratio = max(r / q for r, q in zip(m.residual_vibration, rigid_residual))
        print(f"{'STOS, ' + kind:<28} {1e3 * m.move_time:10.5f} {m.move_time / optimal.T:10.5f} {1e3 * bound:11.5f} "
              f"{m.residual_vibration[0]:10.3e} {m.residual_vibration[1]:10.3e} {ratio:10.3e}")
        runs[f"STOS, {kind} shaper"] = run
    faster = runs["STOS, convolution shaper"].metrics.move_time - runs["STOS, simultaneous shaper"].metrics.move_time
    print(f"simultaneous STOS is faster by {1e6 * faster:.1f} us (the paper reports 12.08 us with its shaper times)")

    law = stos_law(plant, "simultaneous", Ts=TS_COARSE)
    s = law.settle
    print(f"\nTs = {TS_COARSE:g} s, settle controller: kp {s['kp']:.4g} V/rad, kd {s['kd']:.4g} V s/rad, "
          f"ki {s['ki']:.4g} V/(rad s), hand-over region |x_e| < {s['x_enter']:.3g} rad, |v| < {s['v_enter']:.3g} rad/s")
    print(f"{'case':<44} {'settled [ms]':>12} {'hand-over [ms]':>14} {'final error':>11} {'chattering':>10}")
    cases = {}
    for factor in (0.95, 1.05):
        for torque in (1.1, -1.1):
            cases[f"modes x {factor}, torque step {torque:+} V at 2 ms"] = (
                with_mode_error(plant, factor), dict(disturbance=step(2.01e-3, torque)))
    cases["set point 0.1 -> 0.15 rad at 1.5 ms"] = (plant, dict(setpoint_changes=[(1.5e-3, 0.15)]))
    cases["set point 0.1 -> 0.04 rad at 1.5 ms"] = (plant, dict(setpoint_changes=[(1.5e-3, 0.04)]))
    for name, (model, extra) in cases.items():
        m = simulate_stos(model, law, X, TS_COARSE, 0.03, **extra).metrics
        print(f"{name:<44} {1e3 * m.move_time:12.3f} {1e3 * m.handover_time:14.3f} {m.final_error:11.2e} "
              f"{m.chattering:10d}")
    bare = type(law)(law.shaper, law.curves, None)
    m = simulate_stos(with_mode_error(plant, 1.05), bare, X, TS_COARSE, 0.03, disturbance=step(2.01e-3, 1.1)).metrics
    print(f"{'the same without settle controller (paper)':<44} {1e3 * m.move_time:12.3f} {'-':>14} "
          f"{m.final_error:11.2e} {m.chattering:10d}")

    path = Path("results") / "stos_disk_drive.png"
    path.parent.mkdir(exist_ok=True)
    plot_stos(runs, path)
    print(f"\nplot: {path}")


if __name__ == "__main__":
    main()
