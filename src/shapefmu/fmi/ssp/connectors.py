"""The connectors of an FMU as an SSP system sees them, the names that point at them, and parameter
values typed by them.

A connector is an input, output or parameter of the FMU (:func:`fmu_connectors`), with its SSP kind
(``Real``, ``Integer``, ...). FMI 3.0 array variables: SSP 1.0 has no array connectors, and its
``ssv:Parameter`` holds one scalar, so an array travels as its elements, named with FMI 3.0's 1-based
structured index:

* a 1-D array variable is a connector of its own name with a ``size``; a connection names either
  the whole array (``a.y -> b.u``: element i to element i, both of the same size) or one element
  (``a.y[2] -> b.s``, ``a.total -> b.u[1]``), which pairs with a scalar or another element
  (:func:`resolve`). Arrays of more dimensions are not connectors.
* parameter bindings bind elements: ``<ssv:Parameter name="k[2]"><ssv:Real value="3"/>``, as FMI
  2.0 exporters name the scalar variables of a flattened array, so a binding file reads as in other
  SSP tools. A whole array given in Python (``{"k": [1, 2, 3]}``) or as text (``"[1, 2, 3]"``,
  ``--set``) is stored, and written, as its elements ``k[1]``, ``k[2]``, ... (:func:`checked_values`).
* a written .ssd declares a whole array as one connector and a whole-array connection as one
  ``ssd:Connection`` naming it; shapefmu reads them back as such (a tool that takes SSP 1.0
  connectors for scalars would not).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from shapefmu.fmi.archives import read_description
from shapefmu.fmi.variable_types import array_size, array_values, enumeration_items, kind_of, split_element, typed_value


@dataclass
class Connector:
    """One connector of a component: an FMU variable with its causality (``kind``) and type."""

    name: str
    kind: str  # input | output | parameter | calculatedParameter | inout
    type: str = "Real"  # Real | Integer | Boolean | String | Enumeration
    declared_type: str | None = None  # an Enumeration's type name
    items: dict[str, int] = field(default_factory=dict)  # an Enumeration's {item: value}
    start: str | None = None  # the FMU's start value, as written in its modelDescription.xml
    variable_type: str | None = None  # the FMU variable's own type (FMI 3.0: Int8 ... UInt64), which bounds a value
    size: int | None = None  # a 1-D FMI 3.0 array's number of elements; None for a scalar


def fmu_connectors(fmu: Path) -> dict[str, Connector]:
    """Inputs, outputs and parameters of an FMU (scalars and 1-D arrays), read from its modelDescription.xml."""
    description = read_description(fmu)
    connectors = {}
    for variable in description.modelVariables:
        kind = kind_of(variable)
        if variable.causality in ("input", "output", "parameter", "calculatedParameter") and kind and len(variable.shape) <= 1:
            declared = variable.declaredType.name if kind == "Enumeration" and variable.declaredType else None
            connectors[variable.name] = Connector(variable.name, variable.causality, kind, declared,
                                                  enumeration_items(description, variable), variable.start, variable.type,
                                                  array_size(variable))
    return connectors


def resolve(connectors: dict[str, Connector], component: str, reference: str) -> tuple[Connector, int | None]:
    """The connector ``reference`` names among ``connectors`` (those of ``component``), and the
    1-based element index when it names one element of an array (``"u[2]"``); else ValueError.
    A connector called ``u[2]`` itself (an FMI 2.0 flat name) is that connector."""
    if reference in connectors:
        return connectors[reference], None
    element = split_element(reference)
    if element is not None and element[0] in connectors and connectors[element[0]].size:
        connector, index = connectors[element[0]], element[1]
        if index > connector.size:
            raise ValueError(f"{component}.{reference}: index {index} is beyond the {connector.size} elements of "
                             f"{component}.{connector.name}")
        return connector, index
    raise ValueError(f"component {component!r} has no connector {reference!r}")


def elements(connectors: dict[str, Connector], component: str, reference: str) -> list[str]:
    """The scalars ``component.reference`` stands for: each element of a whole array, else itself."""
    connector, index = resolve(connectors, component, reference)
    if connector.size is None or index is not None:
        return [f"{component}.{reference}"]
    return [f"{component}.{reference}[{i}]" for i in range(1, connector.size + 1)]


def checked_values(connectors: dict[str, Connector], fmu_name: str, values: dict, where: str) -> dict:
    """``{name: value}`` typed by the connectors; a whole array's value becomes its elements
    ``name[i]`` (module docstring), and must have the array's size."""
    checked = {}
    for name, value in values.items():
        try:
            connector, index = resolve(connectors, fmu_name, name)
        except ValueError as error:
            element = split_element(name)
            if element is not None and element[0] in connectors:  # an index beyond the array
                raise ValueError(f"{where}: parameter {name!r}: {error}") from None
            raise ValueError(f"{where}: FMU {fmu_name} has no parameter or input {name!r}") from None
        what = f"{where}: parameter {name!r}"
        if connector.size is not None and index is None:
            for i, item in enumerate(array_values(value, connector.size, what), 1):
                checked[f"{name}[{i}]"] = typed_value(item, connector.type, connector.items, f"{where}: parameter "
                                                      f"{f'{name}[{i}]'!r}", connector.variable_type)
        else:
            checked[name] = typed_value(value, connector.type, connector.items, what, connector.variable_type)
    return checked
