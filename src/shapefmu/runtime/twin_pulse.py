"""The twin-pulse family of swing-free profiles (Bowling, Starr, Wood & Lumia, paper 003), standard library only.

What a ProfileGenerator or ShapeFilter FMU computes at initialisation, and what the design layer
(``shapefmu.shapers.twin_pulse``, whose module docstring lists the OCR corrections to eq. 1, 6,
18-23) calls for every design: the guards, the null placement, the offset search and the kernel are
written once, here. The design layer samples the move exactly on its grid;
``tests/test_runtime_profiles.py`` checks that those samples equal the ``motion`` played here.

The acceleration is a(t) = v_slew (TP * BC * TZ)(t): twin pulse TP (impulses 1/2 at 0 and t_TP),
unit-area boxcar BC of width t_BC, and the trapezoid's +/- impulses TZ at 0 and t_TZ (section III-A).
It is a sum of four boxcars, so its acceleration is piecewise constant and the move is returned as a
``motion.PiecewiseAcceleration``, exact at every instant. The names list the components whose nulls
are aligned; "M-" mis-aligns the first-named to omega_n - delta_omega and the last to
omega_n + delta_omega (sections III-C, III-F, III-G).
"""

import cmath
import math
from dataclasses import dataclass

from .checks import check_count, check_finite, check_omega, check_positive, check_size, check_vtol
from .motion import PiecewiseAcceleration
from .scalar_search import bisect

# Samples per period of omega_n on the default time grid.
_SAMPLES_PER_PERIOD = 1000

# Per kind: (twin pulse, boxcar, trapezoid) null at omega_n + s delta_omega, s in {-1, 0, +1}, or
# None for a component that is absent / not aligned (eq. 2-4, 7-8, 11-17, 20-21).
LAYOUT = {
    "TP": (0, None, None),
    "TP:BC": (0, 0, None),
    "M-TP:BC": (-1, +1, None),
    "M-BC:TP": (+1, -1, None),
    "BC:VR": (None, 0, None),
    "BC:TZ": (None, 0, 0),
    "M-BC:TZ": (None, -1, +1),
    "M-TZ:BC": (None, +1, -1),
    "M-BC:TZ:TP": (+1, -1, 0),
    "M-TP:TZ:BC": (-1, +1, 0),
}
KINDS = tuple(LAYOUT)
_MISALIGNED = tuple(kind for kind in LAYOUT if kind.startswith("M-"))


@dataclass(frozen=True)
class TwinPulseTiming:
    """The timing of a designed move: what the runtime's design and the design layer's profile share.

    ``null`` is k, the trapezoid's null index (eq. 13, 17) or the twin pulse's for TP:BC (eq. 3),
    0 if unused; ``trapezoid_aligned`` says whether t_TZ was chosen for a null or set to d / v.
    """

    kind: str
    omega_n: float
    delta_omega: float
    null: int
    slew_speed: float
    t_tp: float
    t_bc: float
    t_tz: float
    trapezoid_aligned: bool

    @property
    def duration(self):
        """Length of the move, t_TP + t_BC + t_TZ, s."""
        return self.t_tp + self.t_bc + self.t_tz


@dataclass(frozen=True)
class TwinPulseDesign(TwinPulseTiming):
    """A designed move: its timing, the exact motion and the sampled kernel TP * BC at ``ts``.

    ``kernel`` is TP * BC integrated over each sample period (unit area).
    """

    motion: PiecewiseAcceleration
    kernel: list
    ts: float

    def sample(self):
        """Lists (t, acceleration, velocity, position) of ``motion`` on the design layer's grid k ts."""
        return self.motion.sample(self.ts, math.ceil((self.t_tp + self.t_bc + self.t_tz) / self.ts) + 2)


def _tp(w, t_tp):
    return 0.5 * (1.0 + cmath.exp(-1j * w * t_tp))


def _bc(w, t_bc):
    # (1 - e^{-j w t}) / (j w t) = e^{-j w t / 2} sin(w t / 2) / (w t / 2), finite at w t = 0.
    half = 0.5 * w * t_bc
    return cmath.exp(-1j * half) * (math.sin(half) / half if half else 1.0)


def _tz(w, t_tz):
    return 1.0 - cmath.exp(-1j * w * t_tz)


def _null_index(distance, speed, omega_tz):
    """k = ceil(d omega_TZ / (2 pi v)) (eq. 13, 17), a ratio within rounding of an integer being it."""
    ratio = distance * omega_tz / (2.0 * math.pi * speed)
    return max(1, math.ceil(ratio - 1e-12 * ratio))


def _times(kind, omega_n, distance, speed, delta_omega, tp_null, pulse_width):
    """(t_TP, t_BC, t_TZ, k, aligned) for a kind (eq. 2-4, 7-8, 11-17, 20-21)."""
    s_tp, s_bc, s_tz = LAYOUT[kind]
    t_tp = 0.0 if s_tp is None else (2 * tp_null - 1) * math.pi / (omega_n + s_tp * delta_omega)
    t_bc = pulse_width if s_bc is None else 2.0 * math.pi / (omega_n + s_bc * delta_omega)
    if s_tz is None:
        return t_tp, t_bc, distance / speed, (tp_null if kind == "TP:BC" else 0), False
    omega_tz = omega_n + s_tz * delta_omega
    k = _null_index(distance, speed, omega_tz)
    return t_tp, t_bc, 2.0 * math.pi * k / omega_tz, k, True


