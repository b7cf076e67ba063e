"""The ShapeFilter FMU: the sampled shape filters, designed at the exit of initialisation.

Parameter ``kind`` selects the family; the taps are designed by the standard-library runtime from
the mode ``f`` (Hz), ``zeta`` and the sampling period ``Ts``:

- a window filter of paper 000 (``runtime.window_filters``): ``rectangle``, ``hanning``,
  ``blackman``, ``hamming``, ``three-hanning`` (weight ``c``, section 7), and the non-symmetric
  ``differenced`` and ``convolved`` (section 8, on the window ``base``, with the paper's k1, k2),
  damping-compensated for ``zeta`` (section 3) and of robustness order ``order`` (eq. 1). The
  window length M must come out whole for ``Ts``; ``adjust_Ts`` uses the nearest period that makes
  it whole instead of failing, and the output ``Ts_used`` reports the period in force;
- a twin-pulse kernel of paper 003 (``runtime.twin_pulse``): TP * BC integrated over each sample,
  a unit-area filter with its nulls placed on ``f`` as the kind names; the M- kinds mis-align them
  by ``delta_f`` (Hz), ``null`` is TP:BC's twin-pulse null k (eq. 3), and the classic TP's pulses
  are one sample wide. The trapezoid TZ of a move is the command's own velocity pulse, so the
  kernel does not depend on a distance or a speed (the ProfileGenerator FMU plays whole moves);
- ``time-frequency`` (paper 004, ``runtime.time_frequency``): the velocity of the move whose held
  acceleration is K g_{phi,n}[k] (eq. 15), ``move_time`` = M Ts, scale n optimal by eq. (20) for
  the first resonance 2 pi f, normalised to unit gain: the shape filter behind that velocity
  profile (paper 000, Fig. 4, read backwards). Its taps are v[k] / sum v, v[k] = sum_{j < k} g[j],
  k = 0..M (v[M + 1] = sum g = 0: g is antisymmetric).

The twin-pulse and time-frequency designs are for an undamped mode and have no robustness order:
``zeta`` must be 0 and ``order`` 1 for them (an error says so rather than ignoring the value).

Sampled semantics, as the Shaper FMU (``runtime.sample_clock``). The command u is sampled at
t0 + k ``Ts_used`` (t0 the start time) wherever the communication points fall, y[k] = sum_j f[j]
u[k - j] with u resting at ``u0`` before the start: the design layer's ``SampledShaper(taps,
Ts).apply`` of the sampled command. Sample k takes the value of u in effect at its instant (set at
the last communication point at or before it, within 1e-6 Ts). Any step h > 0 is accepted; between
samples y holds y[k], and a u set there is used from the next sample on. A step over more than
10^7 samples is refused (fmi2Error).

Feed-through. y at a communication point depends on u at that point exactly when f[0] != 0
(``runtime.shaper_filter.FeedthroughFIR`` keeps f[0] u apart from the committed history): the
rectangle, Hamming and twin-pulse filters feed through; Hanning, Blackman, three-Hanning, the
non-symmetric windows on those bases and the time-frequency filter start with a zero tap and do
not. ModelStructure declares what the start values give; Blackman's f[0] is 0.42 - 0.5 + 0.08 = 0
in exact arithmetic and ~1e-19 in floating point, so a first tap within rounding of zero (1e-12 of
the largest) is taken as the zero it is.
"""

import math

from ...runtime import time_frequency, twin_pulse, window_filters
from ...runtime.checks import check_count, check_finite, check_positive, check_zeta
from ...runtime.sample_clock import FIR_SAMPLE_SECONDS, SampleClock, samples_per_python_step
from ...runtime.shaper_filter import FeedthroughFIR, StreamingShaper
from .interface import Interface, input_, output, parameter, sampled_description
from .model import Model as _Model

WINDOW_KINDS = tuple(window_filters.WINDOW_FILTERS)
KINDS = (*WINDOW_KINDS, *twin_pulse.KINDS, "time-frequency")
BASES = ("rectangle", "hanning", "blackman")
# A first tap this small relative to the largest is rounding of an exact zero (module docstring).
_ZERO_TAP = 1e-12
# The runtime designs whole moves, but neither filter depends on the move: TP * BC is fixed by the
# nulls (module docstring) and the time-frequency distance only scales K, which normalising removes.
# So any distance and speed serve.
_ANY_MOVE = 1.0


