"""The ``shapefmu`` command line: a module per command group, sharing ``arguments``.

    shapefmu design KIND --mode HZ[:ZETA] [--mode ...] [--vtol V] [--n N] [--json]
    shapefmu design WINDOW --mode HZ[:ZETA] [--order N] [--ts S] [--adjust-ts] [--json]
    shapefmu sensitivity KIND --mode HZ[:ZETA] [--mode ...] [--vtol V] --plot out.png
    shapefmu profile KIND --mode HZ[:ZETA] --distance D --speed V [--plot out.png] [--json]
    shapefmu plant show models/disk_drive.toml
    shapefmu plant build models/disk_drive.toml -o fmus/DiskDrive.fmu
    shapefmu optimal models/disk_drive.toml --distance X [--u-max U] [--plot out.png] [--json s.json] [--csv u.csv]
    shapefmu stos models/disk_drive.toml --distance X --shaper simultaneous [--ts S] [--plot out.png]
    shapefmu motion plan --axis NAME:FROM:TO:VMAX:AMAX:JMAX ... --mode [AXIS:]HZ:ZETA ... [--band B] [--vtol V] [--json] [--out traj.csv]
    shapefmu build [all | shaper --kind KIND --mode HZ[:ZETA] ... -o fmus/X.fmu]
    shapefmu build reference solution.json|table.csv [--interpolation hold|linear] -o fmus/TimeOptimal.fmu
    shapefmu build shape-filter --kind WINDOW|TWIN-PULSE|time-frequency --mode HZ[:ZETA] [--order N] [--ts S] -o fmus/X.fmu
    shapefmu sweep system.ssp --vary NAME=START:STOP:N [--vary NAME=V1,V2] --metric residual --out rows.parquet
    shapefmu simulate system.ssp --stop 0.01 --step 1e-6 [--record plant.x ...] [--out r.csv] [--plot out.png]
    shapefmu compare models/disk_drive.toml --distance X [--candidate stos-simultaneous ...] [--step S] [--fmus fmus] [--plot out.png]

Modes are given in Hz on the command line (as a datasheet or an FFT gives them) and converted to
rad/s for the Python API. This is the experiments layer: it may import every other layer; nothing
imports it. Each command module has ``register(commands)``; this package only assembles them.

Errors are one line on stderr, ``shapefmu <command>: error: ...``, naming the argument, file,
element or parameter and the valid range, never a traceback. Exit codes:

- 2: what was given is wrong: an argument value, the content of a file named on the command line
  (a malformed model, system or FMU, a corrupt archive), or a size past ``runtime.limits``;
- 1: what was given is right but the work failed: an FMU failed during a run, every run of a sweep
  failed, or the operating system refused to read or write a file (OSError);
- 130 (Ctrl-C) and 143 (SIGTERM) for an interrupted command (``simulate`` saves what it recorded,
  marked partial; every command removes its temporary folders: see ``signals``).
"""

from __future__ import annotations

import argparse
import signal
import sys
import zipfile
import zlib

from shapefmu import __version__
from shapefmu.cli import build, design, identify, motion, moves, plant, simulate, sweep
from shapefmu.cli.signals import exit_code, interrupts
from shapefmu.cosim.errors import CosimError

# The order of the groups in ``shapefmu --help``.
COMMAND_GROUPS = (design, identify, plant, moves, motion, build, sweep, simulate)


class _Parser(argparse.ArgumentParser):
    """A usage error is one line on stderr (the usage is one ``--help`` away)."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="shapefmu", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"shapefmu {__version__}")
    commands = parser.add_subparsers(dest="command", required=True)
    for group in COMMAND_GROUPS:
        group.register(commands)
    return parser


# What a command raises for bad input (exit 2) and for work that failed (exit 1); anything else is
# a bug in shapefmu and keeps its traceback.
_BAD_INPUT = (ValueError, OverflowError, SyntaxError, zipfile.BadZipFile, zlib.error)
_FAILED = (OSError, CosimError)


def _explain(error: BaseException) -> tuple[int, str]:
    """(exit code, one-line message) for an exception of ``_BAD_INPUT`` or ``_FAILED``."""
    if isinstance(error, SyntaxError):  # malformed XML (ElementTree, lxml) or Python model file
        message = f"{error.filename or 'a file'}: malformed ({type(error).__name__}: {error.msg or error})"
    elif isinstance(error, (zipfile.BadZipFile, zlib.error)):  # an archive not checked where it was opened
        message = f"a corrupt or non-zip archive ({type(error).__name__}: {error})"
    elif isinstance(error, OSError):  # the system refused: permission, disk full, a folder for a file
        message = f"{error.filename}: {error.strerror}" if error.filename else str(error)
    else:
        message = str(error)
    return (1 if isinstance(error, _FAILED) else 2), " | ".join(line for line in message.splitlines() if line.strip())


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    with interrupts() as received:
        try:
            return args.run(args)
        except _BAD_INPUT + _FAILED as error:
            code, message = _explain(error)
            parser.exit(code, f"shapefmu {args.command}: error: {message}\n")
        except KeyboardInterrupt:  # Ctrl-C or SIGTERM outside a run loop (see .signals)
            name = signal.Signals(received[-1]).name if received else "SIGINT"
            parser.exit(exit_code(received), f"shapefmu {args.command}: interrupted ({name})\n")


if __name__ == "__main__":
    sys.exit(main())
