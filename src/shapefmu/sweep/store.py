"""Output files of a sweep: one row per run, as CSV (appended and flushed as rows arrive) or
Parquet (rows journaled to ``<out>.partial.csv`` and converted when the sweep ends, since a Parquet
file is only readable once its footer is written). Both can be resumed after an interruption.
"""

from __future__ import annotations

import csv
import os
from pathlib import Path

import numpy as np

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
    """A sweep's rows on disk (see the module docstring). With ``resume`` the rows already there
    are read into ``done`` in file order (a partial last line is dropped; an empty file or one cut
    inside its header starts anew); otherwise the file is started anew. ``close(rows)`` writes the
    file from all the sweep's rows, one per point."""

    def __init__(self, out, columns: list[str], resume: bool):
        self.out = Path(out)
        if self.out.suffix not in (".csv", ".parquet"):
            raise ValueError(f"out must end in .csv or .parquet, got {str(self.out)!r}")
        self.columns = columns
        self.parquet = self.out.suffix == ".parquet"
        self.journal = self.out.with_name(self.out.name + ".partial.csv") if self.parquet else self.out
        self.out.parent.mkdir(parents=True, exist_ok=True)
        self.done = []
        if resume:
            if self.parquet and self.out.exists():
                self.done += self._read_parquet()
            if self.journal.exists():
                self.done += self._read_csv(self.journal)
        else:
            for path in {self.out, self.journal}:
                path.unlink(missing_ok=True)
        # A file cut inside its header (killed while starting) is empty after _read_csv: it gets one.
        new = not self.journal.exists() or self.journal.stat().st_size == 0
        self.file = open(self.journal, "a", newline="")
        self.writer = csv.DictWriter(self.file, fieldnames=columns)
        if new:
            self.writer.writeheader()
            self.file.flush()

    def _check_columns(self, found, path):
        if list(found) != self.columns:
            raise ValueError(f"cannot resume from {str(path)!r}: its columns {list(found)} differ from this sweep's "
                             f"{self.columns}; choose another out= or pass resume=False to overwrite it")

    def _read_csv(self, path) -> list[dict]:
        # A sweep killed mid-write may leave a partial last line: drop it before appending.
        text = path.read_text()
        if text and not text.endswith("\n"):
            text = text[: text.rfind("\n") + 1]
            path.write_text(text)
        reader = csv.DictReader(text.splitlines())
        if reader.fieldnames is None:
            return []
        self._check_columns(reader.fieldnames, path)
        return [row for row in (_parse_row(raw, self.columns) for raw in reader) if row is not None]

    def _read_parquet(self) -> list[dict]:
        table = pyarrow_module().parquet.read_table(self.out)
        self._check_columns(table.column_names, self.out)
        return table.to_pylist()

    def append(self, rows: list[dict]):
        self.writer.writerows(map(_text, rows))
        self.file.flush()

    def close(self, rows: list[dict]):
        """Write the file anew from ``rows``, one per point: a run retried after a failure was
        appended after its old row, and the file keeps only the new one."""
        self.file.close()
        if not self.parquet:
            temporary = self.out.with_name(self.out.name + ".tmp")
            with open(temporary, "w", newline="") as file:
                writer = csv.DictWriter(file, fieldnames=self.columns)
                writer.writeheader()
                writer.writerows(map(_text, rows))
            os.replace(temporary, self.out)
        if self.parquet:
            pa = pyarrow_module()
            table = pa.Table.from_pylist(rows, schema=_arrow_schema(pa, self.columns))
            temporary = self.out.with_name(self.out.name + ".tmp")
            pa.parquet.write_table(table, temporary)
            os.replace(temporary, self.out)
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
