"""Output files of a sweep: one row per run, as CSV (appended and flushed as rows arrive) or
Parquet (rows journaled to ``<out>.partial.csv`` and converted when the sweep ends, since a Parquet
file is only readable once its footer is written). Both can be resumed after an interruption.
"""

from __future__ import annotations

import csv
import io
import os
from pathlib import Path

import numpy as np

from shapefmu.files import append_to, check_output, write_file
from shapefmu.runtime.checks import read_text_file

STATUSES = ("ok", "error", "timeout", "non-finite")
FIXED_COLUMNS = ("run", "status", "error", "wall_time")


def columns(names, metric_names) -> list[str]:
    """The columns of a sweep varying ``names`` and measuring ``metric_names``."""
    result = ["run", *names, *metric_names, "status", "error", "wall_time"]
    if len(set(result)) != len(result):
        raise ValueError(f"metric names {list(metric_names)} must differ from the parameters {list(names)} and from "
                         f"{list(FIXED_COLUMNS)}")
    return result




def _parse_row(raw: dict, columns: list[str]) -> dict | None:
    """A CSV row with its types back, or None for a row cut short by an interruption."""
    try:
        row = {c: raw[c] for c in columns}
        if any(v is None for v in row.values()) or row["status"] not in STATUSES:
            return None
        row["run"] = int(row["run"])
        for c in columns:
            if c not in ("run", "status", "error"):
                row[c] = float(row[c])
        return row
    except (KeyError, ValueError):
        return None


class Store:
    """A sweep's rows on disk (see the module docstring).

    Nothing is written until :meth:`open`, and the constructor reads only: with ``resume`` the rows
    already there are read into ``done`` in file order, after checking that the file is this
    sweep's (a file of other columns, or not a sweep file at all, is refused and left as it is); an
    empty file, or one cut inside its header by a kill, starts anew. ``open()`` then drops a last
    line cut short by an interruption (without ``resume``: removes the old file) and appends;
    ``close(rows)`` writes the file from all the sweep's rows, one per point. The caller holds the
    file's lock (``shapefmu.cosim.output_files.output_lock``) from before the constructor to the end."""

    def __init__(self, out, columns: list[str], resume: bool):
        self.out = check_output(out, "sweep output")
        if self.out.suffix not in (".csv", ".parquet"):
            raise ValueError(f"out must end in .csv or .parquet, got {str(self.out)!r}")
        self.columns = columns
        self.resume = resume
        self.parquet = self.out.suffix == ".parquet"
        self.journal = check_output(self.out.with_name(self.out.name + ".partial.csv"), "sweep journal") \
            if self.parquet else self.out
        self.done = []
        self._complete_bytes = None  # where a resumed journal's last complete line ends
        self.file = None
        if resume:
            if self.parquet and self.out.exists():
                self.done += self._read_parquet()
            if self.journal.exists():
                self.done += self._read_csv(self.journal)

    def open(self) -> None:
        """Start writing: the first (and only) change to the files (see the class docstring)."""
        self.out.parent.mkdir(parents=True, exist_ok=True)
        if not self.resume:
            for path in {self.out, self.journal}:
                path.unlink(missing_ok=True)
        self.file = append_to(self.journal, "sweep journal")
        if self.resume and self._complete_bytes is not None:
            self.file.truncate(self._complete_bytes)  # a sweep killed mid-write left a partial line
        new = os.fstat(self.file.fileno()).st_size == 0
        self.writer = csv.DictWriter(self.file, fieldnames=self.columns)
        if new:
            self.writer.writeheader()
            self.file.flush()

    def _check_columns(self, found, path):
        if list(found) != self.columns:
            raise ValueError(f"cannot resume from {str(path)!r}: its columns {list(found)} differ from this sweep's "
                             f"{self.columns}; choose another out= or pass resume=False to overwrite it")

    def _read_csv(self, path) -> list[dict]:
        text = read_text_file(path, "sweep file")
        complete = text[: text.rfind("\n") + 1]
        if len(complete) != len(text):
            self._complete_bytes = len(complete.encode())
        header = ",".join(self.columns)
        if not complete:  # empty, or one line without its end: a header cut by a kill, or not a sweep file
            if not header.startswith(text):
                raise ValueError(f"cannot resume from {str(path)!r}: it is not a sweep file (its only line is "
                                 f"{text[:60]!r}); choose another out=, or pass resume=False to overwrite it")
            return []
        reader = csv.DictReader(io.StringIO(complete))
        try:
            self._check_columns(reader.fieldnames or [], path)
            return [row for row in (_parse_row(raw, self.columns) for raw in reader) if row is not None]
        except csv.Error as error:
            # line_num counts the lines read whole: the error is in the next one
            raise ValueError(f"{path}, line {reader.line_num + 1}: not a sweep row ({error})") from None

    def _read_parquet(self) -> list[dict]:
        pa = pyarrow_module()
        try:
            table = pa.parquet.read_table(self.out)
        except (pa.ArrowException, OSError) as error:
            raise ValueError(f"cannot resume from {str(self.out)!r}: it is not a Parquet file of sweep rows ({error}); "
                             f"choose another out=, or pass resume=False to overwrite it") from None
        self._check_columns(table.column_names, self.out)
        return table.to_pylist()

    def append(self, rows: list[dict]):
        if self.file is None:
            self.open()
        self.writer.writerows(map(_text, rows))
        self.file.flush()

    def close(self, rows: list[dict]):
        """Write the file anew from ``rows``, one per point: a run retried after a failure was
        appended after its old row, and the file keeps only the new one."""
        if self.file is None:
            self.open()
        self.file.close()

        def write_csv(temporary: Path) -> None:
            with open(temporary, "w", newline="") as file:
                writer = csv.DictWriter(file, fieldnames=self.columns)
                writer.writeheader()
                writer.writerows(map(_text, rows))

        def write_parquet(temporary: Path) -> None:
            pa = pyarrow_module()
            pa.parquet.write_table(pa.Table.from_pylist(rows, schema=_arrow_schema(pa, self.columns)), temporary)

        write_file(self.out, write_parquet if self.parquet else write_csv, "sweep output")
        if self.parquet:
            self.journal.unlink()


