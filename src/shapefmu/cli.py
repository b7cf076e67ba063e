"""The ``shapefmu`` command line.

    shapefmu design KIND --mode HZ[:ZETA] [--mode ...] [--vtol V] [--n N] [--json]
    shapefmu design WINDOW --mode HZ[:ZETA] [--order N] [--ts S] [--adjust-ts] [--json]
    shapefmu sensitivity KIND --mode HZ[:ZETA] [--mode ...] [--vtol V] --plot out.png
    shapefmu profile KIND --mode HZ[:ZETA] --distance D --speed V [--plot out.png] [--json]
    shapefmu plant show models/disk_drive.toml
    shapefmu plant build models/disk_drive.toml -o fmus/DiskDrive.fmu
    shapefmu optimal models/disk_drive.toml --distance X [--u-max U] [--plot out.png] [--json s.json] [--csv u.csv]
    shapefmu stos models/disk_drive.toml --distance X --shaper simultaneous [--ts S] [--plot out.png]
    shapefmu build [all | shaper --kind KIND --mode HZ[:ZETA] ... -o fmus/X.fmu]
    shapefmu build reference solution.json|table.csv [--interpolation hold|linear] -o fmus/TimeOptimal.fmu
    shapefmu build shape-filter --kind WINDOW|TWIN-PULSE|time-frequency --mode HZ[:ZETA] [--order N] [--ts S] -o fmus/X.fmu
    shapefmu sweep system.ssp --vary NAME=START:STOP:N [--vary NAME=V1,V2] --metric residual --out rows.parquet
    shapefmu simulate system.ssp --stop 0.01 --step 1e-6 [--record plant.x ...] [--out r.csv] [--plot out.png]
    shapefmu compare models/disk_drive.toml --distance X [--candidate stos-simultaneous ...] [--step S] [--fmus fmus] [--plot out.png]

Modes are given in Hz on the command line (as a datasheet or an FFT gives them) and converted to
rad/s for the Python API.
"""

from __future__ import annotations

import argparse
import json
import math
import sys

import numpy as np

from shapefmu import __version__
from shapefmu.analysis import insensitivity, residual_vibration, sensitivity
from shapefmu.shapers import (
    KINDS,
    TWIN_PULSE_PROFILES,
    WINDOW_FILTERS,
    design,
    time_frequency_profile,
    velocity_profile,
)

PROFILE_KINDS = (*TWIN_PULSE_PROFILES, "time-frequency", "hanning", "blackman")


def parse_mode(text: str) -> tuple[float, float]:
    """``"2000"`` or ``"2000:0.01"`` (Hz, damping ratio) -> (omega rad/s, zeta)."""
    hz_text, _, zeta_text = text.partition(":")
    try:
        hz = float(hz_text)
        zeta = float(zeta_text) if zeta_text else 0.0
    except ValueError:
        raise argparse.ArgumentTypeError(f"--mode must be HZ or HZ:ZETA, e.g. 2000:0.01, got {text!r}") from None
    if not (math.isfinite(hz) and hz > 0):
        raise argparse.ArgumentTypeError(f"--mode frequency must be > 0 Hz, got {hz_text!r}")
    if not (math.isfinite(zeta) and 0 <= zeta < 1):
        raise argparse.ArgumentTypeError(f"--mode damping ratio must be in [0, 1), got {zeta_text!r}")
    return 2.0 * math.pi * hz, zeta


def _add_design_arguments(parser: argparse.ArgumentParser, kinds=KINDS) -> None:
    parser.add_argument("kind", choices=kinds, help="shaper design")
    parser.add_argument(
        "--mode", type=parse_mode, action="append", required=True, metavar="HZ[:ZETA]",
        help="mode frequency in Hz and damping ratio; repeat for several modes",
    )
    parser.add_argument("--vtol", type=float, default=0.05, help="tolerable vibration of the EI family (default 0.05)")
    parser.add_argument("--n", type=int, default=1, help="derivative order of zv_dn (0 = ZV, 1 = ZVD, ...)")


def _add_sampling_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--order", type=int, default=1, help="robustness order of window filters (default 1)")
    parser.add_argument("--ts", type=float, help="sampling period in s (window default: pi/(100 omega_d))")
    parser.add_argument("--adjust-ts", action="store_true", help="use the nearest ts that makes M an integer")


def _design(args):
    if args.kind not in WINDOW_FILTERS:
        return design(args.kind, args.mode, vtol=args.vtol, n=args.n)
    if len(args.mode) != 1:
        raise ValueError(f"window filter {args.kind!r} takes exactly one --mode, got {len(args.mode)}")
    return _window_filter(args.kind, args.mode[0], args)


