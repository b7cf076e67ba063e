"""Parameter guards shared by the runtime kernels, the FMUs and the design layer.

Every message names the parameter, the value received and the valid range, so that an FMU can log
it verbatim and a user of the Python API knows what to change.
"""

import math

from . import limits


def check_finite(value, name):
    """Return ``value`` as a float, or raise ValueError if it is not a finite real number."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite real number, got {value!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"{name} must be a finite real number, got {value!r}")
    return x


def check_positive(value, name):
    """Return ``value`` as a float if it is finite and > 0."""
    x = check_finite(value, name)
    if x <= 0.0:
        raise ValueError(f"{name} must be > 0, got {value!r}")
    return x


def check_omega(value, name="omega"):
    """An angular frequency in rad/s: finite and > 0."""
    return check_positive(value, name)


def check_zeta(value, name="zeta", upper=1.0):
    """A damping ratio in [0, upper); ``upper`` is 1 unless a design is only defined below it."""
    x = check_finite(value, name)
    if not 0.0 <= x < upper:
        raise ValueError(f"{name} must be in [0, {upper:g}), got {value!r}")
    return x


def check_vtol(value, name="vtol"):
    """A residual-vibration tolerance, a fraction in (0, 1)."""
    x = check_finite(value, name)
    if not 0.0 < x < 1.0:
        raise ValueError(f"{name} must be in (0, 1), got {value!r}")
    return x


def check_count(value, name, minimum=0):
    """An integer count >= ``minimum``; bools and non-integral numbers are refused."""
    integral = isinstance(value, int) or (isinstance(value, float) and value.is_integer())
    if isinstance(value, bool) or not integral or int(value) < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def check_size(estimate, limit_name, needs, unit, advice):
    """Refuse a design or run whose estimated size exceeds ``limits.<limit_name>``.

    The message reads "<needs> <estimate> <unit>, more than the limit of <limit> (...); <advice>",
    e.g. "zvd over 20 modes would have 3.487e+09 impulses, more than the limit of 10,000 ...".
    The limit is looked up at each call, so a program may raise it (see ``limits``).
    """
    limit = getattr(limits, limit_name)
    if not estimate <= limit:  # also refuses a NaN estimate
        shown = f"{estimate:,}" if isinstance(estimate, int) and estimate < 10**12 else f"{estimate:.4g}"
        raise ValueError(f"{needs} {shown} {unit}, more than the limit of {limit:,} "
                         f"(shapefmu.runtime.limits.{limit_name}); {advice}")
    return estimate


def check_text(value, name):
    """A string that an FMU's modelDescription.xml can carry: XML 1.0 has no control characters
    but tab, newline and carriage return (escaping cannot help), nor U+FFFE and U+FFFF."""
    if not isinstance(value, str):
        raise ValueError(f"{name} must be a string, got {value!r}")
    bad = sorted({f"U+{ord(c):04X}" for c in value
                  if (ord(c) < 32 and c not in "\t\n\r") or ord(c) in (0xFFFE, 0xFFFF)})
    if bad:
        raise ValueError(f"{name} holds the control character(s) {', '.join(bad)}, "
                         f"which an FMU description cannot carry")
    return value


def aliased_modes(modes, ts):
    """Indices of the modes (omega rad/s, zeta) whose damped frequency is at or above the Nyquist
    frequency pi/ts of the sampling period ``ts``: a filter sampled at ``ts`` cannot place a zero
    on them (their samples alias onto a lower frequency), so a shaper for them leaves the mode ringing."""
    nyquist = math.pi / ts
    return [i for i, (omega, zeta) in enumerate(modes) if omega * math.sqrt(1.0 - zeta * zeta) >= nyquist]


def read_text_file(path, what):
    """The text of a file a user named (a model, a signal table, a sweep's rows): refused with a
    one-line message if it is not a regular file (a FIFO or ``/dev/zero`` would block or never end),
    if it holds more than ``limits.MAX_INPUT_FILE_BYTES``, or if it is not UTF-8."""
    import os
    import stat

    name = os.fspath(path)
    try:  # opened without blocking: a FIFO with no writer would wait in open() forever
        with open(os.open(name, os.O_RDONLY | os.O_NONBLOCK), "rb") as stream:
            status = os.fstat(stream.fileno())
            if not stat.S_ISREG(status.st_mode):
                raise ValueError(f"{name}: {what} must be a regular file, not a FIFO, device or folder")
            check_size(status.st_size, "MAX_INPUT_FILE_BYTES", f"{name}: {what} of", "bytes",
                       "give a smaller file")
            data = stream.read(limits.MAX_INPUT_FILE_BYTES + 1)
    except OSError as error:
        raise ValueError(f"{name}: cannot read {what}: {error.strerror}") from None
    check_size(len(data), "MAX_INPUT_FILE_BYTES", f"{name}: {what} of", "bytes", "give a smaller file")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise ValueError(f"{name}: not a {what} (not UTF-8 text: {error.reason} at byte {error.start})") from None


def parse_nested(parse, text, what):
    """``parse(text)`` (json.loads, tomllib.loads), with nesting deeper than Python's parsers can
    follow refused as a ValueError naming ``what`` rather than a RecursionError."""
    try:
        return parse(text)
    except RecursionError:
        raise ValueError(f"{what} is nested deeper than can be read (a list or table inside "
                         f"thousands of others)") from None
