"""Scheduled shapers: an impulse shaper whose design follows a scheduling input (an added mass, a
rope length, a position), re-designed at a sample with no jump in the shaped command.

``Schedule`` is the mode as a function of the scheduling value: a table of rows (value, f, zeta),
measured at a few values (recordings at several bed loads) or computed from a plant model
(``shapefmu.plants.ScheduledPlant.mode_curve``), or a linear law f = f0 + gain * value (Marlin
FT_MOTION's dynamic frequency, with the gain set by the user; Prusa's weight adjustment is the same
line, -20 Hz at 800 g by default, held beyond its mass limit). ``ScheduledShaper`` designs a shaper of
one kind for the mode in force at each sample; how a re-design keeps the shaped command free of jumps
is derived in ``shapefmu.runtime.scheduled_shaper``, the kernel a scheduled Shaper FMU will run.

>>> import numpy as np
>>> from shapefmu.shapers import Schedule, ScheduledShaper
>>> bed = Schedule((0.0, 150.0, 300.0), (30.0, 27.98, 26.31), (0.05, 0.047, 0.044))  # grams on the bed
>>> shaper = ScheduledShaper(bed, ts=5e-4)
>>> [round(shaper.design_at(g).duration * 1e3, 2) for g in (0.0, 300.0)]  # ZV: half a damped period, ms
[16.69, 19.02]
>>> y = shaper.shape(np.ones(50), np.linspace(0.0, 300.0, 50))  # a step while the load grows
>>> bool(np.all(np.diff(y) >= 0.0)), float(y[-1])
(True, 1.0)
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from shapefmu.runtime.checks import check_positive
from shapefmu.runtime.scheduled_shaper import ModeSchedule, ScheduledShaperKernel
from shapefmu.runtime.shaper_designs import SINGLE_MODE, design_impulses
from shapefmu.shapers.impulse import ImpulseShaper


@dataclass(frozen=True)
class Schedule:
    """Rows (``values``, ``frequencies`` in Hz, ``zetas``), linear in the value between rows; beyond
    the ends the end rows hold, unless ``extrapolate`` (a law). See ``runtime.scheduled_shaper.ModeSchedule``.

    Examples
    --------
    >>> bed = Schedule((0.0, 300.0), (30.0, 26.31), (0.05, 0.044))
    >>> [round(x, 4) for x in bed.mode(150.0)]  # halfway: 28.155 Hz = 176.9031 rad/s, zeta 0.047
    [176.9031, 0.047]
    >>> law = Schedule.linear_law(30.0, -0.0125, 0.05)  # Hz per gram, Marlin's dynamic frequency
    >>> [round(x, 4) for x in law.mode(300.0)]  # 30 - 3.75 = 26.25 Hz = 164.9336 rad/s
    [164.9336, 0.05]
    """

    values: tuple[float, ...]
    frequencies: tuple[float, ...]
    zetas: tuple[float, ...]
    extrapolate: bool = False

    def __post_init__(self):
        checked = ModeSchedule(self.values, self.frequencies, self.zetas, self.extrapolate)
        object.__setattr__(self, "values", tuple(checked.values))
        object.__setattr__(self, "frequencies", tuple(checked.frequencies))
        object.__setattr__(self, "zetas", tuple(checked.zetas))

    @classmethod
    def linear_law(cls, f0: float, gain: float, zeta: float) -> Schedule:
        """f = f0 + gain * value everywhere, zeta fixed: Marlin FT_MOTION's dynamic frequency (gain in
        Hz per mm of Z or per gram of filament)."""
        law = ModeSchedule.linear_law(f0, gain, zeta)
        return cls(tuple(law.values), tuple(law.frequencies), tuple(law.zetas), extrapolate=True)

    def runtime(self) -> ModeSchedule:
        """The schedule as the runtime kernels take it."""
        return ModeSchedule(self.values, self.frequencies, self.zetas, self.extrapolate)

    def mode(self, value: float) -> tuple[float, float]:
        """``(omega rad/s, zeta)`` in force at scheduling ``value``."""
        return self.runtime().mode(value)


@dataclass(frozen=True)
class ScheduledShaper:
    """A shaper of ``kind`` (a single-mode kind of ``runtime.shaper_designs``; ``n`` and ``vtol`` as
    there) sampled at ``ts``, designed at every sample for the mode ``schedule`` puts in force; a mode
    that moves by more than ``resolution`` (relative frequency, absolute damping ratio) re-designs it.

    Examples
    --------
    >>> undamped = Schedule((0.0, 1.0), (25.0, 25.0), (0.0, 0.0))
    >>> ScheduledShaper(undamped, ts=1e-3).design_at(0.5)  # ZV, zeta 0: two halves half a period apart
    ImpulseShaper(times=(0.0, 0.02), amplitudes=(0.5, 0.5))
    """

    schedule: Schedule
    ts: float
    kind: str = "zv"
    n: int = 1
    vtol: float = 0.05
    resolution: float = 1e-4

    def __post_init__(self):
        if not isinstance(self.schedule, Schedule):
            raise ValueError(f"schedule must be a Schedule, got {type(self.schedule).__name__}")
        if self.kind not in SINGLE_MODE:
            raise ValueError(f"kind must be one of {', '.join(SINGLE_MODE)}, got {self.kind!r}")
        object.__setattr__(self, "ts", check_positive(self.ts, "ts"))
        self.kernel()  # the kernel checks n, vtol, resolution and that the first design samples at ts

    def design_at(self, value: float) -> ImpulseShaper:
        """The shaper designed for the mode in force at scheduling ``value`` (continuous time)."""
        return ImpulseShaper(*map(tuple, design_impulses(self.kind, [self.schedule.mode(value)], self.n, self.vtol)))

    def kernel(self, u0: float = 0.0, value0: float | None = None) -> ScheduledShaperKernel:
        """The per-sample kernel, the command resting at ``u0`` and the scheduling input at ``value0``
        (default: the schedule's first value) before the first sample."""
        return ScheduledShaperKernel(1.0 / self.ts, self.schedule.runtime(), self.kind, self.n, self.vtol, u0, value0,
                                     self.resolution)

    def shape(self, commands, values) -> np.ndarray:
        """Shape ``commands`` sampled at ``ts``, the scheduling input at ``values`` (one per sample, or
        one for all), the command resting at its first value before."""
        u = np.asarray(commands, dtype=float).ravel()
        if u.size == 0:
            raise ValueError("commands must hold at least one sample")
        s = np.broadcast_to(np.asarray(values, dtype=float), u.shape)
        kernel = self.kernel(float(u[0]), float(s[0]))
        return np.array([kernel.step(a, b) for a, b in zip(u.tolist(), s.tolist())])

    def to_json(self) -> str:
        schedule = self.schedule
        return json.dumps({"kind": "scheduled", "shaper": self.kind, "ts": self.ts, "n": self.n, "vtol": self.vtol,
                           "resolution": self.resolution, "values": list(schedule.values),
                           "frequencies": list(schedule.frequencies), "zetas": list(schedule.zetas),
                           "extrapolate": schedule.extrapolate})

    @classmethod
    def from_json(cls, text: str) -> ScheduledShaper:
        data = json.loads(text)
        if data.get("kind") != "scheduled":
            raise ValueError(f"JSON kind must be 'scheduled', got {data.get('kind')!r}")
        schedule = Schedule(tuple(data["values"]), tuple(data["frequencies"]), tuple(data["zetas"]),
                            bool(data["extrapolate"]))
        return cls(schedule, data["ts"], data["shaper"], data["n"], data["vtol"], data["resolution"])
