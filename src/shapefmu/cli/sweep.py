"""``shapefmu sweep``: a co-simulation mapped over a parameter grid or random samples on Dask.

It names systems as ``simulate`` does (a file, or a shipped system by name), takes ``--stop`` and
``--step`` from the system when they are not given, and records what ``--outputs`` names, patterns
included, without an explicit ``--record``.
"""

from __future__ import annotations

import fnmatch
import sys
from pathlib import Path

from shapefmu.cli.arguments import add_experiment_arguments, examples, experiment, output_file, read_system
from shapefmu.cli.progress import showing


def _cmd_sweep(args) -> int:
    import distributed  # noqa: F401 -- the dask extra: without it, one line naming it before any work

    from shapefmu import sweep as sweeps

    if args.samples is None:
        if not args.vary or args.sample:
            raise ValueError("give the grid with --vary NAME=START:STOP:N, or --sample NAME=LOW:HIGH with --samples N")
        points = sweeps.grid(*args.vary)
    else:
        if not args.sample or args.vary:
            raise ValueError("--samples N draws from the ranges of --sample NAME=LOW:HIGH (not --vary)")
        points = sweeps.random_samples(args.samples, args.sample, seed=args.seed)
    # The options are checked before the system is read: a wrong grid or metric is the cheaper error to
    # report. Patterns in --outputs are expanded once the system's variables are known.
    _metrics(args, args.outputs)
    sweeps.check_workers(args.workers, "--workers")
    system = read_system(args.system)
    stop, step = experiment(system, args)
    known = _variables(system)
    metrics, variables = _metrics(args, _matching(args.outputs, known))
    record = args.record or variables
    for name in [*points.names, *record]:  # refused before a cluster starts: every run would fail on it
        _check_variable(name, known, system, args.system)
    # A file is sent as it is; a shipped system (its FMUs from ./fmus) as the system read.
    source = args.system if Path(args.system).exists() else system
    target = sweeps.cosim(source, step=step, stop_time=stop, record=record, algorithm=args.algorithm)
    rows = sweeps.sweep(target, points, metrics=metrics, out=args.out, client=args.scheduler, n_workers=args.workers,
                        timeout=args.timeout, resume=not args.no_resume, retry_failed=args.retry_failed,
                        progress=showing(args))
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


def _metrics(args, outputs):
    from shapefmu import sweep as sweeps

    return sweeps.named_metrics(args.metric, outputs=outputs, command=args.command_variable, after=args.after,
                                position=args.position, target=args.target, tolerance=args.tolerance)


def _variables(system) -> dict[str, set[str]]:
    """Each component's variable names, from its FMU's model description."""
    from shapefmu.fmi.archives import read_description

    return {name: {v.name for v in read_description(component.fmu).modelVariables}
            for name, component in system.components.items()}


def _matching(patterns, known) -> list[str]:
    """``--outputs`` with each fnmatch pattern replaced by the variables it matches (sorted), so the
    master records them; a pattern that matches nothing is refused by name."""
    names = []
    for pattern in patterns:
        if not any(ch in pattern for ch in "*?["):
            names.append(pattern)
            continue
        found = sorted(f"{c}.{v}" for c, variables in known.items() for v in variables
                       if fnmatch.fnmatchcase(f"{c}.{v}", pattern))
        if not found:
            raise ValueError(f"--outputs {pattern!r} matches no variable of the system")
        names += found
    return list(dict.fromkeys(names))


def _check_variable(name, known, system, origin) -> None:
    component, dot, variable = name.partition(".")
    if not dot or component not in known:
        raise ValueError(f"{name!r} must be component.variable with a component of {origin} "
                         f"({', '.join(system.components)})")
    if variable not in known[component]:
        raise ValueError(f"{name!r}: component {component!r} of {origin} has no variable {variable!r}")


def register(commands) -> None:
    p = commands.add_parser(
        "sweep", help="co-simulate a system over a parameter grid on Dask, one row per run (the dask extra)",
        arguments=_sweep_arguments,
        epilog=examples("shapefmu sweep disk_drive_shaped --vary plant.f[1]=1800:2200:5 --metric residual "
                        "--outputs 'plant.deflection_*' --command shaper.y --out results/sweep.csv"))
    p.set_defaults(run=_cmd_sweep)


def _sweep_arguments(p) -> None:
    from shapefmu.cosim.master import ALGORITHMS

    p.add_argument("system", help="SSP system (.ssp archive, or .ssd with its FMUs beside it) or a shipped one by name "
                   "(shapefmu plant list); packed with its FMUs and sent to the workers as bytes")
    p.add_argument("--vary", action="append", default=[], metavar="NAME=SPEC",
                   help="grid axis: NAME=START:STOP:N (linspace) or NAME=V1,V2,...; repeat for a product grid")
    p.add_argument("--sample", action="append", default=[], metavar="NAME=LOW:HIGH", help="uniform sampling range")
    p.add_argument("--samples", type=int, help="number of random samples drawn from the --sample ranges")
    p.add_argument("--seed", type=int, default=0, help="seed of the random samples (default 0)")
    p.add_argument("--metric", action="append", required=True, choices=("residual", "move_time", "peak"),
                   help="metric per run; repeat for several")
    p.add_argument("--outputs", action="append", default=[], metavar="VAR",
                   help="variables whose residual vibration is measured (fnmatch patterns allowed, recorded "
                        "without --record)")
    p.add_argument("--command", dest="command_variable", metavar="VAR", help="command variable: its rest ends the move; peak is its max |u|")
    p.add_argument("--after", type=float, help="start of the residual window in s (default: end of the move)")
    p.add_argument("--position", metavar="VAR", help="variable that must settle for move_time")
    p.add_argument("--target", type=float, help="final value of --position")
    p.add_argument("--tolerance", type=float, help="settling band half-width of move_time")
    add_experiment_arguments(p)
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
