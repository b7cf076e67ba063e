"""Files that runs write their results to: one writer at a time, whole or marked partial, never a trap.

* ``check_output(path, what)``: refused before any work, with a one-line message, when the path is a
  link, a folder, a FIFO or a device (a FIFO with no reader would block the write forever), or a
  name the file system cannot hold (more than 255 bytes in one part).
* ``output_lock(path)``: an exclusive lock on the file for the lifetime of a run (``fcntl.flock`` on
  a hidden ``.<name>.lock`` beside it): a second run writing the same file is refused at once,
  naming the process that holds it, instead of the two mixing or dropping each other's rows.
* ``replace_atomically(path, write)``: ``write(temporary)`` into a uniquely named file beside
  ``path``, then renamed over it: a reader, or a run killed mid-write, sees the old file or the new
  one, never half of one.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import stat
import tempfile
from pathlib import Path

NAME_MAX = 255  # bytes of one path component on Linux file systems (ext4, xfs, btrfs, tmpfs)


def check_output(path, what: str = "output file") -> Path:
    """``path`` as a file a run may write: refused (ValueError) if it is a link, a folder, a FIFO, a
    device or socket, or if one of its names is longer than the file system allows."""
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
        raise ValueError(f"{what} {str(path)!r} is a symbolic link; give the file itself (the run replaces it whole)")
    if not stat.S_ISREG(status.st_mode):
        kind = ("a folder" if stat.S_ISDIR(status.st_mode) else "a FIFO" if stat.S_ISFIFO(status.st_mode)
                else "a device or socket")
        raise ValueError(f"{what} {str(path)!r} is {kind}, not a regular file")
    return path


@contextlib.contextmanager
def output_lock(path):
    """Hold the writer's lock of ``path`` (see the module docstring); ValueError if another process does."""
    path = Path(path)
    lock_path = path.with_name(f".{path.name}.lock")
    path.parent.mkdir(parents=True, exist_ok=True)
    while True:
        handle = open(lock_path, "a+")
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as error:
            handle.seek(0)
            holder = handle.read().strip() or "another process"
            handle.close()
            if error.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise ValueError(f"{path} is being written by another run ({holder}); wait for it to end or "
                                 f"choose another output file") from None
            raise
        # The lock file may have been removed by the run that held it just before we locked: then
        # our lock is on a file no one else will find. Lock the file that is there instead.
        try:
            same = os.fstat(handle.fileno()).st_ino == os.stat(lock_path).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        handle.close()
    try:
        handle.seek(0)
        handle.truncate()
        handle.write(f"process {os.getpid()}")
        handle.flush()
        yield path
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(lock_path)
        handle.close()


def replace_atomically(path, write) -> Path:
    """Write ``path`` whole: ``write(temporary_path)`` beside it, then rename over it (see the module docstring)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    descriptor, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(descriptor)
    try:
        write(Path(temporary))
        os.chmod(temporary, 0o666 & ~_umask())
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)
        raise
    return path


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def save_results(results, path, partial: str | None = None) -> Path:
    """Write recorded results to ``.csv`` (header = field names, quoted where a name needs it) or
    ``.parquet`` (needs pyarrow), each column with its type: floats with 17 significant digits,
    integers, booleans (true/false), strings. Written whole (``replace_atomically``). ``partial``, the
    reason a run stopped early, marks the file: a last CSV line ``# partial results: <reason>``, or
    the Parquet metadata key ``shapefmu.partial``."""
    import numpy as np

    path = Path(path)
    names = results.dtype.names
    if path.suffix not in (".csv", ".parquet"):
        raise ValueError(f"results path must end in .csv or .parquet, got {path.name!r}")

    def write_csv(temporary: Path) -> None:
        import csv

        with open(temporary, "w", newline="") as handle:
            csv.writer(handle, lineterminator="\n").writerow(names)  # a name with a comma stays one column
            if all(results.dtype[name] == np.float64 for name in names):  # numpy's writer, fast for long runs
                np.savetxt(handle, results.view((np.float64, len(names))) if len(results) else np.empty((0, len(names))),
                           delimiter=",", fmt="%.17g")
            else:
                writer = csv.writer(handle, lineterminator="\n")
                formats = [_csv_format(results.dtype[name]) for name in names]
                for row in results:
                    writer.writerow([form(value) for form, value in zip(formats, row)])
            if partial is not None:
                handle.write(f"# partial results: {' '.join(partial.split())}\n")

    def write_parquet(temporary: Path) -> None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        columns = {name: pa.array(results[name].tolist(), type=pa.string()) if results.dtype[name].kind == "O"
                   else results[name] for name in names}
        table = pa.table(columns)
        if partial is not None:
            table = table.replace_schema_metadata({"shapefmu.partial": partial})
        pq.write_table(table, temporary)

    return replace_atomically(path, write_csv if path.suffix == ".csv" else write_parquet)


def _csv_format(dtype):
    if dtype.kind == "f":
        return lambda value: f"{value:.17g}"
    if dtype.kind == "b":
        return lambda value: "true" if value else "false"
    return str