def _window_filter(kind, mode, args):
    omega, zeta = mode
    ts = args.ts if args.ts is not None else math.pi / (100 * omega * math.sqrt(1 - zeta**2))
    return WINDOW_FILTERS[kind](omega, zeta, ts, args.order, adjust_ts=args.adjust_ts or args.ts is None)


def _cmd_design(args) -> int:
    shaper = _design(args)
    if args.kind in WINDOW_FILTERS and not args.json:
        (w, z), = args.mode
        print(f"{args.kind} filter of order {args.order}: {len(shaper)} taps at ts = {shaper.ts:.10g} s, "
              f"duration {shaper.duration:.6g} s, sum of taps {shaper.gain:.12g}")
        print(f"mode {w / (2 * math.pi):g} Hz, zeta {z:g}: residual vibration {100 * residual_vibration(shaper, w, z):.3g} %")
        return 0
    residuals = [residual_vibration(shaper, w, z) for w, z in args.mode]
    if args.json:
        record = json.loads(shaper.to_json())
        record["modes"] = [{"omega": w, "zeta": z, "residual": r} for (w, z), r in zip(args.mode, residuals)]
        print(json.dumps(record, indent=2))
        return 0
    print(f"{args.kind} shaper, {len(shaper)} impulses, duration {shaper.duration:.6g} s")
    print(f"{'time [s]':>14}  {'amplitude':>10}")
    for t, a in zip(shaper.times, shaper.amplitudes):
        print(f"{t:14.6e}  {a:10.6f}")
    for (w, z), r in zip(args.mode, residuals):
        print(f"mode {w / (2 * math.pi):g} Hz, zeta {z:g}: residual vibration {100 * r:.3g} %")
    return 0


def _cmd_sensitivity(args) -> int:
    shaper = _design(args)
    q = np.linspace(0.0, args.q_max, 1201)
    curves = []
    for w, z in args.mode:
        label = f"{w / (2 * math.pi):g} Hz, zeta {z:g}"
        curves.append((label, sensitivity(shaper, w, z, q)))
        try:
            band = insensitivity(shaper, w, z, args.vtol)
            print(f"{label}: V <= {100 * args.vtol:g} % for q in [{band.q_low:.4f}, {band.q_high:.4f}], I = {band.width:.4f}")
        except ValueError as error:
            print(f"{label}: {error}")
    if args.plot:
        from shapefmu.plots import plot_sensitivity

        path = plot_sensitivity([(f"{args.kind}, {label}", c) for label, c in curves], args.plot, vtol=args.vtol)
        print(f"sensitivity plot written to {path}")
    return 0


def _cmd_profile(args) -> int:
    omega, zeta = args.mode
    if args.kind in TWIN_PULSE_PROFILES:
        extras = {"ts": args.ts}
        if args.kind.startswith("M-"):
            extras.update(delta_omega=args.delta_omega, attenuation=args.attenuation)
        design_ = TWIN_PULSE_PROFILES[args.kind](omega, args.distance, args.speed, **extras)
        profile = design_.profile
        summary = f"null k = {design_.null}, slew speed {design_.slew_speed:.6g}, delta-omega {design_.delta_omega:.6g} rad/s"
    elif args.kind == "time-frequency":
        if args.ts is None or args.move_time is None:
            raise ValueError("the time-frequency profile needs --ts and --move-time (s)")
        design_ = time_frequency_profile(omega, args.ts, args.move_time, args.distance)
        profile = design_.profile
        summary = f"scale n = {design_.n:.4f}, energy leakage 1 - J = {design_.leakage:.3e}"
    else:
        profile = velocity_profile(_window_filter(args.kind, args.mode, args), args.distance)
        summary = f"{args.kind} velocity profile of order {args.order}"
    if args.json:
        print(profile.to_json())
    else:
        print(f"{args.kind}: {summary}")
        print(
            f"duration {profile.duration:.6g} s, peak velocity {max(abs(profile.velocity)):.6g}, "
            f"peak acceleration {max(abs(profile.acceleration)):.6g}, final position {profile.position[-1]:.12g}"
        )
    if args.plot:
        from shapefmu.plots import plot_motion_profile

        print(f"profile plot written to {plot_motion_profile(profile, args.plot, title=args.kind)}")
    return 0


def _cmd_plant_show(args) -> int:
    from shapefmu.plants import describe

    print(describe(args.file))
    return 0


