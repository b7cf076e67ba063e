"""Play a signal table (time, value) with exact discontinuities, as a ReferencePlayer FMU does.

A table is a list of rows (t_i, y_i) with non-decreasing times, read in one of two ways:

- ``"hold"`` (zero-order hold): y_i holds from t_i until the next row's time. This is how
  ``shapefmu.optimal.TimeOptimalSolution`` exports its bang-bang input (``to_csv``: rows at 0, each
  exact switch instant and T, where the input becomes ``u_final``; ``to_json``: ``switch_times``,
  ``levels``, ``u_final``, ``T``).
- ``"linear"``: straight lines between rows; two rows at the same time make a jump from the first
  row's value to the second's.

Either way the signal is right-continuous: at a switch instant it already has its new value, and
before the first row it is ``before`` (default 0, the rest before a rest-to-rest move, as
``optimal.Command``). After the last row it keeps the last value.

FMI 2.0 co-simulation semantics (FMI 2.0 section 4.2.2: outputs after ``fmi2DoStep(t, h)`` are
the values at t + h). A communication step that straddles a switch therefore returns the value at
its end, t + h, the switch having taken effect inside the step; a step that ends exactly on a
switch returns the new value. ``average(t, t + h)`` is the exact mean over the step, the
zero-order-hold-equivalent input for a consumer that integrates the step with a constant input.

Communication points are usually accumulated (t += h), so a step meant to end on a switch can end
one rounding error before it. Times within ``1e-12`` of the table's time scale from a row's time
are taken to be that time; without this a master stepping exactly onto a switch would see the old
value at the switch and the new one a step late.

Bounds. A table file is data from a user: its numbers must be JSON numbers (``"time": "012"`` is
no list of times, ``true`` no value), and every number derived from them must be a finite double
with room to spare: the widths between rows, the running integral (times of +-1e308 made it inf,
which a native FMU's C cannot even hold) and the integral anywhere inside a row's segment stay
within half the largest double, so that a difference of two of them is finite too. A step's mean
inside one segment is that segment's own (no difference of large integrals), and the parts of a
step before the first row or after the last are weighted by their share of the step, so that any
finite step of a host, however far from the table, has a finite mean.
"""

import bisect
import csv
import io
import json
import math
import sys

from .checks import check_finite, parse_nested, read_text_file

INTERPOLATIONS = ("hold", "linear")
_SNAP = 1e-12
_ROOM = sys.float_info.max / 2  # derived numbers stay below it, so that their differences are finite


