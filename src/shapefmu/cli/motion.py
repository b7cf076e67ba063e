"""``shapefmu motion plan``: a jerk-limited multi-axis move that leaves its modes ringing less than a bound.

    shapefmu motion plan --axis NAME:FROM:TO:VMAX:AMAX:JMAX ... --mode [AXIS:]HZ:ZETA ...
                         [--band 0.1] [--vtol 0.01] [--ts 1e-3] [--straight] [--json] [--out traj.csv]

Prints the duration, the computation time and every mode's residual; beside them, when ``ruckig``
is installed, Ruckig's duration for the same move and the rigid move followed by the shortest shaper
of the catalog meeting the same band and bound.
"""

from __future__ import annotations

import argparse
import json
import math

from shapefmu.cli.arguments import examples, output_file, parse_mode_hz, say_written
from shapefmu.files import write_text


def _axis(text: str):
    parts = text.split(":")
    if len(parts) != 6 or not parts[0]:
        raise argparse.ArgumentTypeError(f"--axis must be NAME:FROM:TO:VMAX:AMAX:JMAX, e.g. x:0:0.01:0.3:5:2000, "
                                         f"got {text!r}")
    if not parts[0].replace("_", "").isalnum():
        raise argparse.ArgumentTypeError(f"--axis name must be letters, digits and _, got {parts[0]!r}")
    try:
        values = [float(p) for p in parts[1:]]
    except ValueError:
        raise argparse.ArgumentTypeError(f"--axis values must be numbers, got {text!r}") from None
    if not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"--axis values must be finite, got {text!r}")
    for name, value in zip(("VMAX", "AMAX", "JMAX"), values[2:]):
        if value <= 0.0:
            raise argparse.ArgumentTypeError(f"--axis {name} must be > 0, got {value!r} in {text!r}")
    return parts[0], values


def _mode(text: str):
    """``[AXIS:]HZ:ZETA`` -> (axis or None, f Hz, zeta); the numbers checked as every --mode is."""
    parts = text.split(":")
    axis = parts.pop(0) if len(parts) == 3 else None
    if len(parts) != 2:
        raise argparse.ArgumentTypeError(f"--mode must be [AXIS:]HZ:ZETA, e.g. x:40:0.05, got {text!r}")
    return (axis, *parse_mode_hz(":".join(parts)))


def _cmd_plan(args) -> int:
    from shapefmu.motion import AxisLimits, plan
    from shapefmu.motion.peers import ruckig_duration

    names = [name for name, _ in args.axis]
    if len(set(names)) != len(names):
        raise ValueError(f"--axis names must differ, got {names}")
    modes = {name: [] for name in names}
    for axis, hz, zeta in args.mode or ():
        for name in (names if axis is None else [axis]):
            if name not in modes:
                raise ValueError(f"--mode names axis {axis!r}, which no --axis defines (axes: {', '.join(names)})")
            modes[name].append((hz, zeta))
    start = [values[0] for _, values in args.axis]
    target = [values[1] for _, values in args.axis]
    limits = [AxisLimits(*values[2:]) for _, values in args.axis]
    trajectory = plan(start, target, limits, modes, names=names, band=args.band, vtol=args.vtol,
                      straight=args.straight, ts=args.ts if args.snap else None)
    peer = ruckig_duration([(p, 0.0, 0.0) for p in start], [(p, 0.0, 0.0) for p in target], limits, args.straight)
    if args.out:
        write_text(args.out, trajectory.to_csv(args.ts), what="trajectory table")
    record = {
        "duration": trajectory.duration,
        "method": trajectory.method,
        "compute_seconds": trajectory.compute_seconds,
        "rigid_duration": trajectory.rigid_duration,
        "ruckig_duration": peer,
        "ruckig_shaped_duration": trajectory.ceiling_duration if math.isfinite(trajectory.ceiling_duration) else None,
        "ruckig_shapers": dict(zip(names, trajectory.ceiling_shapers)),
        "modes": [{"axis": r.axis, "hz": r.hz, "zeta": r.zeta, "residual": r.amplitude,
                   "rigid_residual": r.rigid_amplitude, "ratio": r.ratio} for r in trajectory.residuals],
    }
    if args.json:
        print(json.dumps(record, indent=2))
        _say_samples_written(args)
        return 0
    print(f"move of {', '.join(names)}: {1e3 * trajectory.duration:.4f} ms ({trajectory.method}), "
          f"computed in {1e6 * trajectory.compute_seconds:.0f} us")
    for r in trajectory.residuals:
        print(f"  mode {r.axis} {r.hz:g} Hz zeta {r.zeta:g}: residual {r.amplitude:.3e} = {100 * r.ratio:.3g} % "
              f"of the rigid move's {r.rigid_amplitude:.3e} (bound {100 * args.vtol:g} % over +-{100 * args.band:g} %)")
    if peer is None:
        print("Ruckig: not installed (pip install ruckig) - rigid time-optimal duration "
              f"{1e3 * trajectory.rigid_duration:.4f} ms")
    else:
        print(f"Ruckig: {1e3 * peer:.4f} ms (rigid, leaves the modes ringing)")
    if trajectory.residuals:
        shapers = ", ".join(f"{n}: {s}" for n, s in zip(names, trajectory.ceiling_shapers) if s)
        print(f"Ruckig + shortest shaper ({shapers}): {1e3 * trajectory.ceiling_duration:.4f} ms")
    _say_samples_written(args)
    return 0


