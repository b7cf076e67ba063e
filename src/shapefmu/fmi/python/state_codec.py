"""FMU state as plain data: exact snapshots of the slaves' kernels for fmi2Get/Set/SerializeFMUstate.

Bundled into every FMU, so standard library only. A state is a tree of JSON values; what JSON lacks
is tagged:

- floats go through ``repr`` (Python's shortest round-trip form), so every bit comes back, and
  NaN / +-inf are written as JSON's common extension tokens;
- tuples, deques (with their ``maxlen``) and dicts with non-string keys keep their type;
- instances of the classes listed in ``allowed`` (the runtime kernels: StreamingShaper, the EKF,
  ...) are stored as their ``__dict__`` and rebuilt without calling ``__init__``; any other class
  is refused, so a forged byte string can build nothing but data and known kernels.
"""

import json
import math
from collections import deque

_TAG = "\u00a7"  # a key no kernel attribute uses


def encode(value, allowed):
    """A JSON-able copy of ``value``; ``allowed`` maps class names to the classes it may hold."""
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, list):
        return [encode(v, allowed) for v in value]
    if isinstance(value, tuple):
        return {_TAG: "tuple", "items": [encode(v, allowed) for v in value]}
    if isinstance(value, deque):
        return {_TAG: "deque", "maxlen": value.maxlen, "items": [encode(v, allowed) for v in value]}
    if isinstance(value, dict):
        return {_TAG: "dict", "items": [[encode(k, allowed), encode(v, allowed)] for k, v in value.items()]}
    name = type(value).__name__
    if allowed.get(name) is type(value):
        return {_TAG: "object", "class": name, "state": encode(vars(value), allowed)}
    raise TypeError(f"cannot store a {name} in an FMU state")


def decode(data, allowed):
    """The inverse of ``encode``; raises ValueError on anything ``encode`` cannot have produced."""
    if data is None or isinstance(data, (bool, int, float, str)):
        return data
    if isinstance(data, list):
        return [decode(v, allowed) for v in data]
    if not isinstance(data, dict) or _TAG not in data:
        raise ValueError("malformed FMU state: untagged mapping")
    tag = data[_TAG]
    if tag == "tuple":
        return tuple(decode(v, allowed) for v in _items(data))
    if tag == "deque":
        maxlen = data.get("maxlen")
        if maxlen is not None and (not isinstance(maxlen, int) or maxlen < 0):
            raise ValueError(f"malformed FMU state: deque maxlen {maxlen!r}")
        return deque((decode(v, allowed) for v in _items(data)), maxlen)
    if tag == "dict":
        pairs = _items(data)
        if not all(isinstance(p, list) and len(p) == 2 for p in pairs):
            raise ValueError("malformed FMU state: dict items must be pairs")
        result = {}
        for k, v in pairs:
            key = decode(k, allowed)
            try:
                result[key] = decode(v, allowed)
            except TypeError:  # an unhashable key
                raise ValueError("malformed FMU state: unhashable dict key") from None
        return result
    if tag == "object":
        cls = allowed.get(data.get("class"))
        if cls is None:
            raise ValueError(f"malformed FMU state: class {data.get('class')!r} is not a runtime kernel")
        attributes = decode(data.get("state"), allowed)
        if not isinstance(attributes, dict) or not all(isinstance(k, str) for k in attributes):
            raise ValueError("malformed FMU state: object attributes must be a name mapping")
        obj = cls.__new__(cls)
        obj.__dict__.update(attributes)
        return obj
    raise ValueError(f"malformed FMU state: unknown tag {tag!r}")


def first_non_finite(value, path):
    """The path (below ``path``) of the first NaN or infinite float in a decoded state, or None.

    Every number an FMU holds comes from values fmi2SetReal accepts and finite steps, so a state
    holding NaN or inf was forged: restored, it would make NaN outputs.
    """
    if isinstance(value, float):
        return None if math.isfinite(value) else path
    if isinstance(value, dict):
        entries = value.items()
    elif isinstance(value, (list, tuple, deque)):
        entries = enumerate(value)
    elif hasattr(value, "__dict__"):  # a kernel decode rebuilt
        entries = vars(value).items()
    else:
        return None
    for key, item in entries:
        found = first_non_finite(item, f"{path}.{key}")
        if found is not None:
            return found
    return None


def _items(data):
    items = data.get("items")
    if not isinstance(items, list):
        raise ValueError("malformed FMU state: items must be a list")
    return items


def invalid(message):
    """An encoded state that ``Fmi2Slave._set_fmu_state`` refuses with ``message``."""
    return {_TAG: "dict", "items": [["invalid", message]]}


def to_bytes(tree):
    """Serialise an encoded state (``allow_nan``: NaN and inf are legitimate kernel values)."""
    return json.dumps(tree, allow_nan=True, separators=(",", ":")).encode("utf-8")


def from_bytes(raw):
    """Parse bytes from ``to_bytes``; ValueError for anything else."""
    try:
        return json.loads(bytes(raw).decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as error:
        raise ValueError(f"malformed FMU state: {error}") from None