class SignalTable:
    """A right-continuous signal from rows (time, value); see the module docstring."""

    def __init__(self, times, values, interpolation="hold", before=0.0):
        if interpolation not in INTERPOLATIONS:
            raise ValueError(f"interpolation must be one of {', '.join(INTERPOLATIONS)}, got {interpolation!r}")
        if len(times) != len(values) or not times:
            raise ValueError(
                f"times and values must be non-empty and of equal length, got {len(times)} and {len(values)}"
            )
        rows = [
            (check_finite(t, f"times[{i}]"), check_finite(y, f"values[{i}]"))
            for i, (t, y) in enumerate(zip(times, values))
        ]
        for i in range(1, len(rows)):
            if rows[i][0] < rows[i - 1][0]:
                raise ValueError(f"times must be non-decreasing, got times[{i}] = {rows[i][0]!r} after {rows[i - 1][0]!r}")
        self.interpolation = interpolation
        self.before = check_finite(before, "before")
        # Distinct times with the value arriving from the left (first row) and leaving (last row);
        # under a hold only the leaving value is used.
        self.times, self._left, self._right = [], [], []
        for t, y in rows:
            if self.times and t == self.times[-1]:
                self._right[-1] = y
            else:
                self.times.append(t)
                self._left.append(y)
                self._right.append(y)
        scale = max(abs(self.times[0]), abs(self.times[-1]), self.times[-1] - self.times[0])
        if not scale < _ROOM:
            raise ValueError(f"the table spans times {self.times[0]!r} to {self.times[-1]!r}: its span must stay below "
                             f"{_ROOM:.3g} s (every derived number a finite double)")
        self.tolerance = _SNAP * scale
        # Integral of the signal from the first time to each time, for exact step averages.
        self._integral = [0.0]
        for j in range(len(self.times) - 1):
            width = self.times[j + 1] - self.times[j]
            # The integral anywhere in the segment lies within the larger value times its width of the
            # integral at its start (hold, or a line between its ends).
            reach = abs(self._integral[-1]) + width * max(abs(self._right[j]), abs(self._left[j + 1]))
            if not reach < _ROOM:
                raise ValueError(f"the table's running integral reaches {reach:.3g} between times {self.times[j]!r} and "
                                 f"{self.times[j + 1]!r}: |value| x time must stay below {_ROOM:.3g} (every "
                                 f"derived number a finite double)")
            self._integral.append(self._integral[-1] + width * self._segment_mean(j))

    def _segment_mean(self, j):
        if self.interpolation == "hold":
            return self._right[j]
        return 0.5 * (self._right[j] + self._left[j + 1])

    def _snap(self, t):
        """``t``, or the table time it lies within rounding of."""
        j = bisect.bisect_left(self.times, t)
        for k in (j - 1, j):
            if 0 <= k < len(self.times) and abs(self.times[k] - t) <= self.tolerance:
                return self.times[k]
        return t

    def _segment(self, t):
        """Index j with times[j] <= t < times[j+1] (-1 before the table, last index after it)."""
        return bisect.bisect_right(self.times, t) - 1

    def value(self, t):
        """The signal at ``t``, right-continuous at every switch."""
        t = self._snap(check_finite(t, "t"))
        j = self._segment(t)
        if j < 0:
            return self.before
        if j == len(self.times) - 1 or self.interpolation == "hold":
            return self._right[j]
        fraction = (t - self.times[j]) / (self.times[j + 1] - self.times[j])
        return self._right[j] + (self._left[j + 1] - self._right[j]) * fraction

    def integral(self, t):
        """Integral of the signal from the first row's time to ``t`` (negative before it)."""
        t = self._snap(check_finite(t, "t"))
        j = self._segment(t)
        if j < 0:
            return (t - self.times[0]) * self.before
        s = t - self.times[j]
        if j == len(self.times) - 1 or self.interpolation == "hold":
            return self._integral[j] + s * self._right[j]
        slope = (self._left[j + 1] - self._right[j]) / (self.times[j + 1] - self.times[j])
        return self._integral[j] + s * self._right[j] + 0.5 * slope * s * s

    def average(self, t_start, t_end):
        """Exact mean of the signal over [t_start, t_end]; the value at t_start for an empty interval."""
        t_start, t_end = check_finite(t_start, "t_start"), check_finite(t_end, "t_end")
        if t_end < t_start:
            raise ValueError(f"t_end must be >= t_start = {t_start!r}, got {t_end!r}")
        a, b = self._snap(t_start), self._snap(t_end)
        if b == a:
            return self.value(a)
        j = self._segment(a)
        if j == self._segment(b):  # one segment: its own mean, a constant or a line's midpoint
            if j < 0:
                return self.before
            if j == len(self.times) - 1 or self.interpolation == "hold":
                return self._right[j]
            return 0.5 * (self.value(a) + self.value(b))
        # The part inside the table by its integral, the parts before and after it by their share.
        first, last = max(a, self.times[0]), min(b, self.times[-1])
        width = b - a
        return ((self.integral(last) - self.integral(first)) / width + (first - a) / width * self.before
                + (b - last) / width * self._right[-1])

    def next_switch(self, t):
        """The first table time after ``t`` (beyond rounding), or inf: where a master may end a step."""
        t = self._snap(check_finite(t, "t"))
        j = bisect.bisect_right(self.times, t)
        return self.times[j] if j < len(self.times) else math.inf

    def to_dict(self):
        """The table as the ``signal_table`` JSON object ``from_dict`` reads."""
        times, values = [], []
        for t, left, right in zip(self.times, self._left, self._right):
            if self.interpolation == "linear" and left != right:
                times.append(t)
                values.append(left)
            times.append(t)
            values.append(right)
        return {"kind": "signal_table", "interpolation": self.interpolation, "before": self.before,
                "time": times, "value": values}


