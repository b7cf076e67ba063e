"""Argument parsers shared by the command modules (modes in Hz, design and sampling options).

Imported by the command modules of this package, never the other way. It imports only the standard
library at the top: ``shapefmu --help`` loads it.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path


def parse_mode_hz(text: str) -> tuple[float, float]:
    """``"2000"`` or ``"2000:0.01"`` -> (f Hz, zeta), as an FMU's f[i] and zeta[i] take them."""
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
    return hz, zeta


def parse_mode(text: str) -> tuple[float, float]:
    """``"2000"`` or ``"2000:0.01"`` (Hz, damping ratio) -> (omega rad/s, zeta), as the Python API takes them."""
    hz, zeta = parse_mode_hz(text)
    return 2.0 * math.pi * hz, zeta


def examples(*lines: str) -> str:
    """An ``epilog`` of example command lines (each may end in ``#  what it does``)."""
    return "example" + ("s" if len(lines) > 1 else "") + ":\n" + "\n".join(f"  {line}" for line in lines)


def add_design_arguments(parser: argparse.ArgumentParser, kinds=None) -> None:
    """KIND, --mode (repeatable), --vtol and --n: what an impulse-shaper design takes (``kinds``:
    the choices of KIND, default every impulse-shaper design)."""
    if kinds is None:
        from shapefmu.shapers import KINDS as kinds
    parser.add_argument("kind", choices=kinds, help="shaper design")
    parser.add_argument(
        "--mode", type=parse_mode, action="append", required=True, metavar="HZ[:ZETA]",
        help="mode frequency in Hz and damping ratio; repeat for several modes",
    )
    parser.add_argument("--vtol", type=float, default=0.05, help="tolerable vibration of the EI family (default 0.05)")
    parser.add_argument("--n", type=int, default=1, help="derivative order of zv_dn (0 = ZV, 1 = ZVD, ...)")


def add_sampling_arguments(parser: argparse.ArgumentParser) -> None:
    """--order, --ts and --adjust-ts: what a sampled window filter takes."""
    parser.add_argument("--order", type=int, default=1, help="robustness order of window filters (default 1)")
    parser.add_argument("--ts", type=float, help="sampling period in s (window default: pi/(100 omega_d))")
    parser.add_argument("--adjust-ts", action="store_true", help="use the nearest ts that makes M an integer")


def output_file(*suffixes: str, what: str = "file"):
    """An argparse ``type`` for a file the command will write: checked when the command line is
    read, so that a run is never thrown away at the end for a path it cannot write.

    The name must end in one of ``suffixes`` (any when none is given; ``"plot"`` takes what
    matplotlib can save), must not be a folder, and the nearest folder on its path that exists
    must be writable (missing folders are created when the file is written).
    """

    def check(text: str) -> str:
        path = Path(text)
        plot = suffixes == ("plot",)
        allowed = _plot_suffixes() if plot else suffixes
        if allowed and path.suffix.lower() not in allowed:
            raise argparse.ArgumentTypeError(
                f"{text!r}: the {'plot' if plot else what} name must end in {', '.join(sorted(allowed))}")
        _check_writable(path, text)
        return text

    return check


def output_folder(text: str) -> str:
    """An argparse ``type`` for a folder the command writes into: not a file, and writable."""
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is a file; give a folder")
    _check_writable(path / "_", text)
    return text


def say_written(args, message: str) -> None:
    """Say that a file was written: on stdout, or on stderr when ``--json`` keeps stdout for the JSON alone."""
    print(message, file=sys.stderr if getattr(args, "json", None) is True else sys.stdout)


def _check_writable(path: Path, text: str) -> None:
    from shapefmu.files import check_output

    if os.path.isdir(path) and not os.path.islink(path):  # os.path: False, not OSError, on too long a name
        raise argparse.ArgumentTypeError(f"{text!r} is a folder; give a file name")
    try:  # a link, a FIFO or a device, a name the file system cannot hold
        check_output(path, "file")
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None
    folder = path.parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    if not folder.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r}: {str(folder)!r} on its path is a file, not a folder")
    if not os.access(folder, os.W_OK | os.X_OK) or (path.exists() and not os.access(path, os.W_OK)):
        raise argparse.ArgumentTypeError(f"{text!r}: no permission to write there")


def _plot_suffixes() -> set[str]:
    from matplotlib.backend_bases import FigureCanvasBase

    return {f".{kind}" for kind in FigureCanvasBase.get_supported_filetypes()}


def read_system(name_or_path):
    """The SSP system file given, or the shipped example system of that name, which takes its FMUs
    from ./fmus (where ``shapefmu build`` writes them)."""
    from shapefmu.fmi.ssp import read_ssp
    from shapefmu.plants.shipped import SYSTEM_SUFFIXES, find

    path = find(name_or_path, SYSTEM_SUFFIXES, "SSP system")
    if path == Path(name_or_path):
        return read_ssp(path)
    try:
        return read_ssp(path, fmu_folder="fmus")
    except ValueError as error:
        raise ValueError(f"{error}; the shipped system {name_or_path!r} runs the FMUs of ./fmus: "
                         f"run `shapefmu build` here first") from None


def add_experiment_arguments(parser: argparse.ArgumentParser) -> None:
    """--stop and --step of a run, both defaulting to what the system file says."""
    parser.add_argument("--stop", "--stop-time", dest="stop", type=float, metavar="S",
                        help="stop time in s (default: the system's DefaultExperiment stopTime)")
    parser.add_argument("--step", type=float, metavar="S", help="macro (communication) step in s (default: the "
                        "step the system file was written for, OSP baseStepSize or OMSimulator stepSize)")


def experiment(system, args) -> tuple[float, float]:
    """(stop time, step) of a run: ``--stop`` and ``--step``, else the system's own."""
    from shapefmu.fmi.ssp.targets import written_step

    stop = args.stop if args.stop is not None else system.stop_time
    step = args.step if args.step is not None else written_step(system)
    missing = [option for option, value in (("--stop", stop), ("--step", step)) if value is None]
    if missing:
        raise ValueError(f"give {' and '.join(missing)}: the system {system.name!r} does not say "
                         f"({'no DefaultExperiment stopTime' if stop is None else 'no macro step in its annotations'})")
    return stop, step
