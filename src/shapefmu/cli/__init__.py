"""The ``shapefmu`` command line: a module per command group, sharing ``arguments``.

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
rad/s for the Python API. This is the experiments layer: it may import every other layer; nothing
imports it. Each command module has ``register(commands)``; this package only assembles them.
"""

from __future__ import annotations

import argparse
import sys

from shapefmu import __version__
from shapefmu.cli import build, design, moves, plant, simulate, sweep

# The order of the groups in ``shapefmu --help``.
COMMAND_GROUPS = (design, plant, moves, build, sweep, simulate)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="shapefmu", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"shapefmu {__version__}")
    commands = parser.add_subparsers(dest="command", required=True)
    for group in COMMAND_GROUPS:
        group.register(commands)
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
