"""The STOSController FMU: shaped time-optimal closed-loop control of a rigid body (paper 002).

Wraps ``runtime.stos``: at the exit of initialisation the shaper ``kind`` is designed for the
``n_modes`` modes ``f[i]`` (Hz), ``zeta[i]`` (``runtime.shaper_designs``; ``simultaneous`` solves
eq. 20 with ``runtime.multimode``), and ``stos_curves(b, U, times, amplitudes, damping)`` computes
the switching curves (eqs. 7-16). With ``settle`` true, the linear settle law with gains ``kp``,
``kd``, ``ki`` takes over inside the region ``x_enter``, ``v_enter`` (left beyond ``x_exit``,
``v_exit``), its integrator sampled at ``Ts``.

Sampled semantics and feed-through (``runtime.sample_clock``). The law is evaluated once per
sample instant t0 + k ``Ts`` (t0 the start time) wherever the communication points fall, with the
inputs in effect at that instant (set at the last communication point at or before it, within
1e-6 Ts). Any step h > 0 is accepted; a step over more than 10^7 samples is refused (fmi2Error).
At a communication point on the sample grid the output ``u`` is the law evaluated at the inputs
set there (``target``, ``x_r``, ``x_r_dot``), so it feeds through from all three (ModelStructure
says so): setting an input recomputes ``u`` from the committed state without changing it, and
``fmi2DoStep`` commits the samples. Between samples ``u`` holds the value of the current sample,
and inputs set there are used from the next sample on. With one step per sample, the sequence of
``u`` read after setting the inputs is exactly the sequence ``STOSKernel.control`` returns when
called once per sample with those inputs.
"""

import math

from ...runtime import shaper_designs
from ...runtime.checks import check_count, check_finite, check_positive
from ...runtime.sample_clock import STOS_SAMPLE_SECONDS, SampleClock, samples_per_python_step
from ...runtime.stos import STOSKernel, stos_curves
from .interface import Interface, input_, mode_parameters, output, parameter, sampled_description
from .model import Model as _Model

MAX_MODES = 4
SETTLE_GAINS = ("kp", "kd", "ki", "x_enter", "v_enter", "x_exit", "v_exit")


INTERFACE = Interface(
    "STOSController",
    sampled_description(
        "Shaped time-optimal servomechanism (STOS, paper 002): bang-bang closed loop that spares the modes",
        "target, x_r and x_r_dot",
    ),
    (
        parameter("b", 2.7e3, "rigid-body input gain: x_r'' = -damping x_r' + b u", unit="m/s2"),
        parameter("U", 11.0, "input limit |u| <= U"),
        parameter("damping", 0.0, "rigid-body velocity damping (Kt^2/(R J) with back EMF)", unit="1/s", minimum=0.0),
        parameter("kind", "simultaneous", f"shaper the law is built from: {', '.join(shaper_designs.KINDS)}"),
        parameter("n", 1, "derivative order of zv_dn (0 = ZV, 1 = ZVD, ...)", minimum=0),
        parameter("n_modes", 2, f"number of modes, 1..{MAX_MODES}", minimum=1, maximum=MAX_MODES),
        *mode_parameters(MAX_MODES, "f", "Hz", lambda i: 1000.0 * (i + 1), 0.01),
        parameter("Ts", 1e-5, "sampling period of the control law", unit="s"),
        parameter("settle", False, "hand over to the linear settle law near the target"),
        parameter("kp", 0.0, "settle law position gain", unit="1/m"),
        parameter("kd", 0.0, "settle law velocity gain", unit="s/m"),
        parameter("ki", 0.0, "settle law integral gain", unit="1/(m.s)"),
        parameter("x_enter", 1e-6, "settle region: position error at which the settle law takes over", unit="m"),
        parameter("v_enter", 1e-3, "settle region: velocity at which the settle law takes over", unit="m/s"),
        parameter("x_exit", 2e-6, "position error beyond which the settle law lets go", unit="m"),
        parameter("v_exit", 2e-3, "velocity beyond which the settle law lets go", unit="m/s"),
        input_("target", 0.0, "target position", unit="m"),
        input_("x_r", 0.0, "measured rigid-body position", unit="m"),
        input_("x_r_dot", 0.0, "measured rigid-body velocity", unit="m/s"),
        output("u", "control input, |u| <= U"),
    ),
    command_in="target",
    command_out="u",
)


class Model(_Model):
    interface = INTERFACE
    kernels = (STOSKernel, SampleClock)
    state_attributes = ("kernel", "clock")

    def initialize(self):
        values = self.values
        ts = check_positive(values["Ts"], "Ts")
        times, amplitudes = shaper_designs.design_impulses(
            values["kind"], shaper_designs.parameter_modes(values, MAX_MODES), check_count(values["n"], "n")
        )
        curves = stos_curves(values["b"], values["U"], times, amplitudes, values["damping"])
        settle = None
        if values["settle"]:
            settle = {name: check_finite(values[name], name) for name in SETTLE_GAINS}
            settle["Ts"] = ts
        self.kernel = STOSKernel(curves, settle)
        fixed, per_impulse = STOS_SAMPLE_SECONDS
        self.clock = SampleClock(ts, samples_per_python_step(fixed + per_impulse * len(times)))
        self._preview(self._inputs())

    def _inputs(self):
        values = self.values
        return values["target"], values["x_r"], values["x_r_dot"]

    def _preview(self, inputs):
        """u for ``inputs`` from the committed state, which it leaves as it was."""
        saved = self.kernel.get_state()
        self.values["u"] = self.kernel.control(*inputs)
        self.kernel.set_state(saved)

    def output_dependencies(self):
        return {"u": ["target", "x_r", "x_r_dot"]}

    def experiment(self):
        """DefaultExperiment: 2000 samples."""
        ts = self.values["Ts"]
        return 0.0, 2000 * ts, ts

    def picture(self):
        """The rigid body's bang-bang (accelerate, then brake, each twice the shaper long) shaped by the
        law's impulses, which spare the modes: a staircase up, across and back."""
        times, amplitudes = self.kernel.curves["times"], self.kernel.curves["amplitudes"]
        half = 2.0 * times[-1]
        edges = sorted({t + shift for t in times for shift in (0.0, half, 2.0 * half)})

        def level(t):
            return sum(a * ((t >= s) - 2 * (t >= s + half) + (t >= s + 2.0 * half)) for s, a in zip(times, amplitudes))

        levels = [level(0.5 * (a + b)) for a, b in zip(edges, edges[1:])]
        steps = [point for a, b, u in zip(edges, edges[1:], levels) for point in ((a, u), (b, u))]
        return [("line", [(edges[0], 0.0), *steps, (edges[-1], 0.0)])]

    def input_changed(self, name):
        if self.kernel is not None and all(math.isfinite(self.values[n]) for n in ("target", "x_r", "x_r_dot")):
            self._preview(self.clock.current(self._inputs()))

    def step(self, t, h):
        kernel = self.kernel
        self._preview(self.clock.advance(t, h, self._inputs(), lambda inputs: kernel.control(*inputs)))
