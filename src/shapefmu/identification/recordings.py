"""Recordings of a machine, read from the files the tools of the field write.

Each format is recognised from its content (the first line, or Parquet's magic bytes), never from
the file name:

- Klipper raw accelerometer data (``ACCELEROMETER_MEASURE`` / ``TEST_RESONANCES ... OUTPUT=raw_data``):
  header ``#time,accel_x,accel_y,accel_z``, rows of four numbers, time in s (absolute print time,
  slightly irregular), acceleration in mm/s^2;
- Klipper processed spectra (``calibrate_shaper.py --csv``): header ``freq,psd_x,psd_y,psd_z,psd_xyz``
  optionally followed by one column per fitted shaper, or ``freq`` followed by one column per
  combined data set; read as a ``Spectrum`` (``spectra``), not as samples;
- RepRapFirmware ``M956`` recordings: header ``Sample,X,Y,Z`` (only the recorded axes), values in g,
  no time column, and a last line ``Rate <Hz>, overflows <n>``;
- any CSV (with a header line) or Parquet table, given ``time_column`` or ``fs`` and ``column``.

Samples on an irregular time base are interpolated onto the uniform grid of their mean rate before
any spectrum is taken (Klipper's timestamps jitter by a few percent); the jitter, the gaps (intervals
longer than twice the mean) and the clipped samples (runs at the channel's extreme value, a saturated
sensor) are counted and reported, so a user can judge the recording.

Files are bounded before they are parsed: at most ``MAX_RECORDING_BYTES``, at most
``MAX_RECORDING_VALUES`` numbers (rows times columns, counted from the lines or from a Parquet file's
metadata: a small compressed file can hold millions of rows), at most ``MAX_COLUMNS`` columns asked
for; every number read has a magnitude of at most ``MAX_MAGNITUDE`` (so that no square or sum in a
spectrum overflows) and rates are at most ``MAX_RATE``. Every error names the file, the line and
what was expected. A UTF-8 byte-order mark at the start is skipped.
"""

from __future__ import annotations

import io
import math
import os
import re
import stat
from dataclasses import dataclass, field

import numpy as np

G = 9806.65  # mm/s^2 per g: RepRapFirmware records in g, Klipper in mm/s^2
AXES = ("x", "y", "z")
# Read, decoded and parsed, a CSV costs about three times its size; 64 MB keeps a read under 500 MB
# and holds 30 minutes of three axes at 3.2 kHz (a resonance test takes one or two).
MAX_RECORDING_BYTES = 64 * 2**20
MAX_RECORDING_VALUES = 2**24  # 128 MB of float64: 20 minutes of time and three axes at 3.2 kHz
MAX_COLUMNS = 16
MAX_MAGNITUDE = 1e100  # squared and summed over a segment, still far from overflow
MAX_RATE = 1e6  # Hz: above any accelerometer's rate
MAX_OVERFLOWS = 10**12
BOM = b"\xef\xbb\xbf"
NEWLINE = b"\n"
# A number as NumPy's CSV reader takes it (Python's float() would also take '1_234', which it refuses)
_NUMBER = re.compile(r"^\s*[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|nan|inf|infinity)\s*$", re.IGNORECASE)
KLIPPER_RAW = "klipper-raw"
KLIPPER_SPECTRUM = "klipper-spectrum"
RRF_M956 = "rrf-m956"
TABLE = "table"
_RRF_RATE = re.compile(r"^\s*rate\s*[:=]?\s*(\S*?)\s*(?:hz)?\s*,?\s*overflows\s*[:=]?\s*(\S*)\s*$", re.IGNORECASE)


@dataclass(frozen=True)
class Recording:
    """Samples of one or more channels on a uniform grid at ``fs`` Hz.

    ``channels`` maps an axis name (``x``, ``y``, ``z`` or a column name) to its samples, in
    ``unit``. ``jitter`` is the standard deviation of the sampling interval over its mean (0 for a
    file without a time column), ``gaps`` the intervals longer than twice the mean, ``clipped``
    the samples at a channel's extreme value in runs of two or more, ``overflows`` what the
    recorder reported as lost (RepRapFirmware).
    """

    source: str
    format: str
    fs: float
    channels: dict[str, np.ndarray] = field(repr=False)
    unit: str
    jitter: float = 0.0
    gaps: int = 0
    clipped: int = 0
    overflows: int = 0

    @property
    def duration(self) -> float:
        return len(next(iter(self.channels.values()))) / self.fs

    def describe(self) -> str:
        """One line: what was read, at what rate, and what is wrong with it."""
        n = len(next(iter(self.channels.values())))
        return (f"{self.source}: {self.format}, {', '.join(self.channels)} in {self.unit}, {n} samples at "
                f"{self.fs:.1f} Hz ({self.duration:.2f} s), jitter {100 * self.jitter:.2f} %, {self.gaps} gap(s), "
                f"{self.clipped} clipped sample(s)" + (f", {self.overflows} overflow(s)" if self.overflows else ""))


