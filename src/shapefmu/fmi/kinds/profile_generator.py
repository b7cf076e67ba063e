"""The ProfileGenerator FMU: rest-to-rest position, velocity and acceleration profiles.

Parameter ``profile`` selects the family, designed at the exit of initialisation by runtime code:

- a twin-pulse kind of paper 003 (``TP``, ``TP:BC``, ``M-TP:BC``, ..., ``runtime.twin_pulse``) for
  the notch ``omega_n``, ``distance`` and ``speed``; mis-aligned kinds take ``delta_omega`` (rad/s)
  or, when ``attenuation`` > 0, find it for that attenuation; ``null`` is TP:BC's k; the classic
  TP's pulses are ``Ts`` wide;
- ``time-frequency`` (paper 004, ``runtime.time_frequency``): first resonance ``omega_n``, sampling
  period ``Ts``, ``move_time`` (a whole number of samples), ``distance``; the scale n is optimised
  (eq. 20) unless ``optimise_scale`` is false, then it is ``scale``;
- ``bang-bang`` (paper 002, eq. 2, 4, 21; ``runtime.shaped_bang_bang``): the rigid-body
  bang-bang over ``distance`` at ``acceleration_limit`` (bang-coast-bang if ``speed`` > 0 limits it),
  convolved with the shaper ``shaper`` (``none`` or a kind of ``runtime.shaper_designs``) for
  ``n_modes`` modes ``omega[i]`` (rad/s), ``zeta[i]``.

Start. The move starts at ``t_start`` (s), or earlier at the first communication point where the
input ``start`` is >= 0.5 (a rising start latches); a negative ``t_start`` waits for the input.

Outputs at a communication point are the exact values of the move at the time since its start,
counted from the steps the host took (``runtime.sample_clock.StepTime``, so that a start time of
1.7e9 plays the same move as 0; ``runtime.motion.PiecewiseAcceleration.state``): position and
velocity are continuous, the
acceleration is right-continuous. Setting ``start`` high starts the move at that instant, where the
acceleration jumps from 0 to its first level: ModelStructure declares that acceleration depends on
``start``; position and velocity start at 0 and do not.
"""

from ...runtime import shaped_bang_bang, shaper_designs, time_frequency, twin_pulse
from ...runtime.checks import check_finite, check_positive
from ...runtime.motion import PiecewiseAcceleration
from ...runtime.sample_clock import StepTime
from .interface import Interface, input_, mode_parameters, output, parameter
from .model import Model as _Model

PROFILES = (*twin_pulse.KINDS, "time-frequency", "bang-bang")
SHAPERS = ("none", *shaper_designs.KINDS)
MAX_MODES = 4


def design_motion(values):
    """The PiecewiseAcceleration the parameters ``values`` (name -> value) describe."""
    profile = values["profile"]
    distance = check_positive(values["distance"], "distance")
    if profile in twin_pulse.KINDS:
        attenuation = check_finite(values["attenuation"], "attenuation")
        options = {"attenuation": attenuation} if attenuation > 0.0 else {"delta_omega": values["delta_omega"]}
        if not profile.startswith("M-"):
            options = {}
        if profile == "TP:BC":
            options["null"] = values["null"]
        design = twin_pulse.twin_pulse_profile(
            profile, values["omega_n"], distance, values["speed"], ts=values["Ts"], **options
        )
        return design.motion
    if profile == "time-frequency":
        scale = None if values["optimise_scale"] else check_finite(values["scale"], "scale")
        return time_frequency.time_frequency_profile(
            values["omega_n"], values["Ts"], values["move_time"], distance, scale
        ).motion
    if profile == "bang-bang":
        speed = check_finite(values["speed"], "speed")
        if speed < 0.0:
            raise ValueError(f"speed must be >= 0 (0: no speed limit), got {speed!r}")
        times, amplitudes = [0.0], [1.0]
        if values["shaper"] != "none":
            times, amplitudes = shaper_designs.design_impulses(
                values["shaper"], shaper_designs.parameter_modes(values, MAX_MODES, "omega", hertz=False), values["n"]
            )
        return shaped_bang_bang.shaped_bang_bang(distance, values["acceleration_limit"], times, amplitudes, speed or None)
    raise ValueError(f"profile must be one of {', '.join(PROFILES)}, got {profile!r}")


