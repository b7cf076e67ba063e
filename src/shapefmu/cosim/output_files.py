"""Files that runs write their results to: one writer at a time, whole or marked partial, never a trap.

Written, as every file of shapefmu, through ``shapefmu.files`` (checked, whole, never through a link).

* ``output_lock(path)``: an exclusive lock on the file for the lifetime of a run (``fcntl.flock`` on
  a hidden ``.<name>.lock`` beside it): a second run writing the same file is refused at once,
  naming the process that holds it, instead of the two mixing or dropping each other's rows.
* ``save_results(results, path, partial)``: recorded results as CSV or Parquet.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
from pathlib import Path

from shapefmu.files import check_output, write_file


@contextlib.contextmanager
def output_lock(path):
    """Hold the writer's lock of ``path`` (see the module docstring); ValueError if another process does."""
    path = Path(path)
    lock_path = path.with_name(f".{path.name}.lock")
    path.parent.mkdir(parents=True, exist_ok=True)
    while True:
        check_output(lock_path, "lock file")
        # O_NOFOLLOW: a link planted under the lock's name is refused, never written through.
        handle = os.fdopen(os.open(lock_path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o600), "r+")
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


def save_results(results, path, partial: str | None = None) -> Path:
    """Write recorded results to ``.csv`` (header = field names, quoted where a name needs it) or
    ``.parquet`` (needs pyarrow), each column with its type: floats with 17 significant digits,
    integers, booleans (true/false), strings. Written whole (``shapefmu.files.write_file``). ``partial``, the
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

    return write_file(path, write_csv if path.suffix == ".csv" else write_parquet, "results file")


def _csv_format(dtype):
    if dtype.kind == "f":
        return lambda value: f"{value:.17g}"
    if dtype.kind == "b":
        return lambda value: "true" if value else "false"
    return str
