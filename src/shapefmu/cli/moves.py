"""``shapefmu optimal`` and ``stos``: the time-optimal move and the STOS closed loop for a plant model.
"""

from __future__ import annotations

from shapefmu.cli.arguments import examples, output_file


def _cmd_optimal(args) -> int:
    from shapefmu.cli.progress import reporter
    from shapefmu.optimal import optimal_report

    print(optimal_report(args.file, args.distance, u_max=args.u_max, plot=args.plot, json_path=args.json,
                         csv_path=args.csv, progress=reporter(args, "optimal")))
    return 0


def _cmd_stos(args) -> int:
    from shapefmu.stos import stos_report

    print(stos_report(args.file, args.distance, shaper=args.shaper, Ts=args.ts, t_end=args.t_end, u_max=args.u_max,
                      plot=args.plot))
    return 0


def register(commands) -> None:
    p = commands.add_parser("optimal", help="time-optimal move beside the rigid and shaped bang-bang moves",
                            arguments=_optimal_arguments,
                            epilog=examples("shapefmu optimal disk_drive --distance 0.05 --plot results/optimal.png",
                                            "shapefmu optimal disk_drive --distance 0.05 --json results/solution.json"))
    p.set_defaults(run=_cmd_optimal)
    p = commands.add_parser("stos", help="shaped time-optimal closed-loop move (STOS, paper 002), sampled",
                            arguments=_stos_arguments,
                            epilog=examples("shapefmu stos disk_drive --distance 0.05 --shaper simultaneous "
                                            "--plot results/stos.png"))
    p.set_defaults(run=_cmd_stos)


def _optimal_arguments(p) -> None:
    p.add_argument("file", help="plant model file or shipped name, e.g. disk_drive")
    p.add_argument("--distance", type=float, required=True, help="move distance of the plant's first output")
    p.add_argument("--u-max", type=float, default=None, help="input limit (default: the input's limit in the file)")
    p.add_argument("--plot", metavar="PNG", type=output_file("plot"),
                   help="save u(t) of every move and the outputs of the optimal move")
    p.add_argument("--json", metavar="FILE", type=output_file(".json", what="solution file"),
                   help="save the time-optimal solution as JSON (for `shapefmu build reference`)")
    p.add_argument("--csv", metavar="FILE", type=output_file(".csv", what="signal table"),
                   help="save the time-optimal u(t) as a time,value signal table")


def _stos_arguments(p) -> None:
    p.add_argument("file", help="plant model file in the form of eq. (1) of paper 002, or a shipped name (disk_drive)")
    p.add_argument("--distance", type=float, required=True, help="move distance of the rigid body")
    p.add_argument("--shaper", choices=("convolution", "simultaneous", "zvd", "ei"), default="simultaneous",
                   help="multi-mode shaper the law is built from (default simultaneous)")
    p.add_argument("--ts", type=float, default=1e-6, help="sampling period of the controller in s (default 1e-6)")
    p.add_argument("--t-end", type=float, help="simulated time in s (default: twice the rigid move + 2 ms)")
    p.add_argument("--u-max", type=float, default=None, help="input limit (default: the input's limit in the file)")
    p.add_argument("--plot", metavar="PNG", type=output_file("plot"),
                   help="save u, x_r, x_r', x_f, x_f' against time (like Fig. 6)")
