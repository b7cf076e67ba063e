"""``shapefmu simulate`` and ``compare``: SSP systems of FMUs run by the co-simulation master.

``--write-ssp FILE [--target omsimulator|libcosim]`` writes the system a command runs (with its
experiment, and ``--set`` values as bindings), for OMSimulator or libcosim to open without Python.
"""

from __future__ import annotations

import contextlib
import signal
import sys
from pathlib import Path

from shapefmu.cli.arguments import (
    add_experiment_arguments,
    examples,
    experiment,
    output_file,
    output_folder,
    read_system,
)
from shapefmu.cli.progress import reporter, showing
from shapefmu.cli.signals import deferred, exit_code, interrupts


def _write_ssp(system, args, stop: float, step: float, parameters: dict) -> None:
    """``simulate --write-ssp``: the system with this run's stop time, macro step and ``--set``
    values, as an .ssp archive (FMUs inside) or an .ssd file (FMUs where they are). Without
    ``--target`` the step is recorded as OSP's annotation (libcosim's), which other tools ignore, so
    ``shapefmu simulate FILE`` runs the file again as it was run."""
    if args.write_ssp is None:
        if args.target is not None or args.fold:
            raise ValueError("--target and --fold apply to --write-ssp FILE, which is not given")
        return
    from shapefmu.fmi.ssp import write_system

    path = write_system(system.for_experiment(stop, parameters), args.write_ssp, args.target or "libcosim", step,
                        _fold(args.fold))
    print(f"system written to {path}" + (f" for {args.target}" if args.target else ""))


def _fold(items: list[str]) -> dict:
    """``--fold shaper.y=u`` / ``--fold plant.voltage=b2,b4[1]``: ``{connector: [parameters]}``."""
    fold = {}
    for item in items:
        connector, equals, names = item.partition("=")
        if not equals or not connector or not names:
            raise ValueError(f"--fold must be component.output=PARAMETER[,PARAMETER...], got {item!r}")
        fold[connector] = names.split(",")
    return fold


def _cmd_simulate(args) -> int:
    from shapefmu.cosim import CosimError, CosimInterrupted, Master
    from shapefmu.cosim.output_files import output_lock

    parameters = {}
    for item in args.set:
        name, equals, value = item.partition("=")
        if not equals:
            raise ValueError(f"--set must be component.variable=VALUE, got {item!r}")
        parameters[name] = value  # typed by the model description: a number, true/false, an item, text, [array]
    system = read_system(args.system)
    stop, step = experiment(system, args)
    _write_ssp(system, args, stop, step, parameters)
    master = None
    with output_lock(args.out) if args.out else contextlib.nullcontext():  # one run writes a file at a time
        with interrupts() as received:
            try:
                with Master(system, step, algorithm=args.algorithm, record=args.record,
                            output_interval=args.output_interval, model_exchange=args.model_exchange,
                            progress=args.progress or showing(args)) as master:
                    try:
                        results, status, stopped = master.run(stop, parameters=parameters), 0, None
                    except (CosimError, CosimInterrupted) as error:
                        results, status, stopped = error.partial, 1, _failure(error, received)
                        print(f"shapefmu simulate: {stopped}", file=sys.stderr)
                    _print_fmu_warnings(master)
            except KeyboardInterrupt:  # before the run started: nothing recorded
                print("shapefmu simulate: interrupted before the run started", file=sys.stderr)
                results, status, stopped = None, 130, "interrupted"
        if received:
            status = exit_code(received)  # 130 for Ctrl-C, 143 for SIGTERM, as a shell reports them
        elif master is not None and master.termination is not None:
            print(f"shapefmu simulate: {master.termination}: a normal end", file=sys.stderr)
        if results is None or not len(results):  # failed or stopped before the first record
            return status
        with deferred() as late:  # the files are written whole; a signal now takes effect after them
            _report(results, args, stopped)
    if late:
        print(f"shapefmu simulate: {signal.Signals(late[-1]).name} received while the results were written: "
              f"they were written whole", file=sys.stderr)
        return exit_code(late)
    return status