def read_bytes(path) -> bytes:
    """The content of a recording: refused in one line if it is not a regular file or is larger than
    ``MAX_RECORDING_BYTES``.

    >>> read_bytes("/")
    Traceback (most recent call last):
    ...
    ValueError: /: a recording must be a regular file, not a folder
    """
    name = os.fspath(path)
    try:  # without blocking: a FIFO with no writer would wait in open() forever
        with open(os.open(name, os.O_RDONLY | os.O_NONBLOCK), "rb") as stream:
            status = os.fstat(stream.fileno())
            if not stat.S_ISREG(status.st_mode):
                raise ValueError(f"{name}: a recording must be a regular file, not a FIFO, device or folder")
            if status.st_size > MAX_RECORDING_BYTES:
                raise ValueError(f"{name}: the recording has {status.st_size} bytes, more than the "
                                 f"{MAX_RECORDING_BYTES} (shapefmu.identification.recordings.MAX_RECORDING_BYTES) "
                                 f"read at once; cut it into shorter recordings")
            return stream.read(MAX_RECORDING_BYTES + 1)
    except FileNotFoundError:
        raise ValueError(f"{name}: no such file") from None
    except IsADirectoryError:
        raise ValueError(f"{name}: a recording must be a regular file, not a folder") from None


def detect(data: bytes) -> str:
    """The format of a recording's content (see the module docstring), or ``TABLE``.

    >>> detect(b"#time,accel_x,accel_y,accel_z\\n"), detect(b"Sample,X,Y\\n"), detect(b"t,a\\n")
    ('klipper-raw', 'rrf-m956', 'table')
    """
    if data[:4] == b"PAR1":
        return TABLE
    first = data.split(b"\n", 1)[0].strip().lower().replace(b" ", b"")
    if first.startswith(b"#time,accel_"):
        return KLIPPER_RAW
    if first.startswith(b"freq,"):
        return KLIPPER_SPECTRUM
    if first.startswith(b"sample,") and all(c in (b"x", b"y", b"z") for c in first.split(b",")[1:]) and first.count(b",") >= 1:
        return RRF_M956
    return TABLE


def _text(data: bytes, name: str) -> str:
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as error:
        line = data[: error.start].count(b"\n") + 1
        raise ValueError(f"{name}: line {line}: expected UTF-8 text, got the byte 0x{data[error.start]:02x}") from None


def parse_table(data: bytes, name: str, *, first_line: int = 1) -> tuple[list[str], np.ndarray]:
    r"""(column names, rows x columns float array) of a CSV with one header line. Blank lines and
    lines starting with ``#`` after the header are skipped. Every row must hold as many numbers as
    the header has names, each of magnitude at most ``MAX_MAGNITUDE``; the first one that does not is
    named by its line. The rows are counted before they are parsed (at most ``MAX_RECORDING_VALUES``
    numbers), then parsed by NumPy straight from the bytes (no decoded copy, no list of lines).

    >>> parse_table(b"t,a\n0,1.5\n# a comment\n0.1,-2\n", "f.csv")
    (['t', 'a'], array([[ 0. ,  1.5],
           [ 0.1, -2. ]]))
    """
    header_bytes, _, body = data.partition(b"\n")
    header = _text(header_bytes, name)
    if not header.strip():
        raise ValueError(f"{name}: line {first_line}: expected a header line of column names, got an empty file")
    names = [c.strip() for c in header.split(",")]
    if any(not c for c in names):
        raise ValueError(f"{name}: line {first_line}: expected column names separated by commas, got {header[:80]!r}")
    rows = body.count(b"\n") + 1
    if rows * len(names) > MAX_RECORDING_VALUES:
        raise ValueError(f"{name}: up to {rows} rows of {len(names)} columns are more than the {MAX_RECORDING_VALUES} "
                         f"numbers (shapefmu.identification.recordings.MAX_RECORDING_VALUES) read at once; cut the "
                         f"recording into shorter ones")
    if not any(line.strip() and not line.lstrip().startswith(b"#") for line in io.BytesIO(body)):
        raise ValueError(f"{name}: line {first_line + 1}: expected rows of numbers after the header, got none")
    try:
        values = np.loadtxt(io.BytesIO(body), delimiter=",", dtype=float, ndmin=2, comments="#", encoding=None)
    except (ValueError, UnicodeDecodeError):
        values = None
    if values is None or values.shape[1] != len(names):
        _name_the_bad_line(body, names, name, first_line)
    bad = np.flatnonzero(~np.all(np.abs(values) <= MAX_MAGNITUDE, axis=1))
    if bad.size:
        _name_the_bad_line(body, names, name, first_line, row=int(bad[0]))
    return names, values


