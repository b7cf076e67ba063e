"""The ScheduledShaper FMU: an impulse shaper re-designed for the mode a scheduling input puts in force.

Parameters: the schedule, ``n_rows`` rows of ``values[i]`` (the scheduling input's value), ``f[i]``
(Hz) and ``zeta[i]``, linear between rows and held beyond them unless ``extrapolate`` (then the end
rows continue: a law, Marlin FT_MOTION's f = f0 + k z of two rows); ``kind`` (a single-mode shaper:
zv, zvd, zvdd, zv_dn, mzv, ei, ei2, ei3, ...), ``n``, ``vtol`` as the Shaper FMU's; ``resolution``
(a new design when the mode's frequency moved by more than that fraction or its damping ratio by
more than that amount); ``Ts`` and ``u0``. Inputs ``u`` (the command) and ``scheduling`` (its start
value is the scheduling value before the start time); output ``y``.

Each sample runs ``runtime.scheduled_shaper.ScheduledShaperKernel``: every change of the command is
shaped by the shaper designed for the scheduling value in force at the sample it was commanded, so
the output equals at every sample that change-by-change sum, and a re-design moves nothing by itself
(no jump; derived in the kernel's module). Sampled semantics as the Shaper FMU's
(``runtime.sample_clock``): both inputs are sampled at t0 + k Ts, as one pair.

Feed-through: y at a sample is the output if the command held plus the first impulse of the design
for the scheduling value set there times the command's change, so it depends on both inputs at once
(``ScheduledShaperKernel.output``); setting either updates y without taking the sample.
"""

import math

from ...runtime.checks import check_count, check_finite, check_positive, check_vtol
from ...runtime.sample_clock import SampleClock, samples_per_python_step
from ...runtime.scheduled_shaper import CommandSegment, ModeFollowingShaper, ModeSchedule, ScheduledShaperKernel
from ...runtime.shaper_designs import KINDS
from .interface import Interface, input_, output, parameter, redesigned_shaper_parameters, sampled_description
from .model import Model as _Model

MAX_ROWS = 8
# A sample that re-designs (the scheduling input moved) costs a design, measured at 26 us (ZVD) to
# 36 us (EI) with grid_impulses, plus the sums over the designs in flight: 50 us bounds a step's samples.
SAMPLE_SECONDS = 50e-6


def _rows():
    """values[i], f[i], zeta[i] of the schedule's rows, i = 1..MAX_ROWS: the printer bed of
    models/printer_bed.toml by default (1 kg at 30 Hz, zeta 0.05, gaining 300 g: 26.3 Hz)."""
    variables = []
    for i in range(1, MAX_ROWS + 1):
        grams = 300.0 * (i - 1) / (MAX_ROWS - 1)
        scale = math.sqrt(1.0 + grams / 1000.0)
        variables += [
            parameter(f"values[{i}]", grams, f"scheduling value of row {i} (strictly increasing over the rows used)"),
            parameter(f"f[{i}]", 30.0 / scale, f"natural frequency of the mode at row {i}", unit="Hz"),
            parameter(f"zeta[{i}]", 0.05 / scale, f"damping ratio of the mode at row {i}, in [0, 1)", minimum=0.0),
        ]
    return tuple(variables)


INTERFACE = Interface(
    "ScheduledShaper",
    sampled_description(
        "Impulse shaper re-designed for the mode its scheduling input puts in force (a table of value -> f, zeta), "
        "every change of the command shaped by the design in force when it was commanded, with no jump at a "
        "re-design", "u and scheduling"
    ),
    (
        *redesigned_shaper_parameters(KINDS),
        parameter("n_rows", MAX_ROWS, f"rows of the schedule used, 1..{MAX_ROWS}", minimum=1, maximum=MAX_ROWS),
        *_rows(),
        parameter("extrapolate", False, "continue the end rows beyond the table (a linear law) instead of holding them"),
        parameter("resolution", 1e-4, "re-design when the mode's frequency moved by more than this fraction, or its "
                  "damping ratio by more than this, from the design in force (0: at every change)", minimum=0.0),
        parameter("Ts", 1e-3, "sampling period of the filter: u and scheduling are sampled at startTime + k*Ts",
                  unit="s"),
        parameter("u0", 0.0, "command before the start time (the filter starts at rest on it)"),
        input_("u", 0.0, "command to shape"),
        input_("scheduling", 0.0, "scheduling value (an added mass, a position, a rope length) whose mode the "
               "shaper is designed for, in the unit of the table's values"),
        output("y", "shaped command: each change of u shaped by the design for the scheduling value then in force"),
    ),
    command_in="u",
    command_out="y",
)