def _cmd_plant_build(args) -> int:
    from shapefmu.fmi.native import build_plant_fmu, model_from_file

    model = model_from_file(args.file)
    if model is None:
        raise ValueError(f"{args.file} defines no plant() function")
    print(f"plant FMU written to {build_plant_fmu(model, args.output)}")
    return 0


def _cmd_optimal(args) -> int:
    from shapefmu.optimal import optimal_report

    print(optimal_report(args.file, args.distance, u_max=args.u_max, plot=args.plot, json_path=args.json,
                         csv_path=args.csv))
    return 0


def _cmd_stos(args) -> int:
    from shapefmu.stos import stos_report

    print(stos_report(args.file, args.distance, shaper=args.shaper, Ts=args.ts, t_end=args.t_end, u_max=args.u_max,
                      plot=args.plot))
    return 0


def _cmd_sweep(args) -> int:
    from shapefmu import sweep as sweeps

    if args.samples is None:
        if not args.vary or args.sample:
            raise ValueError("give the grid with --vary NAME=START:STOP:N, or --sample NAME=LOW:HIGH with --samples N")
        points = sweeps.grid(*args.vary)
    else:
        if not args.sample or args.vary:
            raise ValueError("--samples N draws from the ranges of --sample NAME=LOW:HIGH (not --vary)")
        points = sweeps.random_samples(args.samples, args.sample, seed=args.seed)
    metrics, variables = sweeps.named_metrics(
        args.metric, outputs=args.outputs, command=args.command_variable, after=args.after, position=args.position,
        target=args.target, tolerance=args.tolerance)
    record = args.record or variables
    if any(ch in o for o in args.outputs for ch in "*?[") and not args.record:
        raise ValueError(f"--outputs {args.outputs} uses patterns: name the variables to record with --record")
    target = sweeps.cosim(args.system, step=args.step, stop_time=args.stop_time, record=record,
                          algorithm=args.algorithm)
    rows = sweeps.sweep(target, points, metrics=metrics, out=args.out, client=args.scheduler, n_workers=args.workers,
                        timeout=args.timeout, resume=not args.no_resume)
    print(sweeps.summary(rows, [m.name for m in metrics]))
    if args.out:
        print(f"rows written to {args.out}")
    if args.plot:
        y = points.names[1] if len(points.names) > 1 else None
        path = sweeps.plot_map(rows, metrics[0].name, args.plot, x=points.names[0], y=y)
        print(f"robustness map written to {path}")
    return 0


def _cmd_simulate(args) -> int:
    from shapefmu.cosim import CosimError, CosimInterrupted, Master, save_results

    parameters = {}
    for item in args.set:
        name, _, value = item.partition("=")
        try:
            parameters[name] = float(value)
        except ValueError:
            raise ValueError(f"--set must be component.variable=NUMBER, got {item!r}") from None
    with Master(args.system, args.step, algorithm=args.algorithm, record=args.record, output_interval=args.output_interval,
                model_exchange=args.model_exchange, progress=args.progress) as master:
        try:
            results, status = master.run(args.stop, parameters=parameters), 0
        except (CosimError, CosimInterrupted) as error:
            print(f"shapefmu simulate: {error}", file=sys.stderr)
            results, status = error.partial, (130 if isinstance(error, CosimInterrupted) else 1)
    if results is None:
        return status
    last = results[-1]
    print(f"{len(results)} records to t = {last['time']:.9g} s")
    for name in results.dtype.names[1:]:
        print(f"  {name:30s} final {last[name]: .9g}   peak |.| {np.max(np.abs(results[name])):.6g}")
    if args.out:
        print(f"results written to {save_results(results, args.out)}")
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        names = results.dtype.names[1:]
        figure, axes = plt.subplots(len(names), 1, sharex=True, figsize=(8, 2 + 1.6 * len(names)), squeeze=False)
        for axis, name in zip(axes[:, 0], names):
            axis.plot(results["time"], results[name])
            axis.set_ylabel(name)
        axes[-1, 0].set_xlabel("time [s]")
        figure.tight_layout()
        figure.savefig(args.plot)
        print(f"plot written to {args.plot}")
    return status