def _name_the_bad_line(body: bytes, names, name: str, first_line: int, row: int | None = None):
    """Raise the one-line error for the first malformed row (or data row ``row``, not finite or too
    large)."""
    data_row = -1
    expected = f"expected {len(names)} numbers ({', '.join(names)[:80]})"
    for number, raw in enumerate(io.BytesIO(body), start=first_line + 1):
        line = raw.decode("utf-8", "replace")
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        data_row += 1
        fields = line.rstrip("\r\n").split(",")
        if not all(_NUMBER.match(f) for f in fields):
            raise ValueError(f"{name}: line {number}: {expected}, got {line.strip()[:80]!r}")
        if len(fields) != len(names):
            raise ValueError(f"{name}: line {number}: {expected}, got {len(fields)}")
        if data_row == row:
            raise ValueError(f"{name}: line {number}: expected finite numbers of magnitude at most {MAX_MAGNITUDE:g}, "
                             f"got {line.strip()[:80]!r} (no spectrum can be taken of it)")
    raise ValueError(f"{name}: {expected} on every line after the header")


def _uniform(time: np.ndarray, columns: np.ndarray, name: str, line_of) -> tuple[float, np.ndarray, float, int]:
    """(rate, columns on the uniform grid, jitter, gaps) of samples taken at ``time``."""
    if time.size < 16:
        raise ValueError(f"{name}: expected at least 16 samples for a spectrum, got {time.size}")
    dt = np.diff(time)
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        raise ValueError(f"{name}: line {line_of(bad[0] + 1)}: expected the time to increase, got "
                         f"{time[bad[0] + 1]!r} after {time[bad[0]]!r}")
    mean = (time[-1] - time[0]) / (time.size - 1)
    if mean * MAX_RATE < 1:  # not 1 / mean: a denormal step's rate is infinite
        raise ValueError(f"{name}: the time column steps by {mean:g} s on average, a rate above {MAX_RATE:g} Hz; "
                         f"expected steps of at least {1 / MAX_RATE:g} s")
    jitter = float(np.std(dt) / mean)
    gaps = int(np.count_nonzero(dt > 2.0 * mean))
    if jitter < 1e-9:
        return 1.0 / mean, columns, jitter, gaps
    grid = time[0] + mean * np.arange(time.size)
    grid[-1] = min(grid[-1], time[-1])
    return 1.0 / mean, np.column_stack([np.interp(grid, time, c) for c in columns.T]), jitter, gaps


def _clipped(samples: np.ndarray) -> int:
    """Samples at the channel's extreme value in runs of two or more: a saturated sensor."""
    count = 0
    for extreme in (samples.max(), samples.min()):
        at = samples == extreme
        runs = at[1:] & at[:-1]
        if runs.any():
            count += int(np.count_nonzero(at & (np.r_[runs, False] | np.r_[False, runs])))
    return count


def _channels(names, columns, axis_names) -> dict[str, np.ndarray]:
    return {axis: np.ascontiguousarray(columns[:, i]) for i, axis in enumerate(axis_names)}


