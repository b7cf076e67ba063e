"""``shapefmu plant list``, ``plant show`` and ``plant build``: plant models and their native FMUs.

A model is a file (``models/disk_drive.toml``, a ``.py`` defining ``plant()``) or the name of one that
ships with shapefmu (``disk_drive``): a path that exists wins.
"""

from __future__ import annotations

from shapefmu.cli.arguments import examples, output_file


def _cmd_plant_list(args) -> int:
    from shapefmu.plants.shipped import describe

    print(describe())
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
    print(f"plant FMU written to {build_plant_fmu(model, args.output, fmi_version=args.fmi_version)}")
    return 0


def register(commands) -> None:
    p = commands.add_parser("plant", help="plant models: list the shipped ones, show one, build its native FMU",
                            arguments=_plant_arguments,
                            epilog=examples("shapefmu plant list", "shapefmu plant show disk_drive",
                                            "shapefmu plant build disk_drive -o fmus/DiskDrive.fmu"))


def _plant_arguments(p) -> None:
    plant_commands = p.add_subparsers(dest="plant_command", required=True, metavar="ACTION")
    q = plant_commands.add_parser("list", help="the plant models and SSP systems that ship with shapefmu",
                                  epilog=examples("shapefmu plant list"), arguments=lambda q: None)
    q.set_defaults(run=_cmd_plant_list)
    q = plant_commands.add_parser("show", help="print a plant model's signals, parameters and modes",
                                  epilog=examples("shapefmu plant show disk_drive",
                                                  "shapefmu plant show my_machine.toml"),
                                  arguments=lambda q: q.add_argument(
                                      "file", help="plant model file or shipped name, e.g. my_machine.toml or disk_drive"))
    q.set_defaults(run=_cmd_plant_show)
    q = plant_commands.add_parser("build", help="generate and compile a native ME + CS plant FMU (FMI 2.0 or 3.0)",
                                  epilog=examples("shapefmu plant build disk_drive -o fmus/DiskDrive.fmu",
                                                  "shapefmu plant build disk_drive --fmi-version 3.0 -o fmus/DiskDrive3.fmu"),
                                  arguments=_plant_build_arguments)
    q.set_defaults(run=_cmd_plant_build)


def _plant_build_arguments(q) -> None:
    q.add_argument("file", help="plant model: a .toml model file, a .py file defining plant(), or a shipped name "
                   "(disk_drive; see shapefmu plant list)")
    q.add_argument("-o", "--output", required=True, metavar="FMU", type=output_file(".fmu", what="FMU"),
                   help="FMU to write, e.g. fmus/DiskDrive.fmu")
    q.add_argument("--fmi-version", choices=("2.0", "3.0"), default="2.0", help="FMI version of the FMU (default 2.0)")
