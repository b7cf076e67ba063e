"""Every file a shapefmu command writes goes through here: checked first, then written whole.

* ``check_output(path, what, named=True)``: the checks alone, for a command to make before its work,
  so that a run is not thrown away at the end for a path it may not write. Refused (ValueError, one
  line naming the file): a symbolic link (the file would be written through it, into whatever it
  points at), a folder, a FIFO (a write with no reader blocks forever), a device or socket, a name
  longer than the file system allows; and, for a file the user did not name (``named=False``: an
  .ssv written beside the FMU they named, a system per candidate), one that exists: shapefmu
  replaces only the files it was told to.
* ``write_file(path, write, what, named=True)``: the checks again, then ``write(temporary)`` into a
  new file beside ``path`` (created exclusively, so never through a link planted under its name),
  renamed over ``path``: a reader, or a run killed mid-write, sees the old file or the new one,
  never half of one; a link planted at ``path`` meanwhile is replaced, never followed.
  ``write_text`` and ``write_bytes`` are its short forms, ``save_figure`` a matplotlib figure's.
* ``append_to(path, what)``: a journal appended row by row (a sweep's), checked and never opened
  through a link.

Standard library only.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from pathlib import Path

NAME_MAX = 255  # bytes of one path component on Linux file systems (ext4, xfs, btrfs, tmpfs)


def check_output(path, what: str = "output file", named: bool = True) -> Path:
    """``path`` as a file a command may write (see the module docstring); ValueError if it may not."""
    path = Path(path)
    for part in path.parts:
        if len(os.fsencode(part)) > NAME_MAX:
            raise ValueError(f"{what} {str(path)[:80]!r}...: the name {part[:40]!r}... is {len(os.fsencode(part))} bytes, "
                             f"more than the {NAME_MAX} a file name may have")
    try:
        status = os.lstat(path)
    except (FileNotFoundError, NotADirectoryError):  # not there yet (its folders are the writer's concern)
        return path
    except OSError as error:
        raise ValueError(f"{what} {str(path)!r}: {error.strerror}") from None
    if stat.S_ISLNK(status.st_mode):
        raise ValueError(f"{what} {str(path)!r} is a symbolic link; give the file itself (shapefmu replaces it whole "
                         f"and never writes through a link)")
    if not stat.S_ISREG(status.st_mode):
        kind = ("a folder" if stat.S_ISDIR(status.st_mode) else "a FIFO" if stat.S_ISFIFO(status.st_mode)
                else "a device or socket")
        raise ValueError(f"{what} {str(path)!r} is {kind}, not a regular file")
    if not named:
        raise ValueError(f"{what} {str(path)!r} exists, and it is not a file you named: shapefmu replaces only those; "
                         f"remove it or choose another output name")
    return path


def write_file(path, write, what: str = "output file", named: bool = True) -> Path:
    """Write ``path`` whole through ``write(temporary_path)`` (see the module docstring)."""
    path = check_output(path, what, named)
    path.parent.mkdir(parents=True, exist_ok=True)
    # mkstemp creates the file exclusively (O_EXCL): a link planted under its name is refused, not followed.
    descriptor, temporary = tempfile.mkstemp(prefix=f".{path.name[:200]}.", suffix=".tmp", dir=path.parent)
    os.close(descriptor)
    try:
        write(Path(temporary))
        os.chmod(temporary, 0o666 & ~_umask())
        os.replace(temporary, path)  # renames over a link planted at path meanwhile: never writes through it
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)
        raise
    return path


def write_text(path, text: str, what: str = "output file", named: bool = True, encoding: str = "utf-8") -> Path:
    return write_file(path, lambda temporary: temporary.write_text(text, encoding=encoding), what, named)


def write_bytes(path, data: bytes, what: str = "output file", named: bool = True) -> Path:
    return write_file(path, lambda temporary: temporary.write_bytes(data), what, named)


def save_figure(figure, path, what: str = "plot", **options) -> Path:
    """A matplotlib ``figure`` saved to ``path`` whole, in the format its suffix names."""
    suffix = Path(path).suffix.lstrip(".").lower()
    return write_file(path, lambda temporary: figure.savefig(temporary, format=suffix or None, **options), what)


def append_to(path, what: str = "journal"):
    """``path`` opened to append text (a journal written row by row, which a kill must not lose): the
    one file not written whole. Checked, created if absent, never opened through a link (O_NOFOLLOW)."""
    path = check_output(path, what)
    path.parent.mkdir(parents=True, exist_ok=True)
    descriptor = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NOFOLLOW, 0o666)
    return os.fdopen(descriptor, "a", newline="")


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