def design_taps(values):
    """(taps, ts) of the filter the parameters ``values`` (name -> value) describe."""
    kind = values["kind"]
    if kind not in KINDS:
        raise ValueError(
            f"kind must be a window filter ({', '.join(WINDOW_KINDS)}), a twin-pulse kernel "
            f"({', '.join(twin_pulse.KINDS)}) or time-frequency, got {kind!r}"
        )
    f = check_positive(values["f"], "f")
    omega = 2.0 * math.pi * f
    zeta = check_zeta(values["zeta"], "zeta")
    order = check_count(values["order"], "order", 1)
    ts = check_positive(values["Ts"], "Ts")
    if kind in WINDOW_KINDS:
        options = {"adjust_ts": values["adjust_Ts"]}
        if kind == "three-hanning":
            options["c"] = values["c"]
        elif kind in ("differenced", "convolved"):
            options["base"] = values["base"]
        try:
            return window_filters.WINDOW_FILTERS[kind](omega, zeta, ts, order, **options)
        except ValueError as error:
            if "adjust_ts" not in str(error):
                raise
            # The runtime speaks of its arguments; say which parameters of this FMU they are.
            raise ValueError(f"{error} (here: the parameters Ts and adjust_Ts)") from None
    if zeta != 0.0 or order != 1:
        raise ValueError(
            f"the {kind} filter is designed for an undamped mode and has no robustness order: zeta must be 0 and "
            f"order 1, got zeta = {zeta!r}, order = {order!r}"
        )
    if kind == "time-frequency":
        design = time_frequency.time_frequency_profile(omega, ts, values["move_time"], _ANY_MOVE)
        velocity = [math.fsum(design.kernel[:k]) for k in range(len(design.kernel))]
        total = math.fsum(velocity)
        return [v / total for v in velocity], ts
    delta_f = check_finite(values["delta_f"], "delta_f")
    options = {}
    if kind.startswith("M-"):
        if not 0.0 <= delta_f < f:
            raise ValueError(f"delta_f must be in [0, f) = [0, {f:g}) Hz, got {delta_f!r}")
        options["delta_omega"] = 2.0 * math.pi * delta_f
    elif delta_f != 0.0:
        raise ValueError(f"delta_f mis-aligns the M- twin-pulse kinds only; {kind} needs delta_f = 0, got {delta_f!r}")
    if kind == "TP:BC":
        options["null"] = values["null"]
    design = twin_pulse.twin_pulse_profile(kind, omega, _ANY_MOVE, _ANY_MOVE, ts=ts, **options)
    return design.kernel, ts


INTERFACE = Interface(
    "ShapeFilter",
    sampled_description(
        "Sampled shape filter (window filters of order n, twin-pulse kernels, time-frequency), designed from its "
        "parameters", "u", "Ts_used"
    ),
    (
        parameter("kind", "hanning", f"filter design: {', '.join(KINDS)}"),
        parameter("f", 10.0, "natural frequency of the mode (time-frequency: its first resonance)", unit="Hz"),
        parameter("zeta", 0.0, "damping ratio of the mode, in [0, 1); window filters only (others need 0)",
                  minimum=0.0),
        parameter("order", 1, "robustness order n of a window filter: its n-fold self-convolution (eq. 1)", minimum=1),
        parameter("Ts", 1e-3, "sampling period of the filter: u is sampled at startTime + k*Ts", unit="s"),
        parameter("adjust_Ts", False, "window filters: use the nearest Ts that makes the window length whole"),
        parameter("c", 0.25, "weight C of the side Hanning windows of three-hanning (section 7), >= 0", minimum=0.0),
        parameter("base", "hanning", f"base window of differenced and convolved: {', '.join(BASES)}"),
        parameter("delta_f", 0.0, "null mis-alignment of the M- twin-pulse kinds, in [0, f)", unit="Hz", minimum=0.0),
        parameter("null", 2, "null index k of the TP:BC twin pulse (eq. 3)", minimum=1),
        parameter("move_time", 0.1, "time-frequency move time M*Ts, a whole number >= 2 of Ts", unit="s"),
        parameter("u0", 0.0, "command before the start time (the filter starts at rest on it)"),
        input_("u", 0.0, "command to shape"),
        output("y", "shaped command: the taps times the delayed command samples"),
        output("Ts_used", "sampling period in force: Ts, or the adjusted one (adjust_Ts)", unit="s"),
    ),
    command_in="u",
    command_out="y",
)


class Model(_Model):
    interface = INTERFACE
    kernels = (FeedthroughFIR, StreamingShaper, SampleClock)
    state_attributes = ("fir", "taps", "clock")

    def initialize(self):
        values = self.values
        u0 = check_finite(values["u0"], "u0")
        taps, ts = design_taps(values)
        if abs(taps[0]) <= _ZERO_TAP * max(abs(w) for w in taps):
            taps = [0.0, *taps[1:]]
        self.taps = tuple(taps)
        self.fir = FeedthroughFIR.from_taps(taps, u0)
        fixed, per_term = FIR_SAMPLE_SECONDS
        terms = sum(1 for w in taps if w != 0.0)
        self.clock = SampleClock(ts, samples_per_python_step(fixed + per_term * terms))
        values["Ts_used"] = ts
        values["y"] = self.fir.output(check_finite(values["u"], "u"))

    def output_dependencies(self):
        return {"y": ["u"] if self.fir.w0 != 0.0 else [], "Ts_used": []}

    def experiment(self):
        """DefaultExperiment (start, stop, step): one sample per step, four filter lengths."""
        ts = self.values["Ts_used"]
        return 0.0, ts * max(10, 4 * len(self.taps)), ts

    def picture(self):
        """The filter's taps."""
        return [("stems", list(enumerate(self.taps)))]

    def input_changed(self, name):
        if self.fir is not None:
            self.values["y"] = self.fir.output(self.clock.current(self.values["u"]))

    def step(self, t, h):
        self.values["y"] = self.fir.output(self.clock.advance(t, h, self.values["u"], self.fir.commit))
