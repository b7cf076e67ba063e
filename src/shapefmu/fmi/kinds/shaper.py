"""The Shaper FMU: any impulse shaper, single or multi-mode, designed at the exit of initialisation.

Parameters: ``kind`` (zv, zvd, zvdd, zv_dn, mzv, um_zv, ei, ei2, ei3, simultaneous), ``n``
(derivative order of zv_dn), ``vtol`` (tolerable vibration of ei, ei2, ei3), ``n_modes`` and
``f[i]`` (Hz), ``zeta[i]`` for i = 1..4, ``Ts`` the sampling period of the filter, ``u0`` the
command before the start time. The design is ``runtime.shaper_designs.design_impulses``: single-mode
kinds given several modes are convolved (paper 002's convolution method); ``simultaneous`` solves
paper 002's eq. (20) for all modes at once with ``runtime.multimode``. Input ``u``, output ``y``.

Sampled semantics (``runtime.sample_clock``). The command is sampled at t0 + k Ts (t0 the start
time), wherever the communication points fall; impulses off the grid are split onto it
(``runtime.shaper_filter.grid_impulses``), so y[k] = sum_d w_d u[k - d], exactly the design layer's
``ImpulseShaper.on_grid(Ts).apply`` of the sampled command. Sample k takes the value of u in effect
at t0 + k Ts: the one set at the last communication point at or before it (within 1e-6 Ts). Any
step h > 0 is accepted, 1e-16 s or 0.8 Ts alike; between samples y holds y[k], and a u set there
is used from the next sample on. A step over more than 10^7 samples is refused (fmi2Error).

Feed-through. Every impulse shaper has its first impulse at t = 0, so y at a communication point
on the sample grid depends on u at that same point: y = w_0 u + r, r = sum_{d >= 1} w_d u[k - d].
ModelStructure declares the dependency, and setting u there updates y at once. ``runtime.shaper_filter.FeedthroughFIR``
keeps the history part r apart, a StreamingShaper on the taps d >= 1 shifted by one sample:
stepping it with u[k] when the step commits u[k] returns r for the next sample, so nothing is ever
un-done.
"""

import math

from ...runtime import shaper_designs
from ...runtime.checks import aliased_modes, check_count, check_finite, check_positive, check_size, check_vtol
from ...runtime.sample_clock import FIR_SAMPLE_SECONDS, SampleClock, samples_per_python_step
from ...runtime.shaper_filter import FeedthroughFIR, StreamingShaper, grid_impulses
from .interface import Interface, input_, mode_parameters, output, parameter, sampled_description
from .model import WARNING, Model as _Model

MAX_MODES = 4
KINDS = shaper_designs.KINDS

INTERFACE = Interface(
    "Shaper",
    sampled_description(
        "Impulse shaper (ZV family, MZV, UM-ZV, EI family, simultaneous multi-mode), designed from its parameters", "u"
    ),
    (
        parameter("kind", "zvd", f"shaper design: {', '.join(KINDS)}"),
        parameter("n", 1, "derivative order of zv_dn (0 = ZV, 1 = ZVD, ...)", minimum=0),
        parameter("vtol", 0.05, "tolerable residual vibration of ei, ei2, ei3, in (0, 0.25]", maximum=0.25),
        parameter("n_modes", 1, f"number of modes used, 1..{MAX_MODES}", minimum=1, maximum=MAX_MODES),
        *mode_parameters(MAX_MODES, "f", "Hz", lambda i: 10.0 * i),
        parameter("Ts", 1e-3, "sampling period of the filter: u is sampled at startTime + k*Ts", unit="s"),
        parameter("u0", 0.0, "command before the start time (the filter starts at rest on it)"),
        input_("u", 0.0, "command to shape"),
        output("y", "shaped command: sum of the impulse amplitudes times the delayed command"),
    ),
    command_in="u",
    command_out="y",
)


def mode_start_values(modes_hz):
    """The start values of a Shaper (or STOSController) for the modes ``modes_hz``, (f Hz, zeta)
    pairs: ``n_modes``, ``f[i]`` and ``zeta[i]``.

    >>> mode_start_values([(2000.0, 0.01), (3000.0, 0.01)])["f[2]"]
    3000.0
    """
    if not 1 <= len(modes_hz) <= MAX_MODES:
        raise ValueError(f"modes must hold 1 to {MAX_MODES} (f Hz, zeta) pairs, got {len(modes_hz)}")
    values = {"n_modes": len(modes_hz)}
    for i, (f, zeta) in enumerate(modes_hz, start=1):
        values[f"f[{i}]"] = f
        values[f"zeta[{i}]"] = zeta
    return values


class Model(_Model):
    interface = INTERFACE
    kernels = (FeedthroughFIR, StreamingShaper, SampleClock)
    state_attributes = ("fir", "design", "clock")

    def initialize(self):
        values = self.values
        vtol = check_vtol(values["vtol"])
        n = check_count(values["n"], "n", minimum=0)
        ts = check_positive(values["Ts"], "Ts")
        u0 = check_finite(values["u0"], "u0")
        modes = shaper_designs.parameter_modes(values, MAX_MODES)
        times, amplitudes = shaper_designs.design_impulses(values["kind"], modes, n, vtol)
        check_size(times[-1] / ts + 1, "MAX_SAMPLED_LENGTH", f"the {values['kind']} shaper, {times[-1]:.6g} s long, "
                   f"sampled at Ts = {ts!r} s has a delay line of", "samples", "use a longer Ts")
        self._warn_above_nyquist(modes, ts)
        delays, weights = grid_impulses(times, amplitudes, ts)
        self.design = (tuple(times), tuple(amplitudes))
        self.fir = FeedthroughFIR(delays, weights, u0)
        fixed, per_term = FIR_SAMPLE_SECONDS
        self.clock = SampleClock(ts, samples_per_python_step(fixed + per_term * len(delays)))
        values["y"] = self.fir.output(check_finite(values["u"], "u"))

    def _warn_above_nyquist(self, modes, ts):
        """A mode at or above the Nyquist frequency of Ts is left ringing: say so through the logger."""
        for i in aliased_modes(modes, ts):
            omega, zeta = modes[i]
            self.log(f"{self.owner}: mode f[{i + 1}] = {self.values[f'f[{i + 1}]']!r} Hz is "
                     f"at or above the Nyquist frequency 1/(2 Ts) = {0.5 / ts:.6g} Hz of Ts = {ts!r} s: the sampled "
                     f"shaper cannot cancel it and leaves its vibration (up to all of it); use Ts < "
                     f"{math.pi / (omega * math.sqrt(1.0 - zeta * zeta)):.6g} s", WARNING)

    def output_dependencies(self):
        return {"y": ["u"] if self.fir.w0 != 0.0 else []}

    def experiment(self):
        """DefaultExperiment (start, stop, step): one sample per step, four shaper lengths."""
        ts = self.values["Ts"]
        return 0.0, ts * max(10, math.ceil(4.0 * self.design[0][-1] / ts)), ts

    def picture(self):
        """The impulses the shaper is designed with."""
        return [("stems", list(zip(*self.design)))]

    def input_changed(self, name):
        if self.fir is not None:
            self.values["y"] = self.fir.output(self.clock.current(self.values["u"]))

    def step(self, t, h):
        self.values["y"] = self.fir.output(self.clock.advance(t, h, self.values["u"], self.fir.commit))
