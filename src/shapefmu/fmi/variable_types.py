"""The kinds of FMI variables as SSP connectors see them, and values typed by them.

An FMI 2.0 or 3.0 variable has one of the SSP 1.0 connector kinds ``Real``, ``Integer``,
``Boolean``, ``String`` or ``Enumeration`` (FMI 3.0 ``Float32``/``Float64`` are Real, its integer
types Integer). :func:`typed_value` turns a value given by a user -- the text of ``--set`` or of a
parameter file, or a Python value -- into the Python value of a variable of that kind, refusing
what does not fit with a message naming the variable, the value and what is valid.

FMI 3.0 array variables (1-D: one ``<Dimension>``) are named as a whole (``k``) or element by element
with the 1-based index of FMI 3.0's structured naming (``k[2]``);
:func:`split_element` reads such a name and :func:`array_values` the value of a whole array: a
sequence, or the text ``[v1, v2, ...]`` of a command line.
"""

from __future__ import annotations

import math

import re

# SSP connector kind of each FMI variable type.
KIND = {"Real": "Real", "Float64": "Real", "Float32": "Real", "Integer": "Integer", "Enumeration": "Enumeration",
        "Boolean": "Boolean", "String": "String",
        **{t: "Integer" for t in ("Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64")}}
KINDS = ("Real", "Integer", "Boolean", "String", "Enumeration")


def kind_of(variable) -> str | None:
    """The SSP connector kind of an fmpy ModelVariable, or None for a type with none (Binary, Clock)."""
    return KIND.get(variable.type)


_ELEMENT = re.compile(r"^(.+)\[([1-9][0-9]*)\]$")


def split_element(reference: str) -> tuple[str, int] | None:
    """``("k", 2)`` for the element name ``"k[2]"``; None for a name without a trailing index.

    Callers look the whole name up first: an FMI 2.0 variable may itself be called ``f[1]`` (flat
    naming of a flattened Modelica array), and it is that scalar, not an element."""
    match = _ELEMENT.match(reference)
    return (match.group(1), int(match.group(2))) if match else None


def array_size(variable) -> int | None:
    """The number of elements of an fmpy ModelVariable that is an array (its shape's product, the
    sizes the model description declares), or None for a scalar."""
    shape = getattr(variable, "shape", None)
    if not shape:
        return None
    size = 1
    for extent in shape:
        size *= extent
    return size


def array_values(value, size: int, what: str) -> list:
    """The ``size`` elements of a whole-array ``value``: a sequence (a list, a numpy array) or the
    text ``"[v1, v2, ...]"``; each still to be typed by :func:`typed_value`."""
    if isinstance(value, str):
        text = value.strip()
        if not (text.startswith("[") and text.endswith("]")):
            raise ValueError(f"{what} is an array of {size} elements: give all as [v1, ..., v{size}] or one as "
                             f"name[i], got {value!r}")
        inner = text[1:-1].strip()
        items = [item.strip() for item in inner.split(",")] if inner else []
    elif hasattr(value, "__iter__") and not isinstance(value, (bytes, dict)):
        items = list(value)
    else:
        raise ValueError(f"{what} is an array of {size} elements: give all as [v1, ..., v{size}] or one as "
                         f"name[i], got {value!r}")
    if len(items) != size:
        raise ValueError(f"{what} has {size} elements, got {len(items)} values: {value!r}")
    return items


_TRUE, _FALSE = ("true", "1"), ("false", "0")
# The values of each integer type: fmi2Integer is a C int (fmi2TypesPlatform.h), as is fmi3Int32, 32
# bits on every platform; FMI 3.0 has a type per width and sign (fmi3PlatformTypes.h), and its
# Enumerations are Int64.
INTEGER_RANGES = {
    "Integer": (-(2**31), 2**31 - 1), "Int32": (-(2**31), 2**31 - 1),
    "Int8": (-(2**7), 2**7 - 1), "UInt8": (0, 2**8 - 1), "Int16": (-(2**15), 2**15 - 1), "UInt16": (0, 2**16 - 1),
    "UInt32": (0, 2**32 - 1), "Int64": (-(2**63), 2**63 - 1), "UInt64": (0, 2**64 - 1),
}


def _overflows(text: str) -> bool:
    """Whether the text of a number is beyond a double's range: float() would make it inf silently."""
    try:
        number = float(text)
    except ValueError:
        return False
    return math.isinf(number) and text.lstrip("+-").lower() not in ("inf", "infinity")


def typed_value(value, kind: str, items: dict[str, int] | None = None, what: str = "value", variable_type: str | None = None):
    """``value`` (a Python value or the text of a command line / parameter file) as the Python value
    of an FMI variable of ``kind``; an Enumeration takes an item name (``items``) or its integer.
    ``variable_type`` is the variable's FMI type (``"UInt8"``, ``"Int64"``, ...): an integer must fit
    it (without one, the 32 bits of fmi2Integer / fmi3Int32).

    Nothing is lost on the way: ``1.5`` for an Integer is refused, not truncated to 1, and an
    integer beyond its type's range is refused, not wrapped around by ctypes.
    """
    text = value.strip() if isinstance(value, str) else None
    if kind == "Real" and text is not None and _overflows(text):
        raise ValueError(f"{what} must be a number a double holds (|x| <= 1.8e308, or inf itself), got {value!r}")
    integer_type = variable_type if variable_type in INTEGER_RANGES else "Integer"
    low, high = INTEGER_RANGES[integer_type]
    try:
        if kind == "Real":
            if isinstance(value, bool):
                raise ValueError
            return float(text if text is not None else value)
        if kind == "String":
            return str(value)
        if kind == "Boolean":
            if text is not None and text.lower() in _TRUE + _FALSE:
                return text.lower() in _TRUE
            if isinstance(value, bool) or (isinstance(value, (int, float)) and value in (0, 1)):
                return bool(value)
            raise ValueError
        if kind == "Enumeration" and text is not None and items and text in items:
            return items[text]
        number = int(text) if text is not None else value
        if isinstance(number, bool) or not isinstance(number, int) and not (isinstance(number, float) and number.is_integer()):
            raise ValueError
        number = int(number)
        if not low <= number <= high or kind == "Enumeration" and items and number not in items.values():
            raise ValueError
        return number
    except (TypeError, ValueError, OverflowError):
        valid = {"Real": "a number", "Integer": f"an integer in [{low}, {high}]", "Boolean": "true, false, 1 or 0",
                 "String": "text",
                 "Enumeration": f"one of {', '.join(items)} or its number" if items else "an integer"}[kind]
        named = integer_type if kind == "Integer" and variable_type else kind  # "(UInt8)", "(Integer)"
        raise ValueError(f"{what} must be {valid} ({named}), got {value!r}") from None


def enumeration_items(description, variable) -> dict[str, int]:
    """``{item name: value}`` of an Enumeration variable's declared type ({} for other types)."""
    if variable.type != "Enumeration" or variable.declaredType is None:
        return {}
    return {item.name: int(item.value) for item in variable.declaredType.items}
