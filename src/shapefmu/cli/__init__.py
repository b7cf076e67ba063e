"""The ``shapefmu`` command line: a module per command group; this package assembles them.

Each command module has ``register(commands)``, which adds its commands with a one-line purpose
(``help``), an example (``epilog``) and, as ``arguments=``, the function that defines the command's
options: it runs only when that command is parsed, so ``shapefmu --help`` and a light command
(``plant list``) import neither numpy nor fmpy nor CasADi. A command imports what it needs inside
its ``run`` function for the same reason (``benchmarks/cli_start.py`` measures the start-up).

Modes are given in Hz on the command line (as a datasheet or an FFT gives them) and converted to
rad/s for the Python API. This is the experiments layer: it may import every other layer; nothing
imports it.

Errors are one line on stderr, ``shapefmu <command>: error: ...``, naming the argument, file,
element or parameter and the valid range, never a traceback. Exit codes:

- 2: what was given is wrong: an argument value, the content of a file named on the command line
  (a malformed model, system or FMU, a corrupt archive), or a size past ``runtime.limits``;
- 1: what was given is right but the work failed: an FMU failed during a run, every run of a sweep
  failed, the operating system refused to read or write a file (OSError), or a package of an
  extra the command needs is not installed (the line names the extra: see ``extras``);
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
from shapefmu.cli import build, design, extras, identify, motion, moves, plant, simulate, sweep
from shapefmu.cli.signals import exit_code, interrupts

# The order of the groups in ``shapefmu --help``.
COMMAND_GROUPS = (design, identify, plant, moves, motion, build, sweep, simulate)

DESCRIPTION = """Design vibration-suppressing commands for flexible machines (input shapers, shape filters,
motion profiles, time-optimal and STOS moves), package them as FMI 2.0/3.0 FMUs, and run them
against plant FMUs in a co-simulation master."""
EPILOG = """examples:
  shapefmu design zvd --mode 2000:0.01          a ZVD shaper for a 2 kHz mode with 1 % damping
  shapefmu plant list                           the plant models and SSP systems that ship
  shapefmu build                                every FMU into ./fmus
  shapefmu compare disk_drive --distance 0.05   the disk-drive seek: every candidate vs time-optimal
  shapefmu recommend resonances_x.csv           a shaper for a machine, from its recording

Modes are given in Hz, HZ[:ZETA]. `shapefmu COMMAND --help` shows a command's options and an example."""


class _Parser(argparse.ArgumentParser):
    """A usage error is one line on stderr (the usage is one ``--help`` away).

    ``arguments=define`` (a function of the parser) defines the options when the parser is first
    used, so that building the whole command tree imports nothing a command does not need; every
    command also gets ``--quiet`` (no progress on stderr; see ``progress``)."""

    def __init__(self, *args, arguments=None, **kwargs):
        kwargs.setdefault("formatter_class", argparse.RawDescriptionHelpFormatter)
        super().__init__(*args, **kwargs)
        self._define, self._complete = arguments, False

    def _defined(self):
        if not self._complete:
            self._complete = True
            if self._define is not None:
                self._define(self)
            if "run" in self._defaults and "--quiet" not in self._option_string_actions:
                self.add_argument("-q", "--quiet", action="store_true",
                                  help="no progress messages on stderr (they are shown on a terminal only)")
        return self

    def parse_known_args(self, args=None, namespace=None):
        return super(_Parser, self._defined()).parse_known_args(args, namespace)

    def format_help(self):
        return super(_Parser, self._defined()).format_help()

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="shapefmu", description=DESCRIPTION, epilog=EPILOG)
    parser.add_argument("--version", action="version", version=f"shapefmu {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for group in COMMAND_GROUPS:
        group.register(commands)
    return parser


# What a command raises for bad input (exit 2) and for work that failed (exit 1); anything else is
# a bug in shapefmu and keeps its traceback.
_BAD_INPUT = (ValueError, OverflowError, SyntaxError, zipfile.BadZipFile, zlib.error)


def _failed() -> tuple[type[BaseException], ...]:
    """The exceptions of work that failed. CosimError counts only once the master was imported: a
    command that never imported it cannot have raised it, and --help stays free of fmpy."""
    cosim_errors = sys.modules.get("shapefmu.cosim.errors")
    return (OSError, cosim_errors.CosimError) if cosim_errors else (OSError,)


def _explain(error: BaseException) -> tuple[int, str] | None:
    """(exit code, one-line message) for an error a command may raise, None for a bug."""
    if isinstance(error, ImportError) and (missing := extras.explain(error)):
        return 1, missing
    if not isinstance(error, _BAD_INPUT + _failed()):
        return None
    if isinstance(error, SyntaxError):  # malformed XML (ElementTree, lxml) or Python model file
        message = f"{error.filename or 'a file'}: malformed ({type(error).__name__}: {error.msg or error})"
    elif isinstance(error, (zipfile.BadZipFile, zlib.error)):  # an archive not checked where it was opened
        message = f"a corrupt or non-zip archive ({type(error).__name__}: {error})"
    elif isinstance(error, OSError):  # the system refused: permission, disk full, a folder for a file
        message = f"{error.filename}: {error.strerror}" if error.filename else str(error)
    else:
        message = str(error)
    return (2 if isinstance(error, _BAD_INPUT) else 1), " | ".join(line for line in message.splitlines() if line.strip())


def main(argv=None) -> int:
    parser = build_parser()
    with interrupts() as received:
        try:
            args = parser.parse_args(argv)  # defining a command's options may import a missing extra
            return args.run(args)
        except Exception as error:  # noqa: BLE001 -- sorted by _explain; a bug keeps its traceback
            explained = _explain(error)
            if explained is None:
                raise
            code, message = explained
            parser.exit(code, f"shapefmu {_command(argv)}: error: {message}\n")
        except KeyboardInterrupt:  # Ctrl-C or SIGTERM outside a run loop (see .signals)
            name = signal.Signals(received[-1]).name if received else "SIGINT"
            parser.exit(exit_code(received), f"shapefmu {_command(argv)}: interrupted ({name})\n")


def _command(argv) -> str:
    """The command's name as typed (the first word that is not an option)."""
    words = sys.argv[1:] if argv is None else argv
    return next((word for word in words if not str(word).startswith("-")), "")


if __name__ == "__main__":
    sys.exit(main())