def _number(data, key, index=None):
    """``data[key]`` (or its element ``index``) as a float: a JSON number, nothing else (a string, a
    boolean, null are refused with the key named)."""
    value = data[key] if index is None else data[key][index]
    where = key if index is None else f"{key}[{index}]"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{where} must be a number, got {json.dumps(value)[:40]} (a {_json_type(value)})")
    return check_finite(value, where)


def _numbers(data, key):
    """``data[key]``, a JSON list of numbers, as floats (``"time": 5`` or ``"012"`` refused, naming the key)."""
    if not isinstance(data[key], list):
        raise ValueError(f"{key} must be a list of numbers, got {json.dumps(data[key])[:40]} (a {_json_type(data[key])})")
    return [_number(data, key, i) for i in range(len(data[key]))]


def _json_type(value):
    return {bool: "boolean", str: "string", type(None): "null", dict: "object", list: "list"}.get(type(value), "number")


def from_dict(data):
    """A table from a ``time_optimal`` (TimeOptimalSolution.to_dict) or ``signal_table`` JSON object; every
    number must be a JSON number (see the module docstring)."""
    if not isinstance(data, dict):
        raise ValueError(f"a signal table must be a JSON object, got {type(data).__name__}")
    kind = data.get("kind")
    try:
        if kind == "time_optimal":
            switches, levels = _numbers(data, "switch_times"), _numbers(data, "levels")
            times = [0.0, *switches, _number(data, "T")]
            values = [*levels, _number(data, "u_final")]
            if len(values) != len(switches) + 2:
                raise ValueError(
                    f"a time_optimal solution needs len(levels) == len(switch_times) + 1, got "
                    f"{len(levels)} and {len(switches)}"
                )
            return SignalTable(times, values, "hold")
        if kind == "signal_table":
            before = _number(data, "before") if "before" in data else 0.0
            return SignalTable(_numbers(data, "time"), _numbers(data, "value"), data.get("interpolation", "hold"), before)
    except KeyError as missing:
        raise ValueError(f"a {kind} object needs the field {missing}") from None
    raise ValueError(f"kind must be 'time_optimal' or 'signal_table', got {kind!r}")


def from_csv(text, interpolation="hold", before=0.0):
    """A table from CSV text with a header row and two columns, time then value (``to_csv``'s format)."""
    rows = [row for row in csv.reader(io.StringIO(text)) if row and any(cell.strip() for cell in row)]
    if len(rows) < 2:
        raise ValueError("a CSV signal table needs a header row and at least one data row")
    times, values = [], []
    for number, row in enumerate(rows[1:], start=2):
        if len(row) != 2:
            raise ValueError(f"CSV line {number} must have 2 columns (time, value), got {len(row)}")
        try:
            times.append(float(row[0]))
            values.append(float(row[1]))
        except ValueError:
            raise ValueError(f"CSV line {number} must hold two numbers, got {row!r}") from None
    return SignalTable(times, values, interpolation, before)


def load(path, interpolation="hold"):
    """Read a ``.json`` (from_dict) or ``.csv`` (from_csv, with ``interpolation``) signal table file."""
    name = str(path)
    text = read_text_file(name, "signal table")
    if name.lower().endswith(".json"):
        try:
            data = parse_nested(json.loads, text, name)
        except json.JSONDecodeError as error:
            raise ValueError(f"{name} is not valid JSON: {error}") from None
        read = from_dict
    elif name.lower().endswith(".csv"):
        data, read = text, lambda csv_text: from_csv(csv_text, interpolation)
    else:
        raise ValueError(f"path must end in .json or .csv, got {name!r}")
    try:
        return read(data)
    except ValueError as error:
        raise ValueError(f"{name}: {error}") from None
