"""Units of the variables shapefmu's FMUs declare, with their SI base units (FMI 2.0 section 2.2.2,
FMI 3.0 section 2.4.3): ``base_units(name)`` gives the exponents of the BaseUnit element (kg, m, s,
A, K, mol, cd, rad) and its factor, or None for a unit this table does not know (written without one).
"""

# name -> {base unit: exponent}
UNITS = {
    "1": {},
    "s": {"s": 1},
    "Hz": {"s": -1},
    "rad/s": {"rad": 1, "s": -1},
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "m/s2": {"m": 1, "s": -2},
    "1/s": {"s": -1},
    "1/m": {"m": -1},
    "s/m": {"m": -1, "s": 1},
    "1/(m.s)": {"m": -1, "s": -1},
}


def base_units(name: str) -> dict | None:
    """The BaseUnit attributes of unit ``name`` (exponents as text), or None if it is not known."""
    exponents = UNITS.get(name)
    return None if exponents is None else {k: str(e) for k, e in exponents.items()}