def _report(results, args, stopped: str | None) -> None:
    """Print the run's summary, save ``--out`` (marked partial when the run ``stopped`` early) and ``--plot``."""
    import numpy as np

    from shapefmu.cosim import save_results

    last = results[-1]
    print(f"{len(results)} records to t = {last['time']:.9g} s" + (" (partial: the run stopped early)" if stopped else ""))
    for name in results.dtype.names[1:]:
        if results.dtype[name].kind in "fiu":
            print(f"  {name:30s} final {last[name]: .9g}   peak |.| {np.max(np.abs(results[name])):.6g}")
        else:
            print(f"  {name:30s} final {last[name]!s}")
    if args.out:
        path = save_results(results, args.out, partial=stopped)
        if stopped:
            print(f"shapefmu simulate: {path} holds partial results, to t = {last['time']:.9g} s "
                  f"(its last line says so)", file=sys.stderr)
        print(f"results written to {path}")
    if args.plot and not any(results.dtype[name].kind in "fiub" for name in results.dtype.names[1:]):
        print("no numeric variable recorded: no plot written")
    elif args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from shapefmu.files import save_figure

        names = [name for name in results.dtype.names[1:] if results.dtype[name].kind in "fiub"]  # no strings
        figure, axes = plt.subplots(len(names), 1, sharex=True, figsize=(8, 2 + 1.6 * len(names)), squeeze=False)
        for axis, name in zip(axes[:, 0], names):
            axis.plot(results["time"], results[name], drawstyle="default" if results.dtype[name].kind == "f" else "steps-post")
            axis.set_ylabel(name)
        axes[-1, 0].set_xlabel("time [s]")
        figure.tight_layout()
        save_figure(figure, args.plot)
        print(f"plot written to {args.plot}")


def _failure(error, received) -> str:
    """The line that reports a run that stopped: interrupted, or failed (naming the FMU and call).

    A signal that lands while a Python FMU runs its own code surfaces as that FMU's error (the
    exception is raised inside it): it is reported as the interruption it was."""
    if received:
        when = f" at t = {error.time:.9g} s" if error.time is not None else ""
        return f"co-simulation interrupted{when} ({signal.Signals(received[0]).name})"
    return "error: " + " | ".join(str(error).splitlines())


def _print_fmu_warnings(master) -> None:
    """What the FMUs logged as warnings (e.g. a mode above a shaper's Nyquist frequency), on stderr."""
    for unit in master.units:
        for message in unit.messages:
            if message.startswith("[fmi2Warning]"):
                print(f"shapefmu simulate: warning: component {unit.name!r}: {message[len('[fmi2Warning] '):]}",
                      file=sys.stderr)


def _cmd_compare(args) -> int:
    from shapefmu.compare import compare

    if args.target is not None and args.write_ssp is None:
        raise ValueError("--target applies to --write-ssp FILE, which is not given")
    comparison = compare(args.file, args.distance, candidates=args.candidate or None, step=args.step, cache=args.fmus,
                         u_max=args.u_max, tolerance=args.tolerance, plot=args.plot, write_ssp=args.write_ssp,
                         target=args.target, native=args.native, fmi_version=args.fmi_version,
                         progress=reporter(args, "compare"))
    print(comparison.table())
    if args.plot:
        print(f"plot written to {args.plot}")
    for path in comparison.written:
        print(f"system written to {path}" + (f" for {args.target}" if args.target else ""))
    return 0


def _add_write_ssp(parser, fold: bool) -> None:
    from shapefmu.fmi.ssp.targets import TARGETS

    parser.add_argument("--write-ssp", metavar="FILE", type=output_file(".ssp", ".ssd", what="SSP file"),
                        help="also write the system run, with its experiment: .ssp (FMUs inside) or .ssd")
    parser.add_argument("--target", choices=TARGETS, help="write --write-ssp for this tool (with the macro step)")
    if fold:
        parser.add_argument("--fold", action="append", default=[], metavar="COMP.OUT=PARAM[,PARAM]",
                            help="--target omsimulator: fold a connection's factor into these parameters; repeat")


