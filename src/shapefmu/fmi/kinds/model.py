"""What an FMU kind computes, apart from FMI: the base of every kind's ``Model``, and the bases of
the kinds that run a sampled FIR (``SampledFIRModel``), made of impulses (``ImpulseFIRModel``).

A ``Model`` holds the values of its FMU's variables (a dict ``name -> value`` shared with whoever
runs it: the pythonfmu slave, or the native build that designs with it) and the runtime kernels it
designs from them. The pythonfmu slave (``shapefmu.fmi.python.slave_base``) owns the FMI state
machine and calls the hooks below; the native build calls ``initialize`` once, at build time, and
writes what it designed into the C twin's ``model.c``.

Bundled into every pythonfmu FMU: standard library only.
"""

import math

from ...runtime.checks import check_finite, check_size
from ...runtime.sample_clock import FIR_SAMPLE_SECONDS, SampleClock, samples_per_python_step
from ...runtime.shaper_filter import FeedthroughFIR, StreamingShaper, grid_impulses

OK, WARNING, ERROR = 0, 1, 3  # the FMI status of a logged message


class Model:
    """Base of the kinds' models: the hooks, with what a kind that needs nothing more does."""

    interface = None          # the kind's Interface
    kernels = ()              # runtime classes that may appear in a saved FMU state
    state_attributes = ()     # attributes holding the kernels, saved and restored with the state

    def __init__(self, values, owner="", log=None):
        self.values = values
        self.owner = owner    # "<model name> <instance name>", heading logged messages
        self._log = log
        self.time = 0.0       # the FMU's time: the start time at ``initialize``, then each step's end
        self.running = False  # initialised and stepping (the pythonfmu slave's "step" phase)
        for name in self.state_attributes:
            setattr(self, name, None)

    def log(self, message, status=OK):
        if self._log is not None:
            self._log(message, status)

    def initialize(self):
        """Validate the parameters (ValueError naming the parameter, its value and the valid range)
        and design the kernels, at ``self.time``: the exit of initialisation."""

    def step(self, t, h):
        """Advance the kernels over (t, t + h] and set the outputs. Any h > 0 is honoured (hosts trim
        their last step to 1e-16 s): a sampled model takes its samples on the grid t0 + k Ts with
        ``runtime.sample_clock.SampleClock`` (made in ``initialize``, listed in ``kernels`` and
        ``state_attributes``), which counts them from the steps, never from the host's t."""
        raise NotImplementedError

    def input_changed(self, name):
        """Called after input ``name`` is set: recompute the outputs that feed through from it."""

    def output_dependencies(self):
        """``{output: [inputs it depends on at the same instant]}``, after ``initialize``."""
        return {v.name: [] for v in self.interface.variables if v.causality == "output"}

    def experiment(self):
        """The DefaultExperiment (start, stop, step) in s, after ``initialize``."""
        return 0.0, 1.0, 1e-3

    def picture(self):
        """What the FMU's icon shows of the design, after ``initialize``: strokes ``(kind, points)``
        (``shapefmu.fmi.icon``); the base draws a step."""
        return [("line", [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (3.0, 1.0)])]


class SampledFIRModel(Model):
    """Base of the kinds whose kernel is a sampled FIR with feed-through (``runtime.shaper_filter.FeedthroughFIR``,
    y = w_0 u + the committed history) stepped on the grid t0 + k Ts (``runtime.sample_clock.SampleClock``),
    input ``u``, output ``y``: the ShapeFilter, and through ``ImpulseFIRModel`` the Shaper and the
    ImpulseTrain. A kind's ``initialize`` designs, then calls ``start``."""

    kernels = (FeedthroughFIR, StreamingShaper, SampleClock)

    def start(self, fir, ts, terms):
        """Run ``fir`` at the period ``ts``; ``terms``: its non-zero taps, what a sample costs."""
        self.fir = fir
        fixed, per_term = FIR_SAMPLE_SECONDS
        self.clock = SampleClock(ts, samples_per_python_step(fixed + per_term * terms))
        self.values["y"] = fir.output(check_finite(self.values["u"], "u"))

    def input_changed(self, name):
        if self.fir is not None:
            self.values["y"] = self.fir.output(self.clock.current(self.values["u"]))

    def step(self, t, h):
        self.values["y"] = self.fir.output(self.clock.advance(t, h, self.values["u"], self.fir.commit))


class ImpulseFIRModel(SampledFIRModel):
    """Base of the kinds that run impulses (times s, amplitudes) split onto the grid k Ts
    (``runtime.shaper_filter.grid_impulses``): the Shaper and the ImpulseTrain. ``design`` holds them."""

    state_attributes = ("fir", "design", "clock")

    def start_impulses(self, times, amplitudes, ts, u0, what):
        """Run the impulses at ``ts`` from rest at ``u0``; ``what`` names the train in the error of a
        delay line over ``limits.MAX_SAMPLED_LENGTH`` samples."""
        check_size(times[-1] / ts + 1, "MAX_SAMPLED_LENGTH", f"{what}, {times[-1]:.6g} s long, sampled at Ts = {ts!r} "
                   f"s has a delay line of", "samples", "use a longer Ts")
        delays, weights = grid_impulses(times, amplitudes, ts)
        self.design = (tuple(times), tuple(amplitudes))
        self.start(FeedthroughFIR(delays, weights, u0), ts, len(delays))

    def experiment(self):
        """DefaultExperiment (start, stop, step): one sample per step, four lengths of the train."""
        ts = self.values["Ts"]
        return 0.0, ts * max(10, math.ceil(4.0 * self.design[0][-1] / ts)), ts

    def picture(self):
        """The impulses."""
        return [("stems", list(zip(*self.design)))]