def read_recording(path, *, time_column: str | None = None, fs: float | None = None,
                   columns: list[str] | None = None):
    r"""The ``Recording`` (or, for a Klipper processed-spectrum file, the ``Spectrum`` of each axis
    by name) in ``path``.

    ``time_column`` or ``fs`` (Hz) and ``columns`` describe a generic CSV or Parquet table; they are
    refused for the formats that carry their own (the file's content says which it is).

    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "m956.csv"
    >>> rows = "".join(f"{i},{0.01 * (i % 7)}\n" for i in range(32))
    >>> _ = path.write_text("\ufeffSample,X\n" + rows + "Rate 1000, overflows 0\n")
    >>> read_recording(path).describe().split(": ", 1)[1]
    'rrf-m956, x in mm/s^2, 32 samples at 1000.0 Hz (0.03 s), jitter 0.00 %, 0 gap(s), 0 clipped sample(s)'
    """
    name = os.fspath(path)
    data = read_bytes(path)
    if data.startswith(BOM):
        data = data[len(BOM):]
    if not data.strip():
        raise ValueError(f"{name}: line 1: expected a recording, got an empty file")
    kind = detect(data)
    if data[:4] != b"PAR1" and b"\x00" in data[:65536]:
        raise ValueError(f"{name}: line 1: expected a text (CSV) recording or a Parquet file, got binary data")
    if kind != TABLE and (time_column or fs or columns):
        raise ValueError(f"{name}: a {kind} file carries its own time base and columns; --time, --fs and --column "
                         f"are for other CSV or Parquet tables")
    if kind == KLIPPER_SPECTRUM:
        from shapefmu.identification.spectra import klipper_spectrum

        return klipper_spectrum(*parse_table(_without_shaper_marker(data), name), source=name)
    if kind == KLIPPER_RAW:
        names, values = parse_table(data, name)
        axes = [n.lower().removeprefix("accel_") for n in names[1:]]
        if names[0].lower() != "#time" or sorted(axes) != sorted(set(axes)) or not set(axes) <= set(AXES) or not axes:
            raise ValueError(f"{name}: line 1: expected '#time,accel_x,accel_y,accel_z', got {','.join(names)!r}")
        rate, uniform, jitter, gaps = _uniform(values[:, 0], values[:, 1:], name, lambda i: i + 2)
        return _recording(name, kind, rate, _channels(names, uniform, axes), "mm/s^2", jitter, gaps)
    if kind == RRF_M956:
        return _read_rrf(data, name)
    return _read_table(data, name, time_column, fs, columns)


def _without_shaper_marker(data: bytes) -> bytes:
    """A Klipper spectrum file without the empty ``shapers:`` column that newer Klipper writes between
    the spectra and the shapers' responses (``freq,psd_x,...,psd_xyz,shapers:,zv(59.0),...``, rows
    ``10.0,...,1.2e+03,,0.981,...``)."""
    header, _, body = data.partition(b"\n")
    columns = header.split(b",")
    if b"shapers:" not in [c.strip() for c in columns]:
        return data
    at = [c.strip() for c in columns].index(b"shapers:")
    rows = [b",".join(line.split(b",")[:at] + line.split(b",")[at + 1:]) if line.strip() else line
            for line in body.split(b"\n")]
    return b",".join(columns[:at] + columns[at + 1:]) + b"\n" + b"\n".join(rows)


def _recording(name, kind, rate, channels, unit, jitter=0.0, gaps=0, overflows=0) -> Recording:
    clipped = sum(_clipped(c) for c in channels.values())
    return Recording(name, kind, float(rate), channels, unit, jitter, gaps, clipped, overflows)


def _read_rrf(data: bytes, name: str) -> Recording:
    body, _, last = data.rstrip().rpartition(b"\n")
    last_line = last.decode("utf-8", "replace")
    line = f"{name}: line {body.count(NEWLINE) + 2}"
    match = _RRF_RATE.match(last_line)
    if match is None:
        raise ValueError(f"{line}: expected the last line of an M956 recording, 'Rate <Hz>, overflows <n>', "
                         f"got {last_line[:80]!r}")
    rate_text, overflow_text = match.group(1), match.group(2)
    rate = float(rate_text) if _NUMBER.match(rate_text) else math.nan
    if not 0 < rate <= MAX_RATE:
        raise ValueError(f"{line}: expected the M956 'Rate' in (0, {MAX_RATE:g}] Hz, got {rate_text[:20]!r}")
    if not (overflow_text.isdigit() and len(overflow_text) <= 13 and int(overflow_text) <= MAX_OVERFLOWS):
        shown = overflow_text[:20] + (f"... ({len(overflow_text)} characters)" if len(overflow_text) > 20 else "")
        raise ValueError(f"{line}: expected the overflow count as a whole number in [0, {MAX_OVERFLOWS}], got {shown!r}")
    names, values = parse_table(body, name)
    axes = [n.lower() for n in names[1:]]
    if len(set(axes)) != len(axes):
        raise ValueError(f"{name}: line 1: an axis is named twice in {','.join(names)!r}")
    if values.shape[0] < 16:
        raise ValueError(f"{name}: expected at least 16 samples for a spectrum, got {values.shape[0]}")
    return _recording(name, RRF_M956, rate, _channels(names, values[:, 1:] * G, axes), "mm/s^2",
                      overflows=int(overflow_text))