def register(commands) -> None:
    p = commands.add_parser(
        "simulate", help="run an SSP system of FMUs with the co-simulation master", arguments=_simulate_arguments,
        epilog=examples("shapefmu simulate disk_drive_shaped            # a shipped system, after `shapefmu build`",
                        "shapefmu simulate system.ssp --stop 0.01 --step 1e-5 --record plant.position --out r.csv"))
    p.set_defaults(run=_cmd_simulate)
    p = commands.add_parser(
        "compare", help="one plant, every candidate command, co-simulated as FMUs beside the time-optimal move",
        arguments=_compare_arguments,
        epilog=examples("shapefmu compare disk_drive --distance 0.05 --plot results/compare_disk_drive.png",
                        "shapefmu compare disk_drive --distance 0.05 --candidate convolution --native"))
    p.set_defaults(run=_cmd_compare)


def _simulate_arguments(p) -> None:
    from shapefmu.cosim.master import ALGORITHMS

    p.add_argument("system", help="SSP system (.ssp archive or .ssd file), or a shipped one by name (shapefmu plant list)")
    add_experiment_arguments(p)
    p.add_argument("--record", action="append", metavar="COMP.VAR",
                   help="variable to record, an array as a column per element; repeat (default: every output)")
    p.add_argument("--output-interval", type=float, help="record every this many s (a multiple of --step)")
    p.add_argument("--algorithm", choices=ALGORITHMS, default="gauss-seidel", help="master algorithm")
    p.add_argument("--model-exchange", action="append", metavar="COMP", help="integrate this component as Model Exchange")
    p.add_argument("--set", action="append", default=[], metavar="COMP.VAR=VALUE",
                   help="parameter for this run, typed by the FMU (a number, true/false, an enumeration item, text; "
                        "an FMI 3.0 array whole as [V1,V2,...] or one element as COMP.VAR[I]=VALUE, I from 1); repeat")
    p.add_argument("--out", metavar="FILE", type=output_file(".csv", ".parquet", what="results file"),
                   help="save the results as .csv or .parquet (checked before the run)")
    p.add_argument("--plot", metavar="PNG", type=output_file("plot"), help="plot every recorded variable against time")
    p.add_argument("--progress", action="store_true", help="show the progress bar even when stderr is not a terminal")
    _add_write_ssp(p, fold=True)


def _compare_arguments(p) -> None:
    from shapefmu.compare import CANDIDATES

    p.add_argument("file", help="plant model in the form of eq. (1) of paper 002: a model file or a shipped name "
                   "(disk_drive)")
    p.add_argument("--distance", type=float, required=True, help="move distance of the rigid body")
    p.add_argument("--candidate", action="append", choices=CANDIDATES, help="candidate to run; repeat (default: all)")
    p.add_argument("--step", type=float, default=1e-6, help="macro step and sampling period of every FMU in s (default 1e-6)")
    p.add_argument("--fmus", default="fmus", type=output_folder,
                   help="folder where the FMUs are built and reused (default fmus)")
    p.add_argument("--u-max", type=float, default=None, help="input limit (default: the input's limit in the file)")
    p.add_argument("--tolerance", type=float, default=1e-3, help="settling band of the move time, relative to X and U")
    p.add_argument("--native", action="store_true", help="run every command FMU as its native C twin (no Python in the "
                   "loop; built into FMUS/native/ with each system's parameters baked in)")
    p.add_argument("--fmi-version", choices=("2.0", "3.0"), default="2.0",
                   help="with --native: 3.0 runs every FMU, the plant too, as FMI 3.0 (built into FMUS/native3/; the "
                   "shaper's modes bound as the array parameters f and zeta)")
    p.add_argument("--plot", metavar="PNG", type=output_file("plot"),
                   help="save u, position error and deflection of every candidate")
    _add_write_ssp(p, fold=False)
