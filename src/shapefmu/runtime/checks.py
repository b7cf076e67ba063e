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
