"""Units of the variables shapefmu's FMUs declare, with their SI base units (FMI 2.0 section 2.2.2,
FMI 3.0 section 2.4.3).

``base_units(text)`` reads a unit as model files and kinds write it -- a product and quotient of
named units with integer powers: ``V``, ``rad/s``, ``m/s2`` (FMI's own ``s2`` for s^2), ``m/s^2``,
``1/(V*s^2)``, ``N.m``, ``1`` -- and gives the attributes of its BaseUnit element: the exponents of
kg, m, s, A, K, mol, cd and rad, and the factor to them; None for a unit it cannot read, which is
then written without one.
"""

from __future__ import annotations

import math
import re

BASE = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")

# name -> (factor, {base unit: exponent}): the SI base units, the derived units with special names
# the plants and kinds use (BIPM, The International System of Units, 9th ed., table 4) and a few
# scaled ones.
NAMED = {
    "kg": (1.0, {"kg": 1}), "m": (1.0, {"m": 1}), "s": (1.0, {"s": 1}), "A": (1.0, {"A": 1}),
    "K": (1.0, {"K": 1}), "mol": (1.0, {"mol": 1}), "cd": (1.0, {"cd": 1}), "rad": (1.0, {"rad": 1}),
    "g": (1e-3, {"kg": 1}), "mm": (1e-3, {"m": 1}), "cm": (1e-2, {"m": 1}), "km": (1e3, {"m": 1}),
    "in": (0.0254, {"m": 1}), "ms": (1e-3, {"s": 1}), "us": (1e-6, {"s": 1}), "min": (60.0, {"s": 1}),
    "Hz": (1.0, {"s": -1}), "N": (1.0, {"kg": 1, "m": 1, "s": -2}), "J": (1.0, {"kg": 1, "m": 2, "s": -2}),
    "W": (1.0, {"kg": 1, "m": 2, "s": -3}), "V": (1.0, {"kg": 1, "m": 2, "s": -3, "A": -1}),
    "Ohm": (1.0, {"kg": 1, "m": 2, "s": -3, "A": -2}), "ohm": (1.0, {"kg": 1, "m": 2, "s": -3, "A": -2}),
    "deg": (math.pi / 180.0, {"rad": 1}),
    "rpm": (2.0 * math.pi / 60.0, {"rad": 1, "s": -1}), "1": (1.0, {}),
}
_TOKEN = re.compile(r"\s*(?:(?P<name>[A-Za-z]+)(?P<power>-?\d+)?|(?P<one>1)|(?P<op>[*./^()])|(?P<int>-?\d+))")


def base_units(text: str) -> dict | None:
    """The BaseUnit attributes of the unit ``text`` (exponents and factor as text; {} for "1"), or
    None if it is not a product of known units with integer powers.

    >>> base_units("1/(V*s^2)")
    {'kg': '-1', 'm': '-2', 's': '1', 'A': '1'}
    >>> base_units("m/s2") == base_units("m/s^2") == {"m": "1", "s": "-2"}
    True
    >>> base_units("furlong") is None
    True
    """
    try:
        factor, exponents, rest = _product(_tokens(text), 0)
    except (KeyError, ValueError, IndexError):
        return None
    if rest != len(_tokens(text)):
        return None
    attributes = {name: str(exponents[name]) for name in BASE if exponents.get(name)}
    if factor != 1.0:
        attributes["factor"] = repr(factor)
    return attributes


def _tokens(text: str) -> list[tuple[str, str]]:
    tokens, at = [], 0
    while at < len(text.strip()):
        match = _TOKEN.match(text.strip(), at)
        if match is None or match.end() == at:
            raise ValueError(text)
        kind = match.lastgroup if match.lastgroup != "power" else "name"
        if match.group("name"):
            tokens.append(("name", match.group("name")))
            if match.group("power"):
                tokens += [("op", "^"), ("int", match.group("power"))]
        else:
            tokens.append((kind, match.group(kind)))
        at = match.end()
    return tokens


def _product(tokens, at):
    """factor, exponents of the product/quotient starting at token ``at``; and where it ends."""
    factor, exponents, at = _power(tokens, at)
    while at < len(tokens) and tokens[at] in (("op", "*"), ("op", "."), ("op", "/")):
        sign = -1 if tokens[at][1] == "/" else 1
        f, e, at = _power(tokens, at + 1)
        factor *= f**sign
        for name, power in e.items():
            exponents[name] = exponents.get(name, 0) + sign * power
    return factor, exponents, at


def _power(tokens, at):
    kind, value = tokens[at]
    if (kind, value) == ("op", "("):
        factor, exponents, at = _product(tokens, at + 1)
        if tokens[at] != ("op", ")"):
            raise ValueError("unbalanced")
        at += 1
    elif kind in ("name", "one"):
        factor, exponents = NAMED[value]
        exponents, at = dict(exponents), at + 1
    else:
        raise ValueError(value)
    if at < len(tokens) and tokens[at] == ("op", "^"):
        power = int(tokens[at + 1][1])
        factor, exponents, at = factor**power, {k: v * power for k, v in exponents.items()}, at + 2
    return factor, exponents, at
