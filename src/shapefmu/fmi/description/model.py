"""One model description of a built FMU, whatever its FMI version (as FMPy's ``ModelDescription``):
what the writers ``fmi2.write`` and ``fmi3.write`` turn into ``modelDescription.xml``."""

from __future__ import annotations

import datetime
from dataclasses import dataclass, field

from shapefmu.fmi.kinds.interface import Variable


def now() -> str:
    """The generation date and time of a description written now (UTC, to the second)."""
    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


@dataclass(frozen=True)
class ModelDescription:
    """A built FMU's model description.

    ``variables`` are in value-reference order: FMI 2.0 numbers them by position, FMI 3.0 by position
    after time with the elements of an array parameter as one variable (``fmi3.variables3``); a
    variable of causality "independent" is time. ``dependencies`` maps each output and derivative to
    the inputs and states it depends on at the same instant. ``designed``: the FMU designs at the exit
    of initialisation from every parameter, so its initial outputs depend on all of them and a
    feed-through factor is fixed from there on (a plant's are tunable, its initial unknowns depend on
    everything). ``host_memory``: it allocates with the host's memory functions. ``clock_interval``
    (FMI 3.0): > 0 declares the periodic input clock ``sample`` of that interval.
    """

    model_name: str
    identifier: str
    guid: str
    description: str
    generation_tool: str
    variables: tuple[Variable, ...]
    dependencies: dict = field(default_factory=dict)
    log_categories: tuple = ()          # (name, description) pairs
    generation_date: str | None = None
    experiment: tuple | None = None     # (start, stop, step) in s
    model_exchange: bool = False
    directional_derivatives: bool = False
    host_memory: bool = True
    source_files: tuple = ()
    designed: bool = True
    clock_interval: float = 0.0

    def units(self) -> list[str]:
        """The units the Real variables use, sorted."""
        return sorted({v.unit for v in self.variables if v.type == "Real" and v.unit})
