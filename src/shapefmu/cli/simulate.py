"""``shapefmu simulate`` and ``compare``: SSP systems of FMUs run by the co-simulation master.
"""

from __future__ import annotations

import contextlib
import signal
import sys
from pathlib import Path

import numpy as np

from shapefmu.cli.arguments import output_file, output_folder


def _cmd_simulate(args) -> int:
    from shapefmu.cosim import CosimError, CosimInterrupted, Master, save_results

    parameters = {}
    for item in args.set:
        name, equals, value = item.partition("=")
        if not equals:
            raise ValueError(f"--set must be component.variable=VALUE, got {item!r}")
        parameters[name] = value  # typed by the model description: a number, true/false, an item, text
    master = None
    with _interrupts() as received:
        try:
            with Master(args.system, args.step, algorithm=args.algorithm, record=args.record,
                        output_interval=args.output_interval, model_exchange=args.model_exchange,
                        progress=args.progress) as master:
                try:
                    results, status = master.run(args.stop, parameters=parameters), 0
                except (CosimError, CosimInterrupted) as error:
                    results, status = error.partial, 1
                    print(f"shapefmu simulate: {_failure(error, received)}", file=sys.stderr)
                _print_fmu_warnings(master)
        except KeyboardInterrupt:  # before the run started: nothing recorded
            print("shapefmu simulate: interrupted before the run started", file=sys.stderr)
            results, status = None, 130
    if received:
        status = 128 + received[0]  # 130 for Ctrl-C, 143 for SIGTERM, as a shell reports them
    elif master is not None and master.termination is not None:
        print(f"shapefmu simulate: {master.termination}: a normal end", file=sys.stderr)
    if results is None or not len(results):  # failed or stopped before the first record
        return status
    last = results[-1]
    print(f"{len(results)} records to t = {last['time']:.9g} s")
    for name in results.dtype.names[1:]:
        if results.dtype[name].kind in "fiu":
            print(f"  {name:30s} final {last[name]: .9g}   peak |.| {np.max(np.abs(results[name])):.6g}")
        else:
            print(f"  {name:30s} final {last[name]!s}")
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        print(f"results written to {save_results(results, args.out)}")
    if args.plot and not any(results.dtype[name].kind in "fiub" for name in results.dtype.names[1:]):
        print("no numeric variable recorded: no plot written")
    elif args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        names = [name for name in results.dtype.names[1:] if results.dtype[name].kind in "fiub"]  # no strings
        figure, axes = plt.subplots(len(names), 1, sharex=True, figsize=(8, 2 + 1.6 * len(names)), squeeze=False)
        for axis, name in zip(axes[:, 0], names):
            axis.plot(results["time"], results[name], drawstyle="default" if results.dtype[name].kind == "f" else "steps-post")
            axis.set_ylabel(name)
        axes[-1, 0].set_xlabel("time [s]")
        figure.tight_layout()
        Path(args.plot).parent.mkdir(parents=True, exist_ok=True)
        figure.savefig(args.plot)
        print(f"plot written to {args.plot}")
    return status


@contextlib.contextmanager
def _interrupts():
    """Ctrl-C and SIGTERM (``kill``, ``timeout``, a batch system ending a job) stop a run alike, so
    the results recorded so far are saved; yields the list of signals received."""
    received = []

    def interrupt(signum, frame):
        received.append(signum)
        raise KeyboardInterrupt

    try:
        previous = {number: signal.signal(number, interrupt) for number in (signal.SIGINT, signal.SIGTERM)}
    except ValueError:  # not the main thread (shapefmu.cli.main called from a worker): leave them alone
        yield received
        return
    try:
        yield received
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


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
    from shapefmu.cosim.compare import compare

    comparison = compare(args.file, args.distance, candidates=args.candidate or None, step=args.step, cache=args.fmus,
                         u_max=args.u_max, tolerance=args.tolerance, plot=args.plot)
    print(comparison.table())
    if args.plot:
        print(f"plot written to {args.plot}")
    return 0


def register(commands) -> None:
    p = commands.add_parser("simulate", help="run an SSP system of FMUs with the co-simulation master")
    p.add_argument("system", help="SSP system (.ssp archive or .ssd file)")
    p.add_argument("--stop", type=float, required=True, help="stop time in s")
    p.add_argument("--step", type=float, required=True, help="macro (communication) step in s")
    p.add_argument("--record", action="append", metavar="COMP.VAR", help="variable to record; repeat (default: every output)")
    p.add_argument("--output-interval", type=float, help="record every this many s (a multiple of --step)")
    p.add_argument("--algorithm", choices=("gauss-seidel", "jacobi"), default="gauss-seidel", help="master algorithm")
    p.add_argument("--model-exchange", action="append", metavar="COMP", help="integrate this component as Model Exchange")
    p.add_argument("--set", action="append", default=[], metavar="COMP.VAR=VALUE",
                   help="parameter for this run, typed by the FMU (a number, true/false, an enumeration item, text); repeat")
    p.add_argument("--out", metavar="FILE", type=output_file(".csv", ".parquet", what="results file"),
                   help="save the results as .csv or .parquet (checked before the run)")
    p.add_argument("--plot", metavar="PNG", type=output_file("plot"), help="plot every recorded variable against time")
    p.add_argument("--progress", action="store_true", help="show a progress bar")
    p.set_defaults(run=_cmd_simulate)

    from shapefmu.cosim.compare import CANDIDATES

    p = commands.add_parser("compare", help="one plant, every candidate command, co-simulated as FMUs side by side")
    p.add_argument("file", help="plant model in the form of eq. (1) of paper 002, e.g. models/disk_drive.toml")
    p.add_argument("--distance", type=float, required=True, help="move distance of the rigid body")
    p.add_argument("--candidate", action="append", choices=CANDIDATES, help="candidate to run; repeat (default: all)")
    p.add_argument("--step", type=float, default=1e-6, help="macro step and sampling period of every FMU in s (default 1e-6)")
    p.add_argument("--fmus", default="fmus", type=output_folder,
                   help="folder where the FMUs are built and reused (default fmus)")
    p.add_argument("--u-max", type=float, default=None, help="input limit (default: the input's limit in the file)")
    p.add_argument("--tolerance", type=float, default=1e-3, help="settling band of the move time, relative to X and U")
    p.add_argument("--plot", metavar="PNG", type=output_file("plot"),
                   help="save u, position error and deflection of every candidate")
    p.set_defaults(run=_cmd_compare)
