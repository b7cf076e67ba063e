"""``shapefmu sweep``: a co-simulation mapped over a parameter grid or random samples on Dask.
"""

from __future__ import annotations

import sys

from shapefmu.cli.arguments import output_file
from shapefmu.cosim.master import ALGORITHMS


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
    sweeps.check_workers(args.workers, "--workers")
    _check_variables(args.system, [*points.names, *record])
    target = sweeps.cosim(args.system, step=args.step, stop_time=args.stop_time, record=record,
                          algorithm=args.algorithm)
    rows = sweeps.sweep(target, points, metrics=metrics, out=args.out, client=args.scheduler, n_workers=args.workers,
                        timeout=args.timeout, resume=not args.no_resume, retry_failed=args.retry_failed)
    print(sweeps.summary(rows, [m.name for m in metrics]))
    if args.out:
        print(f"rows written to {args.out}")
    if args.plot:
        y = points.names[1] if len(points.names) > 1 else None
        path = sweeps.plot_map(rows, metrics[0].name, args.plot, x=points.names[0], y=y)
        print(f"robustness map written to {path}")
    if not (rows["status"] == "ok").any():
        print(f"shapefmu sweep: error: none of the {len(rows)} runs succeeded (first error: {rows['error'][0]})",
              file=sys.stderr)
        return 1
    return 0


def _check_variables(system_file, names) -> None:
    """Refuse, before a cluster starts, a parameter or recorded variable the system does not have:
    otherwise every run would fail on it, one row at a time."""
    from shapefmu.fmi.archives import read_description
    from shapefmu.fmi.ssp import read_ssp

    system = read_ssp(system_file)
    known = {}
    for name in names:
        component, dot, variable = name.partition(".")
        if not dot or component not in system.components:
            raise ValueError(f"{name!r} must be component.variable with a component of {system_file} "
                             f"({', '.join(system.components)})")
        if component not in known:
            known[component] = {v.name for v in read_description(system.components[component].fmu).modelVariables}
        if variable not in known[component]:
            raise ValueError(f"{name!r}: component {component!r} of {system_file} has no variable {variable!r}")


def register(commands) -> None:
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
    p.add_argument("--algorithm", choices=ALGORITHMS, help="master algorithm (default: the master's)")
    p.add_argument("--out", metavar="FILE", type=output_file(".csv", ".parquet", what="rows file"),
                   help="rows as .csv or .parquet, appended as runs finish")
    p.add_argument("--no-resume", action="store_true", help="overwrite --out instead of skipping the points it has")
    p.add_argument("--retry-failed", action="store_true",
                   help="resuming --out, run again the points whose row is an error or a timeout")
    p.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler, e.g. tcp://host:8786 (default: a local cluster)")
    p.add_argument("--workers", type=int, help="worker processes of the local cluster (default: one per core)")
    p.add_argument("--timeout", type=float, help="seconds a run may take before it is recorded as a timeout")
    p.add_argument("--plot", metavar="PNG", type=output_file("plot"),
                   help="robustness map of the first metric against the first two parameters")
    p.set_defaults(run=_cmd_sweep)
