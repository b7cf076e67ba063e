"""Plants whose modes move: a scheduling input on which masses, stiffnesses or lengths depend.

A printer's bed gains the mass of the part printed on it, a crane's rope pays out, a gantry's carriage
moves along its beam: the plant is the same model at another value of one input. A model file
declares that input and, for each parameter that depends on it, its change per unit of the input::

    [scheduling]
    name = "added_mass"
    unit = "kg"
    min = 0.0
    max = 0.3
    start = 0.0
    [scheduling.per_unit]
    masses = [1.0]        # kg per kg: masses = [1.0] + [1.0] * (added_mass - start)

A parameter is then value + per_unit * (s - start): the file's value is the plant at ``start``, so a
reader that ignores the table (the plant-FMU generator until it takes the input) gets a valid plant,
the one at the start value. The laws are affine, so a plant valid at ``min`` and at ``max`` (positive
masses and lengths, damping ratios in [0, 1)) is valid everywhere between; the loader builds both.

Modes come from the model at each value exactly (eigenvalues, ``Plant.modes``), never from a fit:
for the bed, omega = sqrt(k / m(s)); for the crane, omega = sqrt(g / L(s)).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from shapefmu.plants.model import Parameter, Plant
from shapefmu.runtime.checks import check_finite


@dataclass(frozen=True)
class SchedulingInput:
    """The input a plant's parameters depend on: its ``name`` and ``unit``, its range
    [``minimum``, ``maximum``], the ``start`` value the file's parameters describe, and ``per_unit``:
    parameter name -> change of its value per unit of the input, in the parameter's unit (a float, or
    a tuple as long as the parameter's list).

    Examples
    --------
    >>> rope = SchedulingInput("rope_length", "m", 0.5, 2.0, 1.0, {"lengths": (1.0,)})
    >>> rope.parameters_at({"lengths": Parameter((1.0,), "m")}, 2.0)  # 1 m + 1 m/m * (2 - 1) m
    {'lengths': Parameter(value=(2.0,), unit='m')}
    >>> rope.check(3.0)
    Traceback (most recent call last):
    ...
    ValueError: rope_length must be in [0.5, 2] m, got 3.0
    """

    name: str
    unit: str
    minimum: float
    maximum: float
    start: float
    per_unit: Mapping[str, float | tuple[float, ...]]
    description: str = ""

    def __post_init__(self):
        object.__setattr__(self, "per_unit", MappingProxyType(dict(self.per_unit)))

    def check(self, value) -> float:
        """``value`` as a float if it lies in the range, else a ValueError naming the range."""
        x = check_finite(value, self.name)
        if not self.minimum <= x <= self.maximum:
            raise ValueError(f"{self.name} must be in [{self.minimum:g}, {self.maximum:g}] {self.unit}, got {value!r}")
        return x

    def parameters_at(self, parameters: Mapping[str, Parameter], value) -> dict[str, Parameter]:
        """The parameters (as written in the file) at ``value`` of the input."""
        shift = self.check(value) - self.start
        moved = dict(parameters)
        for key, rate in self.per_unit.items():
            written = parameters[key]
            if isinstance(written.value, tuple):
                moved[key] = Parameter(tuple(v + r * shift for v, r in zip(written.value, rate)), written.unit)
            else:
                moved[key] = Parameter(written.value + rate * shift, written.unit)
        return moved


@dataclass(frozen=True)
class ModeCurve:
    """Modes along the scheduling input: ``values`` of the input, and at each the natural frequency
    ``frequencies`` (Hz) and damping ratio ``zetas`` of one mode, computed from the model.

    Examples
    --------
    >>> from shapefmu.plants import load_scheduled
    >>> curve = load_scheduled("gantry_crane").mode_curve([0.5, 2.0])  # rope lengths, m
    >>> [round(f, 6) for f in curve.frequencies]  # sqrt(g / L) / (2 pi) with g = 9.80665
    [0.704848, 0.352424]
    """

    values: tuple[float, ...]
    frequencies: tuple[float, ...]
    zetas: tuple[float, ...]


@dataclass(frozen=True, eq=False)
class ScheduledPlant:
    """A plant model with a scheduling input: ``plant`` is the model at ``scheduling.start``, ``at(s)``
    the model at another value. ``build`` turns the file's parameters into a plant (the loader's).

    Examples
    --------
    >>> from shapefmu.plants import load_scheduled
    >>> bed = load_scheduled("printer_bed")
    >>> bed.plant.parameters["masses"], bed.at(300.0).parameters["masses"]  # 300 g at 0.001 kg/g
    (Parameter(value=(1.0,), unit='kg'), Parameter(value=(1.3,), unit='kg'))
    """

    plant: Plant
    scheduling: SchedulingInput
    build: Callable[[dict[str, Parameter]], Plant] = field(repr=False)

    def at(self, value) -> Plant:
        """The plant at ``value`` of the scheduling input (a ValueError outside its range)."""
        return self.build(self.scheduling.parameters_at(self.plant.parameters, value))

    def flexible_modes_at(self, value) -> list[tuple[float, float]]:
        """``(omega rad/s, zeta)`` of the oscillatory modes the input excites, at ``value``."""
        return self.at(value).flexible_modes()

    def mode_curve(self, values: Sequence[float], mode: int = 0) -> ModeCurve:
        """Frequency and damping of flexible mode number ``mode`` (lowest first) at each of ``values``."""
        frequencies, zetas = [], []
        for value in values:
            modes = self.flexible_modes_at(value)
            if not 0 <= mode < len(modes):
                raise ValueError(f"mode must be in [0, {len(modes) - 1}] (the plant's flexible modes at "
                                 f"{self.scheduling.name} = {value:g}), got {mode!r}")
            omega, zeta = modes[mode]
            frequencies.append(omega / (2.0 * math.pi))
            zetas.append(zeta)
        return ModeCurve(tuple(float(v) for v in values), tuple(frequencies), tuple(zetas))

    def describe(self) -> list[str]:
        """Lines for ``shapefmu plant show``: the input, its laws and the lowest mode across its range."""
        s = self.scheduling
        lines = [f"  scheduling input {s.name} [{s.unit}] in [{s.minimum:g}, {s.maximum:g}], start {s.start:g}"
                 + (f": {s.description}" if s.description else "")]
        for key, rate in s.per_unit.items():
            shown = ", ".join(f"{r:g}" for r in rate) if isinstance(rate, tuple) else f"{rate:g}"
            lines.append(f"    {key} changes by {shown} [{self.plant.parameters[key].unit}] per {s.unit}")
        curve = self.mode_curve(np.linspace(s.minimum, s.maximum, 5))
        for value, f, zeta in zip(curve.values, curve.frequencies, curve.zetas):
            lines.append(f"    {s.name} = {value:<10.6g} lowest flexible mode {f:.6g} Hz, zeta {zeta:.4g}")
        return lines