def _text(row: dict) -> dict:
    # repr: floats read back bit for bit, which matching resumed points relies on.
    return {c: repr(float(v)) if isinstance(v, float) else v for c, v in row.items()}


def pyarrow_module():
    """pyarrow with its parquet module, or a ValueError saying how to get it."""
    try:
        import pyarrow
        import pyarrow.parquet  # noqa: F401  (binds pyarrow.parquet)
    except ImportError:
        raise ValueError("out=*.parquet needs pyarrow (pip install 'shapefmu[dask]'); or use out=*.csv") from None
    return pyarrow


def _arrow_schema(pa, columns):
    types = {"run": pa.int64(), "status": pa.string(), "error": pa.string()}
    return pa.schema([(c, types.get(c, pa.float64())) for c in columns])


def read_rows(path) -> np.ndarray:
    """The rows of a sweep's output file (.csv or .parquet) as a structured array, by run index
    (a CSV holds them in the order they finished)."""
    path = Path(path)
    if path.suffix == ".parquet":
        table = pyarrow_module().parquet.read_table(path)
        rows, columns = table.to_pylist(), table.column_names
    else:
        with open(path, newline="") as file:
            reader = csv.DictReader(file)
            columns = list(reader.fieldnames or [])
            rows = [r for r in (_parse_row(raw, columns) for raw in reader) if r is not None]
    return np.sort(as_array(rows, columns), order="run", kind="stable")


def as_array(rows: list[dict], columns: list[str]) -> np.ndarray:
    """Rows (dicts) as a structured array: ``run`` int, ``status`` and ``error`` text, the rest float."""
    def dtype(c):
        if c == "run":
            return np.int64
        if c in ("status", "error"):
            return f"U{max([1] + [len(r[c]) for r in rows])}"
        return np.float64

    return np.array([tuple(r[c] for c in columns) for r in rows], dtype=[(c, dtype(c)) for c in columns])


def metric_names_in_file(out, names) -> list[str]:
    """The metric columns of an existing output file (or its Parquet journal), [] if none."""
    out = Path(out)
    journal = out.with_name(out.name + ".partial.csv")
    if out.suffix == ".parquet" and out.exists():
        found = pyarrow_module().parquet.read_schema(out).names
    elif (journal if out.suffix == ".parquet" else out).exists():
        with open(journal if out.suffix == ".parquet" else out, newline="") as file:
            header = file.readline()
        if not header.endswith("\n"):  # empty, or cut inside the header by a kill: it names nothing
            return []
        found = next(csv.reader([header]), [])
    else:
        return []
    return [c for c in found if c not in FIXED_COLUMNS and c not in names]