def _say_samples_written(args) -> None:
    if args.out:
        say_written(args, f"samples at ts = {args.ts:g} s written to {args.out}")


def register(commands) -> None:
    p = commands.add_parser("motion", help="online jerk-limited multi-axis moves with vibration bounds",
                            arguments=_motion_arguments,
                            epilog=examples("shapefmu motion plan --axis x:0:0.01:0.3:5:2000 --mode 40:0.05"))


def _motion_arguments(p) -> None:
    sub = p.add_subparsers(dest="motion_command", required=True, metavar="ACTION")
    q = sub.add_parser("plan", help="plan a move; print its duration, computation time and residuals beside Ruckig's",
                       arguments=_plan_arguments,
                       epilog=examples("shapefmu motion plan --axis x:0:0.01:0.3:5:2000 --mode 40:0.05",
                                       "shapefmu motion plan --axis x:0:0.01:0.3:5:2000 --axis y:0:0.02:0.3:5:2000 "
                                       "--mode 40:0.05 --band 0.1 --out results/move.csv"))
    q.set_defaults(run=_cmd_plan)


def _plan_arguments(q) -> None:
    q.add_argument("--axis", type=_axis, action="append", required=True, metavar="NAME:FROM:TO:VMAX:AMAX:JMAX",
                   help="an axis moving from rest at FROM to rest at TO within |v| <= VMAX, |a| <= AMAX, |j| <= JMAX; "
                        "repeat per axis")
    q.add_argument("--mode", type=_mode, action="append", metavar="[AXIS:]HZ:ZETA",
                   help="a mode of AXIS (of every axis without AXIS) in Hz with its damping ratio; repeatable")
    q.add_argument("--band", type=float, default=0.0, help="robustness band +- delta as a fraction of each mode's "
                                                             "frequency (default 0)")
    q.add_argument("--vtol", type=float, default=0.01, help="bound on each mode's residual, a fraction of the rigid "
                                                             "move's over the band (default 0.01)")
    q.add_argument("--ts", type=float, default=1e-3, help="sampling period of the CSV in s (default 1e-3)")
    q.add_argument("--snap", action="store_true", help="make the duration a whole number of periods --ts")
    q.add_argument("--straight", action="store_true", help="move along the straight line between the positions")
    q.add_argument("--json", action="store_true", help="print the result as JSON")
    q.add_argument("--out", metavar="CSV", type=output_file(".csv", what="trajectory table"),
                   help="write time and every axis's position, velocity, acceleration, jerk at --ts")