def _cmd_compare(args) -> int:
    from shapefmu.cosim.compare import compare

    comparison = compare(args.file, args.distance, candidates=args.candidate or None, step=args.step, cache=args.fmus,
                         u_max=args.u_max, tolerance=args.tolerance, plot=args.plot)
    print(comparison.table())
    if args.plot:
        print(f"plot written to {args.plot}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="shapefmu", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"shapefmu {__version__}")
    commands = parser.add_subparsers(dest="command", required=True)

    p = commands.add_parser("design", help="design an impulse shaper or window filter and print it")
    _add_design_arguments(p, kinds=(*KINDS, *WINDOW_FILTERS))
    _add_sampling_arguments(p)
    p.add_argument("--json", action="store_true", help="print the design as JSON")
    p.set_defaults(run=_cmd_design)

    p = commands.add_parser("sensitivity", help="residual vibration against frequency error")
    _add_design_arguments(p)
    p.add_argument("--q-max", type=float, default=2.0, help="largest frequency ratio plotted (default 2)")
    p.add_argument("--plot", metavar="PNG", help="save the sensitivity curve to this file")
    p.set_defaults(run=_cmd_sensitivity)

    p = commands.add_parser("profile", help="rest-to-rest motion profile (twin-pulse, time-frequency, window)")
    p.add_argument("kind", choices=PROFILE_KINDS, help="profile family")
    p.add_argument("--mode", type=parse_mode, required=True, metavar="HZ[:ZETA]", help="mode to suppress")
    p.add_argument("--distance", type=float, required=True, help="move distance")
    p.add_argument("--speed", type=float, help="desired slew speed (twin-pulse family)")
    p.add_argument("--delta-omega", type=float, help="null offset in rad/s (M- twin-pulse kinds)")
    p.add_argument("--attenuation", type=float, help="spectrum magnitude at the mode, to find delta-omega by bisection")
    p.add_argument("--move-time", type=float, help="move time in s (time-frequency profile)")
    _add_sampling_arguments(p)
    p.add_argument("--plot", metavar="PNG", help="save acceleration, velocity and position to this file")
    p.add_argument("--json", action="store_true", help="print the sampled profile as JSON")
    p.set_defaults(run=_cmd_profile)

    p = commands.add_parser("plant", help="plant models (models/*.toml)")
    plant_commands = p.add_subparsers(dest="plant_command", required=True)
    q = plant_commands.add_parser("show", help="print a plant model's signals, parameters and modes")
    q.add_argument("file", help="plant model file, e.g. models/disk_drive.toml")
    q.set_defaults(run=_cmd_plant_show)
    q = plant_commands.add_parser("build", help="generate and compile a native FMI 2.0 ME + CS plant FMU")
    q.add_argument("file", help="plant model: models/*.toml, or a .py file defining plant() (models/pendulum.py)")
    q.add_argument("-o", "--output", required=True, metavar="FMU", help="FMU to write, e.g. fmus/DiskDrive.fmu")
    q.set_defaults(run=_cmd_plant_build)

    p = commands.add_parser("optimal", help="time-optimal move beside the rigid and shaped bang-bang moves")
    p.add_argument("file", help="plant model file, e.g. models/disk_drive.toml")
    p.add_argument("--distance", type=float, required=True, help="move distance of the plant's first output")
    p.add_argument("--u-max", type=float, default=None, help="input limit (default: the input's limit in the file)")
    p.add_argument("--plot", metavar="PNG", help="save u(t) of every move and the outputs of the optimal move")
    p.add_argument("--json", metavar="FILE", help="save the time-optimal solution as JSON (for `shapefmu build reference`)")
    p.add_argument("--csv", metavar="FILE", help="save the time-optimal u(t) as a time,value signal table")
    p.set_defaults(run=_cmd_optimal)

    p = commands.add_parser("stos", help="shaped time-optimal closed-loop move (STOS, paper 002), sampled")
    p.add_argument("file", help="plant model file in the form of eq. (1), e.g. models/disk_drive.toml")
    p.add_argument("--distance", type=float, required=True, help="move distance of the rigid body")
    p.add_argument("--shaper", choices=("convolution", "simultaneous", "zvd", "ei"), default="simultaneous",
                   help="multi-mode shaper the law is built from (default simultaneous)")
    p.add_argument("--ts", type=float, default=1e-6, help="sampling period of the controller in s (default 1e-6)")
    p.add_argument("--t-end", type=float, help="simulated time in s (default: twice the rigid move + 2 ms)")
    p.add_argument("--u-max", type=float, default=None, help="input limit (default: the input's limit in the file)")
    p.add_argument("--plot", metavar="PNG", help="save u, x_r, x_r', x_f, x_f' against time (like Fig. 6)")
    p.set_defaults(run=_cmd_stos)

    from shapefmu.build_command import add_build_command

    add_build_command(commands)

    p = commands.add_parser("sweep", help="co-simulate a system over a parameter grid on Dask, one row per run")
    p.add_argument("system", help="SSP system (.ssp archive, or .ssd with its FMUs beside it); packed with its FMUs and sent to the workers as bytes")
    p.add_argument("--vary", action="append", default=[], metavar="NAME=SPEC",
                   help="grid axis: NAME=START:STOP:N (linspace) or NAME=V1,V2,...; repeat for a product grid")
    p.add_argument("--sample", action="append", default=[], metavar="NAME=LOW:HIGH", help="uniform sampling range")
    p.add_argument("--samples", type=int, help="number of random samples drawn from the --sample ranges")
    p.add_argument("--seed", type=int, default=0, help="seed of the random samples (default 0)")
    p.add_argument("--metric", action="append", required=True, choices=("residual", "move_time", "peak"),
                   help="metric per run; repeat for several")
    p.add_argument("--outputs", action="append", default=[], metavar="VAR",
                   help="variables whose residual vibration is measured (fnmatch patterns allowed)")
    p.add_argument("--command", dest="command_variable", metavar="VAR", help="command variable: its rest ends the move; peak is its max |u|")
    p.add_argument("--after", type=float, help="start of the residual window in s (default: end of the move)")
    p.add_argument("--position", metavar="VAR", help="variable that must settle for move_time")
    p.add_argument("--target", type=float, help="final value of --position")
    p.add_argument("--tolerance", type=float, help="settling band half-width of move_time")
    p.add_argument("--step", type=float, required=True, help="communication step of the master in s")
    p.add_argument("--stop-time", type=float, required=True, help="end of each run in s")
    p.add_argument("--record", action="append", metavar="VAR", help="variables to record (default: what the metrics read)")
    p.add_argument("--algorithm", help="master algorithm (default: the master's)")
    p.add_argument("--out", metavar="FILE", help="rows as .csv or .parquet, appended as runs finish")
    p.add_argument("--no-resume", action="store_true", help="overwrite --out instead of skipping the points it has")
    p.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler, e.g. tcp://host:8786 (default: a local cluster)")
    p.add_argument("--workers", type=int, help="worker processes of the local cluster (default: one per core)")
    p.add_argument("--timeout", type=float, help="seconds a run may take before it is recorded as a timeout")
    p.add_argument("--plot", metavar="PNG", help="robustness map of the first metric against the first two parameters")
    p.set_defaults(run=_cmd_sweep)

    p = commands.add_parser("simulate", help="run an SSP system of FMUs with the co-simulation master")
    p.add_argument("system", help="SSP system (.ssp archive or .ssd file)")
    p.add_argument("--stop", type=float, required=True, help="stop time in s")
    p.add_argument("--step", type=float, required=True, help="macro (communication) step in s")
    p.add_argument("--record", action="append", metavar="COMP.VAR", help="variable to record; repeat (default: every output)")
    p.add_argument("--output-interval", type=float, help="record every this many s (a multiple of --step)")
    p.add_argument("--algorithm", choices=("gauss-seidel", "jacobi"), default="gauss-seidel", help="master algorithm")
    p.add_argument("--model-exchange", action="append", metavar="COMP", help="integrate this component as Model Exchange")
    p.add_argument("--set", action="append", default=[], metavar="COMP.VAR=VALUE", help="parameter for this run; repeat")
    p.add_argument("--out", metavar="FILE", help="save the results as .csv or .parquet")
    p.add_argument("--plot", metavar="PNG", help="plot every recorded variable against time")
    p.add_argument("--progress", action="store_true", help="show a progress bar")
    p.set_defaults(run=_cmd_simulate)

    from shapefmu.cosim.compare import CANDIDATES

    p = commands.add_parser("compare", help="one plant, every candidate command, co-simulated as FMUs side by side")
    p.add_argument("file", help="plant model in the form of eq. (1) of paper 002, e.g. models/disk_drive.toml")
    p.add_argument("--distance", type=float, required=True, help="move distance of the rigid body")
    p.add_argument("--candidate", action="append", choices=CANDIDATES, help="candidate to run; repeat (default: all)")
    p.add_argument("--step", type=float, default=1e-6, help="macro step and sampling period of every FMU in s (default 1e-6)")
    p.add_argument("--fmus", default="fmus", help="folder where the FMUs are built and reused (default fmus)")
    p.add_argument("--u-max", type=float, default=None, help="input limit (default: the input's limit in the file)")
    p.add_argument("--tolerance", type=float, default=1e-3, help="settling band of the move time, relative to X and U")
    p.add_argument("--plot", metavar="PNG", help="save u, position error and deflection of every candidate")
    p.set_defaults(run=_cmd_compare)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.run(args)
    except ValueError as error:
        parser.exit(2, f"shapefmu {args.command}: error: {error}\n")


if __name__ == "__main__":
    sys.exit(main())
