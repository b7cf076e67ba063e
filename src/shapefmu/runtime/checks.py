"""Parameter guards shared by the runtime kernels, the FMUs and the design layer.

Every message names the parameter, the value received and the valid range, so that an FMU can log
it verbatim and a user of the Python API knows what to change.
"""

import math


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