def _offset_for(kind, omega_n, distance, speed, attenuation, tp_null):
    """delta_omega whose magnitude at omega_n equals ``attenuation`` (section III-C): scan, then bisect.

    The magnitude is that of the two mis-aligned components: |TP BC| (eq. 5-6), or |BC TZ| / 2
    when the trapezoid is one of them (eq. 18-19). In the triple profiles the trapezoid's null sits
    on omega_n, so the whole spectrum vanishes there whatever delta_omega; their offset is set by
    the TP:BC pair, the part the paper says acts alone while the load accelerates (section III-G).
    The magnitude is 0 at delta_omega = 0 and grows with it; a scan finds the first delta_omega
    where it exceeds the request, and bisection refines that crossing: the widest notch whose
    centre still meets the attenuation.
    """
    trapezoid_misaligned = bool(LAYOUT[kind][2])  # +1 / -1; 0 (centred) and None are excluded

    def excess(dw):
        t_tp, t_bc, t_tz, _, _ = _times(kind, omega_n, distance, speed, dw, tp_null, 0.0)
        m = abs(_tp(omega_n, t_tp) * _bc(omega_n, t_bc))
        return (m * abs(_tz(omega_n, t_tz)) / 2.0 if trapezoid_misaligned else m) - attenuation

    step = 0.5 / 500
    previous = 0.0
    for i in range(1, 501):
        current = omega_n * (i * step)
        if excess(current) > 0.0:
            return bisect(excess, previous, current, xtol=1e-14 * omega_n)
        previous = current
    raise ValueError(
        f"attenuation = {attenuation!r} is met for every delta_omega up to omega_n / 2 = {omega_n / 2:g} rad/s; "
        f"pass delta_omega directly"
    )


def _boxcars(t_tp, t_bc, t_tz, slew):
    """The acceleration v_slew (TP * BC * TZ)(t) as four boxcars of width t_BC, merged into segments."""
    starts = (0.0, t_tp, t_tz, t_tz + t_tp)
    weights = (0.5 * slew, 0.5 * slew, -0.5 * slew, -0.5 * slew)
    breaks = sorted({*starts, *(s + t_bc for s in starts)})
    levels = []
    for a, b in zip(breaks, breaks[1:]):
        middle = 0.5 * (a + b)
        levels.append(math.fsum(w / t_bc for s, w in zip(starts, weights) if s <= middle < s + t_bc))
    return PiecewiseAcceleration(breaks, levels)


def _kernel(t_tp, t_bc, ts):
    """TP * BC integrated over each sample period: a unit-area sequence at ts."""
    check_size((t_tp + t_bc) / ts + 2, "MAX_SAMPLED_LENGTH",
               f"a kernel of {t_tp + t_bc!r} s sampled at ts = {ts!r} s has", "samples", "use a longer ts")
    ramp = [
        0.5 * (min(max(k * ts, 0.0), t_bc) / t_bc) + 0.5 * (min(max(k * ts - t_tp, 0.0), t_bc) / t_bc)
        for k in range(math.ceil((t_tp + t_bc) / ts) + 1)
    ]
    return [b - a for a, b in zip(ramp, ramp[1:])]


def twin_pulse_profile(
    kind, omega_n, distance, speed, *, delta_omega=None, attenuation=None, ts=None, null=None, pulse_width=None
):
    """Design profile ``kind`` (one of ``KINDS``) for the notch omega_n, a move ``distance`` at ``speed``.

    Mis-aligned kinds need exactly one of ``delta_omega`` (rad/s, in [0, omega_n)) or
    ``attenuation`` (magnitude at omega_n, in (0, 1)). ``null`` is the twin pulse's null k of TP:BC
    (default 2, eq. 3); ``pulse_width`` the boxcar width of the classic TP and BC-free kinds
    (default ``ts``); ``ts`` the kernel's sampling period (default 2 pi / omega_n / 1000).
    """
    if kind not in LAYOUT:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    omega_n = check_omega(omega_n, "omega_n")
    distance = check_positive(distance, "distance")
    speed = check_positive(speed, "speed")
    ts = (2.0 * math.pi / omega_n) / _SAMPLES_PER_PERIOD if ts is None else check_positive(ts, "ts")
    pulse_width = ts if pulse_width is None else check_positive(pulse_width, "pulse_width")
    if kind == "TP:BC":
        tp_null = 2 if null is None else check_count(null, "null", 1)
    elif null is not None:
        raise ValueError(f"null applies to the TP:BC profile only, got null = {null!r} for {kind}")
    else:
        tp_null = 1
    if kind in _MISALIGNED:
        if (delta_omega is None) == (attenuation is None):
            raise ValueError(
                f"{kind} needs exactly one of delta_omega or attenuation, got {delta_omega!r} and {attenuation!r}"
            )
        if delta_omega is None:
            delta_omega = _offset_for(kind, omega_n, distance, speed, check_vtol(attenuation, "attenuation"), tp_null)
        delta_omega = check_finite(delta_omega, "delta_omega")
        if not 0.0 <= delta_omega < omega_n:
            raise ValueError(f"delta_omega must be in [0, omega_n) = [0, {omega_n:g}) rad/s, got {delta_omega!r}")
    else:
        delta_omega = 0.0
    t_tp, t_bc, t_tz, k, aligned = _times(kind, omega_n, distance, speed, delta_omega, tp_null, pulse_width)
    slew = distance / t_tz
    return TwinPulseDesign(
        kind, omega_n, delta_omega, k, slew, t_tp, t_bc, t_tz, aligned, _boxcars(t_tp, t_bc, t_tz, slew),
        _kernel(t_tp, t_bc, ts), ts,
    )
