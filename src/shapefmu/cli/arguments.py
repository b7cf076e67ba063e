"""Argument parsers shared by the command modules (modes in Hz, design and sampling options).

Imported by the command modules of this package, never the other way.
"""

from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

from shapefmu.shapers import KINDS


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


def add_design_arguments(parser: argparse.ArgumentParser, kinds=KINDS) -> None:
    """KIND, --mode (repeatable), --vtol and --n: what an impulse-shaper design takes."""
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


def _check_writable(path: Path, text: str) -> None:
    from shapefmu.cosim.output_files import check_output

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
