"""FMI variable types as the master moves them: one *family* per FMI get/set function.

FMI 2.0 has four families (``fmi2GetReal``, ``fmi2GetInteger`` -- which Enumerations share --,
``fmi2GetBoolean``, ``fmi2GetString``); FMI 3.0 has one per scalar type (``fmi3GetFloat64``,
``fmi3GetInt32``, ... -- Enumerations share ``fmi3GetInt64``). A family fixes the C element type of
the batched value arrays, the numpy type of a recorded column and the C type the compiled step loop
uses (None for strings, which only the Python loop moves).

Every variable also has a *kind*, the type of the SSP connector (``Real``, ``Integer``, ``Boolean``,
``String``, ``Enumeration``): connections are checked on kinds, so an FMI 2.0 Real output may feed an
FMI 3.0 Float64 input and an Integer an Int32.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass

from shapefmu.fmi.variable_types import (KIND, array_size, array_values, enumeration_items, kind_of, split_element,
                                         typed_value)

__all__ = ["FAMILIES_2", "FAMILIES_3", "Family", "KIND", "array_size", "array_values", "enumeration_items", "family_of",
           "kind_of", "split_element", "typed_value"]


@dataclass(frozen=True)
class Family:
    """How the values of one FMI get/set function pair travel."""

    name: str          # the FMI type in the function name: Real, Integer, ..., Float64, Int32, ...
    ctype: type        # ctypes element of the value arrays
    record: str        # numpy dtype of a recorded column
    c_type: str | None  # C element type in the compiled loop; None: Python loop only


FAMILIES_2 = {
    "Real": Family("Real", ctypes.c_double, "f8", "double"),
    "Integer": Family("Integer", ctypes.c_int, "i4", "int"),
    "Boolean": Family("Boolean", ctypes.c_int, "?", "int"),
    "String": Family("String", ctypes.c_char_p, "O", None),
}
FAMILIES_3 = {
    "Float64": Family("Float64", ctypes.c_double, "f8", "double"),
    "Float32": Family("Float32", ctypes.c_float, "f4", "float"),
    "Int8": Family("Int8", ctypes.c_int8, "i1", "signed char"),
    "UInt8": Family("UInt8", ctypes.c_uint8, "u1", "unsigned char"),
    "Int16": Family("Int16", ctypes.c_int16, "i2", "short"),
    "UInt16": Family("UInt16", ctypes.c_uint16, "u2", "unsigned short"),
    "Int32": Family("Int32", ctypes.c_int32, "i4", "int"),
    "UInt32": Family("UInt32", ctypes.c_uint32, "u4", "unsigned int"),
    "Int64": Family("Int64", ctypes.c_int64, "i8", "long long"),
    "UInt64": Family("UInt64", ctypes.c_uint64, "u8", "unsigned long long"),
    "Boolean": Family("Boolean", ctypes.c_bool, "?", "_Bool"),
    "String": Family("String", ctypes.c_char_p, "O", None),
}

def family_of(variable, fmi3: bool) -> Family:
    """The family that gets and sets ``variable`` (an fmpy ModelVariable)."""
    if variable.type == "Enumeration":
        return FAMILIES_3["Int64"] if fmi3 else FAMILIES_2["Integer"]
    table = FAMILIES_3 if fmi3 else FAMILIES_2
    family = table.get(variable.type)
    if family is None:
        raise ValueError(f"variable {variable.name!r} has type {variable.type}, which the master does not move "
                         f"(it moves {', '.join(KIND)})")
    return family