def _read_table(data: bytes, name: str, time_column, fs, columns) -> Recording:
    if not columns:
        first = data.split(b"\n", 1)[0][:60].decode("utf-8", "replace")
        raise ValueError(f"{name}: not a Klipper or RepRapFirmware recording (line 1: {first!r}); for any other CSV or "
                         f"Parquet table give --column NAME and --time COLUMN or --fs HZ")
    if len(columns) > MAX_COLUMNS:
        raise ValueError(f"--column: at most {MAX_COLUMNS} columns are read, got {len(columns)}")
    twice = sorted({c for c in columns if columns.count(c) > 1})
    if twice:
        raise ValueError(f"--column {twice[0]!r} is given {columns.count(twice[0])} times; give each column once")
    if (time_column is None) == (fs is None):
        raise ValueError(f"{name}: give exactly one of --time COLUMN and --fs HZ for the samples' time base")
    if fs is not None and not 0 < fs <= MAX_RATE:
        raise ValueError(f"--fs must be a rate in (0, {MAX_RATE:g}] Hz, got {fs!r}")
    wanted = [*columns, *([time_column] if time_column else [])]
    if data[:4] == b"PAR1":
        names, values = _parquet(data, name, wanted)
        line_of = lambda i: f"row {i + 1} of"  # noqa: E731 -- Parquet has rows, not lines
    else:
        names, values = parse_table(data, name)
        line_of = lambda i: i + 2  # noqa: E731
    index = {n: i for i, n in enumerate(names)}
    for column in wanted:
        if column not in index:
            raise ValueError(f"{name}: no column {column!r}; the columns are {', '.join(names)[:200]}")
    picked = values[:, [index[c] for c in columns]]
    if time_column is not None:
        rate, uniform, jitter, gaps = _uniform(values[:, index[time_column]], picked, name, line_of)
    else:
        rate, uniform, jitter, gaps = fs, picked, 0.0, 0
        if picked.shape[0] < 16:
            raise ValueError(f"{name}: expected at least 16 samples for a spectrum, got {picked.shape[0]}")
    return _recording(name, TABLE, rate, _channels(names, uniform, columns), "as recorded", jitter, gaps)


def _parquet(data: bytes, name: str, wanted: list[str]) -> tuple[list[str], np.ndarray]:
    """(names, values) of the numeric columns of a Parquet file among ``wanted``, bounded by its
    metadata (rows times columns) before any is read."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        parquet = pq.ParquetFile(pa.BufferReader(data))
        available = parquet.schema_arrow.names
        for column in wanted:
            if column not in available:
                raise ValueError(f"{name}: no column {column!r}; the columns are {', '.join(available)[:200]}")
        present = list(dict.fromkeys(wanted))
        rows = parquet.metadata.num_rows
        if rows * len(present) > MAX_RECORDING_VALUES:
            raise ValueError(f"{name}: {rows} rows of {len(present)} column(s) are more than the {MAX_RECORDING_VALUES} "
                             f"numbers (shapefmu.identification.recordings.MAX_RECORDING_VALUES) read at once; cut "
                             f"the recording into shorter ones")
        table = parquet.read(columns=present)
    except (pa.ArrowException, OSError) as error:
        raise ValueError(f"{name}: not a readable Parquet file ({str(error)[:120]})") from None
    names, arrays = [], []
    for column in table.column_names:
        try:
            arrays.append(table[column].to_numpy().astype(float))
            names.append(column)
        except (TypeError, ValueError, pa.ArrowException):
            continue  # a text column: not a signal
    if len(arrays) < len(present):
        text = sorted(set(present) - set(names))[0]
        raise ValueError(f"{name}: column {text!r} holds no numbers")
    values = np.column_stack(arrays)
    bad = np.flatnonzero(~np.all(np.abs(values) <= MAX_MAGNITUDE, axis=1))
    if bad.size:
        raise ValueError(f"{name}: row {bad[0] + 1}: expected finite numbers of magnitude at most {MAX_MAGNITUDE:g} "
                         f"in every column read")
    return names, values