def schedule_start_values(values, frequencies, zetas, extrapolate=False):
    """The start values of a ScheduledShaper for the schedule rows ``values`` -> (``frequencies`` Hz,
    ``zetas``): ``n_rows``, ``values[i]``, ``f[i]``, ``zeta[i]``, ``extrapolate``.

    >>> schedule_start_values([0.0, 300.0], [30.0, 26.3], [0.05, 0.044])["f[2]"]
    26.3
    """
    rows = len(values)
    if not 1 <= rows <= MAX_ROWS or len(frequencies) != rows or len(zetas) != rows:
        raise ValueError(f"the schedule must hold 1 to {MAX_ROWS} rows of value, f and zeta, got {len(values)}, "
                         f"{len(frequencies)} and {len(zetas)}")
    start = {"n_rows": rows, "extrapolate": bool(extrapolate)}
    for i, (value, f, zeta) in enumerate(zip(values, frequencies, zetas), start=1):
        start |= {f"values[{i}]": float(value), f"f[{i}]": float(f), f"zeta[{i}]": float(zeta)}
    return start


class Model(_Model):
    interface = INTERFACE
    kernels = (ScheduledShaperKernel, ModeFollowingShaper, ModeSchedule, CommandSegment, SampleClock)
    state_attributes = ("kernel", "clock")

    def initialize(self):
        values = self.values
        rows = check_count(values["n_rows"], "n_rows", minimum=1)
        if rows > MAX_ROWS:
            raise ValueError(f"n_rows must be in [1, {MAX_ROWS}], got {rows}")
        ts = check_positive(values["Ts"], "Ts")
        schedule = ModeSchedule([values[f"values[{i}]"] for i in range(1, rows + 1)],
                                [values[f"f[{i}]"] for i in range(1, rows + 1)],
                                [values[f"zeta[{i}]"] for i in range(1, rows + 1)], values["extrapolate"])
        self.kernel = ScheduledShaperKernel(
            1.0 / ts, schedule, values["kind"], check_count(values["n"], "n", minimum=0), check_vtol(values["vtol"]),
            check_finite(values["u0"], "u0"), check_finite(values["scheduling"], "scheduling"), values["resolution"])
        self.clock = SampleClock(ts, samples_per_python_step(SAMPLE_SECONDS))
        values["y"] = self.kernel.output(values["u"], values["scheduling"])

    def _commit(self, sample):
        self.kernel.step(*sample)

    def _inputs(self):
        return self.values["u"], self.values["scheduling"]

    def output_dependencies(self):
        return {"y": ["u", "scheduling"]}

    def experiment(self):
        """DefaultExperiment (start, stop, step): one sample per step, four lengths of the first design."""
        ts = self.values["Ts"]
        return 0.0, ts * max(10, 4 * self.kernel.shaper.span), ts

    def picture(self):
        """The impulses of the design at the scheduling start value, on the sample grid."""
        ts = self.values["Ts"]
        return [("stems", [(d * ts, w) for d, w in self.kernel.shaper.taps])]

    def input_changed(self, name):
        if self.kernel is not None:
            self.values["y"] = self.kernel.output(*self.clock.current(self._inputs()))

    def step(self, t, h):
        self.values["y"] = self.kernel.output(*self.clock.advance(t, h, self._inputs(), self._commit))
