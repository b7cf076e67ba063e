"""Values given for FMI variables (SSP bindings, a run's parameters), converted to the variable's
FMI 2.0 type without losing anything: ``n_modes = 1.5`` is refused, not truncated to 1, and an
Integer beyond fmi2Integer's 32 bits is refused, not wrapped around by ctypes."""

from __future__ import annotations

import math

# fmi2Integer is a C int (fmi2TypesPlatform.h): 32 bits on every platform FMUs are built for.
FMI2_INTEGER_RANGE = (-(2**31), 2**31 - 1)
_BOOLEAN_TEXT = {"true": True, "false": False, "1": True, "0": False}


def fmi_value(type_name: str, value, name: str):
    """``value`` as the Python value of an FMI ``type_name`` variable called ``name``, or ValueError
    naming the variable, the value and what it must be."""
    if type_name == "Real":
        try:
            return float(value)
        except (TypeError, ValueError, OverflowError):
            raise ValueError(f"{name} is a Real variable: it needs a number, got {value!r}") from None
    if type_name in ("Integer", "Enumeration"):
        return _integer(value, name, type_name)
    if type_name == "Boolean":
        if isinstance(value, bool):
            return value
        if isinstance(value, (int, float)) and value in (0, 1):
            return bool(value)
        if isinstance(value, str) and value.strip().lower() in _BOOLEAN_TEXT:
            return _BOOLEAN_TEXT[value.strip().lower()]
        raise ValueError(f"{name} is a Boolean variable: it needs true, false, 1 or 0, got {value!r}")
    if type_name == "String":
        return value if isinstance(value, str) else str(value)
    raise ValueError(f"{name} has FMI type {type_name!r}, which has no values here")


def _integer(value, name, type_name):
    low, high = FMI2_INTEGER_RANGE
    number = value
    if isinstance(value, str):
        try:
            number = int(value)
        except ValueError:
            try:
                number = float(value)
            except ValueError:
                number = None
    whole = isinstance(number, int) or (isinstance(number, float) and math.isfinite(number) and number.is_integer())
    if isinstance(number, bool) or not whole or not low <= number <= high:
        raise ValueError(f"{name} is an {type_name} variable: it needs a whole number in [{low}, {high}], "
                         f"got {value!r}")
    return int(number)