INTERFACE = Interface(
    "ProfileGenerator",
    "Rest-to-rest motion profiles: twin-pulse family, time-frequency, shaped bang-bang",
    (
        parameter("profile", "BC:TZ", f"profile family: {', '.join(PROFILES)}"),
        parameter("distance", 1.7, "move distance", unit="m"),
        parameter("speed", 0.7, "slew speed (twin-pulse); speed limit of the bang-bang, 0 for none", unit="m/s",
                  minimum=0.0),
        parameter("acceleration_limit", 1.0, "acceleration limit of the bang-bang", unit="m/s2"),
        parameter("omega_n", 3.5, "notch frequency (twin-pulse) or first resonance (time-frequency)", unit="rad/s"),
        parameter("delta_omega", 0.2, "null mis-alignment of the M- twin-pulse kinds (if attenuation is 0)", unit="rad/s"),
        parameter("attenuation", 0.05, "magnitude at omega_n the M- kinds are designed for; 0 uses delta_omega",
                  minimum=0.0),
        parameter("null", 2, "null index k of the TP:BC twin pulse (eq. 3)", minimum=1),
        parameter("Ts", 1e-3, "sampling period of the profile's kernel (time-frequency: of the profile)", unit="s"),
        parameter("move_time", 2.5e-3, "time-frequency move time, a whole number of Ts", unit="s"),
        parameter("optimise_scale", True, "time-frequency: choose the scale n by eq. (20)"),
        parameter("scale", 11.0, "time-frequency scale n when optimise_scale is false"),
        parameter("shaper", "none", f"shaper convolved with the bang-bang: {', '.join(SHAPERS)}"),
        parameter("n", 1, "derivative order of the zv_dn shaper", minimum=0),
        parameter("n_modes", 1, f"number of modes of the bang-bang's shaper, 1..{MAX_MODES}", minimum=1, maximum=MAX_MODES),
        *mode_parameters(MAX_MODES, "omega", "rad/s", lambda i: 10.0 * i, mode="shaper mode"),
        parameter("t_start", 0.0, "start time of the move; negative: wait for the start input", unit="s"),
        input_("start", 0.0, "starts the move at the communication point where it is >= 0.5"),
        output("position", "position of the move", unit="m"),
        output("velocity", "velocity of the move", unit="m/s"),
        output("acceleration", "acceleration of the move (right-continuous)", unit="m/s2"),
    ),
    command_in=None,
    command_out="position",
)


class Model(_Model):
    interface = INTERFACE
    kernels = (PiecewiseAcceleration, StepTime)
    # started_at and the time the outputs are read at are times since t0, the start time
    state_attributes = ("motion", "started_at", "t0", "elapsed")

    def initialize(self):
        if self.values["shaper"] not in SHAPERS:
            raise ValueError(f"shaper must be one of {', '.join(SHAPERS)}, got {self.values['shaper']!r}")
        check_finite(self.values["t_start"], "t_start")
        self.motion = design_motion(self.values)
        self.t0, self.elapsed, self.started_at = self.time, StepTime(), None
        self._maybe_start(0.0)
        self._update(0.0)

    def _scheduled(self, elapsed):
        """Whether the move's t_start (an absolute time; negative: none) has come ``elapsed`` after t0."""
        t_start = self.values["t_start"]
        return 0.0 <= t_start and t_start - self.t0 <= elapsed

    def _maybe_start(self, elapsed):
        if self.started_at is not None:
            return
        if self.values["start"] >= 0.5:
            self.started_at = elapsed
        elif self._scheduled(elapsed):
            self.started_at = self.values["t_start"] - self.t0

    def _update(self, elapsed):
        position, velocity, acceleration = (
            (0.0, 0.0, 0.0) if self.started_at is None else self.motion.state(elapsed - self.started_at)
        )
        self.values["position"], self.values["velocity"], self.values["acceleration"] = position, velocity, acceleration

    def output_dependencies(self):
        return {"position": [], "velocity": [], "acceleration": ["start"]}

    def experiment(self):
        """DefaultExperiment: the move and a fifth more, in 1000 steps."""
        start = max(self.values["t_start"], 0.0)
        stop = start + 1.2 * max(self.motion.breaks[-1], 1e-9)
        return 0.0, stop, stop / 1000.0

    def picture(self):
        """The position over the move."""
        end = self.motion.breaks[-1]
        return [("line", [(end * k / 64, self.motion.state(end * k / 64)[0]) for k in range(65)])]

    def input_changed(self, name):
        if self.running and self.started_at is None and self.values["start"] >= 0.5:
            self.started_at = self.elapsed.value()
            self._update(self.started_at)

    def step(self, t, h):
        self._maybe_start(self.elapsed.value())
        self.elapsed.add(h)
        elapsed = self.elapsed.value()
        if self.started_at is None and self._scheduled(elapsed):
            self.started_at = self.values["t_start"] - self.t0
        self._update(elapsed)
