"""The twin-pulse family of swing-free motion profiles (Bowling, Starr, Wood & Lumia, paper 003).

Every profile is the acceleration ``a(t) = v_slew * (TP * BC * TZ)(t)``, a convolution of up to three
unit kernels, so its spectrum is the product of theirs (paper 003, section III-A):

- TP, twin pulse: impulses 1/2 at 0 and t_TP; TP(w) = (1 + e^{-j w t_TP}) / 2, nulls at
  w t_TP = (2m - 1) pi. A null at w_TP on its k-th null needs t_TP = (2k - 1) pi / w_TP (eq. 3).
- BC, boxcar of unit area over t_BC; BC(w) = (1 - e^{-j w t_BC}) / (j w t_BC), nulls at
  w t_BC = 2 pi m. Its first null at w_BC needs t_BC = 2 pi / w_BC (eq. 2).
- TZ, the trapezoid's +/- impulses at 0 and t_TZ; TZ(w) = 1 - e^{-j w t_TZ}, nulls at
  w t_TZ = 2 pi m. It turns the velocity step of TP * BC into a rest-to-rest move of distance
  d = v_slew t_TZ (eq. 12).

The names list the components whose nulls are aligned; "M-" mis-aligns them by delta_omega, the
first-named component taking the lower null omega_n - delta_omega and the last the higher one
(section III-C: "for the M-TP:BC the twin pulse null point has the lower frequency"; section III-F:
M-BC:TZ has t_BC = 2 pi / (omega_n - delta_omega)). In the triple profiles the trapezoid sits at
omega_n (section III-G). Where no TZ is named, the trapezoid is not aligned: t_TZ = d / v exactly.

OCR / print errors found by checking the paper's formulas against the constructed spectra (the
construction is trusted, see tests/test_twin_pulse.py):

- eq. (1) lacks the factor omega_n of eq. (5)-(6): |TP BC| = omega_n / (4 pi w) |...|;
- eq. (6): the boxcar term must read e^{-2 j pi w / (omega_n - delta_omega)};
- eq. (18)-(19): the last exponent lacks the factor omega_n of the others and its denominator is
  omega_n^2 - delta_omega^2 (as in eq. 15-16); the prefactor of eq. (19) is omega_n + delta_omega
  (the boxcar's null);
- eq. (20)-(21) are swapped with respect to the naming above: M-TP:TZ:BC (TP low, BC high) is the
  shorter one, pi (3 omega_n - delta_omega) / (omega_n^2 - delta_omega^2) + 2 pi k / omega_n, as eq.
  (22) (TP at omega_n - delta_omega, BC at omega_n + delta_omega) confirms;
- eq. (22)-(23) place the trapezoid off omega_n and eq. (23) repeats eq. (22)'s twin pulse; with the
  trapezoid at omega_n (section III-G) eq. (22) is |TP BC TZ| (no 1/2, unlike eq. 18-19);
- the experiment's slew 0.4735 m/s (section IV, "Equation 16, k = 2") is eq. (14) with the trapezoid
  at omega_n: d omega_n / (2 pi k).

The magnitudes of eq. (18)-(19) divide TZ by 2 (its peak); :meth:`TwinPulseProfile.magnitude`
follows them for every kind: |TP| |BC| |TZ| / 2 for the kinds that align a trapezoid and |TP| |BC|
for the others, each factor peaking at 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import bisect

from shapefmu.runtime.checks import check_count, check_finite, check_omega, check_positive, check_vtol
from shapefmu.runtime.twin_pulse import LAYOUT
from shapefmu.shapers.profile import MotionProfile
from shapefmu.shapers.sampled import SampledShaper

# Samples per period of omega_n on the default time grid.
_SAMPLES_PER_PERIOD = 1000


@dataclass(frozen=True)
class TwinPulseProfile:
    """A designed twin-pulse-family move and its sampled profile.

    Attributes
    ----------
    kind : str
        One of :data:`TWIN_PULSE_PROFILES`.
    omega_n, delta_omega : float
        Notch frequency and mis-alignment offset, rad/s (0 when aligned).
    null : int
        k: the trapezoid's null index (eq. 13, 17), or the twin pulse's for TP:BC (eq. 3); 0 if unused.
    slew_speed : float
        Actual slew speed d / t_TZ (eq. 14, 16); the velocity reaches it only if t_TZ >= the
        kernel length (otherwise the two ramps overlap; the move still covers d).
    t_tp, t_bc, t_tz : float
        Interpulse time, boxcar width and trapezoid pulse spacing, s (t_tp = 0 without a twin pulse).
    trapezoid_aligned : bool
        Whether t_TZ was chosen for a null (the TZ kinds) or set to d / v.
    profile : MotionProfile
        Exact v, p at t[k] = k ts, mean a over each sample period; its kernel is TP * BC
        integrated over each sample period.
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
    profile: MotionProfile

    @property
    def kernel_length(self) -> float:
        """Length of TP * BC (eq. 4, 7, 8); add t_tz for the whole move (eq. 12, 15, 16, 20, 21)."""
        return self.t_tp + self.t_bc

    @property
    def duration(self) -> float:
        return self.kernel_length + self.t_tz

    def spectrum(self, omega) -> np.ndarray:
        """Acceleration spectrum per unit slew speed, TP(w) BC(w) TZ(w), exact and vectorised."""
        w = np.asarray(omega, dtype=float)
        return _tp(w, self.t_tp) * _bc(w, self.t_bc) * _tz(w, self.t_tz)

    def magnitude(self, omega) -> np.ndarray:
        """The paper's normalised magnitude: |TP BC| (and |TZ| / 2 where a trapezoid is aligned)."""
        w = np.asarray(omega, dtype=float)
        m = np.abs(_tp(w, self.t_tp) * _bc(w, self.t_bc))
        return m * np.abs(_tz(w, self.t_tz)) / 2.0 if self.trapezoid_aligned else m

    def residual_swing(self, omega, gravity: float = 9.81) -> np.ndarray:
        """Swing amplitude (rad) left on a linearised pendulum of natural frequency ``omega``.

        theta'' + omega^2 theta = -a(t) / L with L = gravity / omega^2; after the move the swing
        amplitude is |int a(t) e^{j omega t} dt| / (L omega) = omega v_slew |TP BC TZ| / gravity.
        """
        w = np.asarray(omega, dtype=float)
        return w * self.slew_speed * np.abs(self.spectrum(w)) / check_positive(gravity, "gravity")


def _tp(w, t_tp):
    return 0.5 * (1.0 + np.exp(-1j * w * t_tp))


def _bc(w, t_bc):
    # (1 - e^{-j w t}) / (j w t) = e^{-j w t / 2} sinc(w t / 2 pi), finite at w = 0.
    return np.exp(-0.5j * w * t_bc) * np.sinc(w * t_bc / (2.0 * math.pi))


def _tz(w, t_tz):
    return 1.0 - np.exp(-1j * w * t_tz)


# --- shared guards ---------------------------------------------------------------------------


def _move(omega_n, distance, speed):
    return check_omega(omega_n, "omega_n"), check_positive(distance, "distance"), check_positive(speed, "speed")


def _offset(delta_omega, omega_n):
    delta_omega = check_finite(delta_omega, "delta_omega")
    if not 0.0 <= delta_omega < omega_n:
        raise ValueError(f"delta_omega must be in [0, omega_n) = [0, {omega_n:g}) rad/s, got {delta_omega!r}")
    return delta_omega


def _null_index(distance, speed, omega_tz):
    """k = ceil(d omega_TZ / (2 pi v)) (eq. 13, 17): the slowest aligned trapezoid not above v."""
    ratio = distance * omega_tz / (2.0 * math.pi * speed)
    # A ratio within rounding of an integer is that integer, not the next one.
    return max(1, math.ceil(ratio - 1e-12 * ratio))


# LAYOUT, the runtime's table (one for both layers), gives per kind the (twin pulse, boxcar,
# trapezoid) null at omega_n + s delta_omega, s in {-1, 0, +1}, or None if absent / not aligned.
_MISALIGNED = tuple(kind for kind in LAYOUT if kind.startswith("M-"))


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


def _sample(t_tp, t_bc, t_tz, slew, ts):
    """Exact a, v, p of v_slew (TP * BC * TZ)(t) on t = k ts, and the kernel TP * BC per sample."""
    starts = np.array([0.0, t_tp, t_tz, t_tz + t_tp])
    weights = np.array([0.5, 0.5, -0.5, -0.5]) * slew
    n = math.ceil((t_tp + t_bc + t_tz) / ts) + 1
    t = np.arange(n + 1) * ts
    s = t[:, None] - starts  # time since each boxcar started
    v = (np.clip(s, 0.0, t_bc) / t_bc) @ weights
    # The mean acceleration over each sample period keeps v exact at the grid points (profile.py).
    a = np.append(np.diff(v) / ts, 0.0)
    # Position of a unit-area boxcar ramp: s^2 / (2 t_BC) while on, then s - t_BC / 2.
    p = np.where(s <= 0.0, 0.0, np.where(s < t_bc, s * s / (2.0 * t_bc), s - t_bc / 2.0)) @ weights
    # TP * BC integrated over each sample period: a unit-area sequence at the profile's ts.
    ramp = np.clip(np.arange(math.ceil((t_tp + t_bc) / ts) + 1)[:, None] * ts - starts[:2], 0.0, t_bc) / t_bc
    kernel = np.diff(ramp @ np.array([0.5, 0.5]))
    return MotionProfile(t, a, v, p, SampledShaper(kernel, ts))


def _design(kind, omega_n, distance, speed, delta_omega, attenuation, ts, tp_null=1, pulse_width=None):
    omega_n, distance, speed = _move(omega_n, distance, speed)
    ts = (2.0 * math.pi / omega_n) / _SAMPLES_PER_PERIOD if ts is None else check_positive(ts, "ts")
    pulse_width = ts if pulse_width is None else check_positive(pulse_width, "pulse_width")
    if kind in _MISALIGNED:
        if (delta_omega is None) == (attenuation is None):
            raise ValueError(
                f"{kind} needs exactly one of delta_omega or attenuation, got {delta_omega!r} and {attenuation!r}"
            )
        if delta_omega is None:
            delta_omega = _offset_for(kind, omega_n, distance, speed, check_vtol(attenuation, "attenuation"), tp_null)
        delta_omega = _offset(delta_omega, omega_n)
    else:
        delta_omega = 0.0
    t_tp, t_bc, t_tz, k, aligned = _times(kind, omega_n, distance, speed, delta_omega, tp_null, pulse_width)
    slew = distance / t_tz
    profile = _sample(t_tp, t_bc, t_tz, slew, ts)
    return TwinPulseProfile(kind, omega_n, delta_omega, k, slew, t_tp, t_bc, t_tz, aligned, profile)


def _offset_for(kind, omega_n, distance, speed, attenuation, tp_null):
    """delta_omega whose magnitude at omega_n equals ``attenuation`` (section III-C, bisection).

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

    grid = omega_n * np.linspace(0.0, 0.5, 501)
    for lo, hi in zip(grid[:-1], grid[1:]):
        if excess(hi) > 0.0:
            return bisect(excess, lo, hi, xtol=1e-14 * omega_n)
    raise ValueError(
        f"attenuation = {attenuation!r} is met for every delta_omega up to omega_n / 2 = {omega_n / 2:g} rad/s; "
        f"pass delta_omega directly"
    )


# --- designs: one function per profile, signature (omega_n, distance, speed, *, ...) -----------


def tp(omega_n, distance, speed, *, ts=None, pulse_width=None) -> TwinPulseProfile:
    """Classic twin pulse (Starr): impulses pi / omega_n apart, t_TZ = d / v (paper 003, Fig. 1, 13).

    Parameters
    ----------
    omega_n : float
        Notch (natural) frequency, rad/s.
    distance : float
        Move distance d > 0.
    speed : float
        Slew speed v > 0.
    ts : float, optional
        Sampling period of the returned profile; default one thousandth of 2 pi / omega_n.
    pulse_width : float, optional
        Width of the boxcar each pulse is realised with (section III-A: a pulse needs some width,
        usually a sample period); default ``ts``.

    Returns
    -------
    TwinPulseProfile
    """
    return _design("TP", omega_n, distance, speed, None, None, ts, pulse_width=pulse_width)


def tp_bc(omega_n, distance, speed, *, null=2, ts=None) -> TwinPulseProfile:
    """Twin pulse with its null ``null`` = k aligned on a boxcar's first null (eq. 1-4).

    t_BC = 2 pi / omega_n (eq. 2), t_TP = (2k - 1) pi / omega_n (eq. 3), kernel (2k + 1) pi /
    omega_n (eq. 4). Other parameters as :func:`tp`.
    """
    return _design("TP:BC", omega_n, distance, speed, None, None, ts, tp_null=check_count(null, "null", 1))


def m_tp_bc(omega_n, distance, speed, *, delta_omega=None, attenuation=None, ts=None) -> TwinPulseProfile:
    """Mis-aligned TP:BC, twin pulse null at omega_n - delta_omega, boxcar at + (eq. 5, 7).

    Give ``delta_omega`` (rad/s, in [0, omega_n)) or ``attenuation`` (the magnitude at omega_n, in
    (0, 1)) to find it by bisection (section III-C). Other parameters as :func:`tp`.
    """
    return _design("M-TP:BC", omega_n, distance, speed, delta_omega, attenuation, ts)


def m_bc_tp(omega_n, distance, speed, *, delta_omega=None, attenuation=None, ts=None) -> TwinPulseProfile:
    """Mis-aligned BC:TP, boxcar null at omega_n - delta_omega, twin pulse at + (eq. 6, 8)."""
    return _design("M-BC:TP", omega_n, distance, speed, delta_omega, attenuation, ts)


def bc_vr(omega_n, distance, speed, *, ts=None) -> TwinPulseProfile:
    """Boxcar / velocity ramp: one boxcar of 2 pi / omega_n, acceleration v omega_n / 2 pi (eq. 9-11)."""
    return _design("BC:VR", omega_n, distance, speed, None, None, ts)


def bc_tz(omega_n, distance, speed, *, ts=None) -> TwinPulseProfile:
    """Boxcar / trapezoid with nulls aligned at omega_n: k by eq. (13), slew speed by eq. (14)."""
    return _design("BC:TZ", omega_n, distance, speed, None, None, ts)


def m_bc_tz(omega_n, distance, speed, *, delta_omega=None, attenuation=None, ts=None) -> TwinPulseProfile:
    """Mis-aligned BC:TZ: boxcar at omega_n - delta_omega, trapezoid at + (eq. 15, 18).

    k = ceil(d (omega_n + delta_omega) / (2 pi v)), the analogue of eq. (17) for this ordering.
    """
    return _design("M-BC:TZ", omega_n, distance, speed, delta_omega, attenuation, ts)


def m_tz_bc(omega_n, distance, speed, *, delta_omega=None, attenuation=None, ts=None) -> TwinPulseProfile:
    """Mis-aligned TZ:BC: trapezoid at omega_n - delta_omega, boxcar at + (eq. 16, 17, 19)."""
    return _design("M-TZ:BC", omega_n, distance, speed, delta_omega, attenuation, ts)


def m_bc_tz_tp(omega_n, distance, speed, *, delta_omega=None, attenuation=None, ts=None) -> TwinPulseProfile:
    """Boxcar at omega_n - delta_omega, trapezoid at omega_n (k by eq. 13), twin pulse at + (sect. III-G).

    The profile of the ten-pendula experiment (section IV). Its length is eq. (21)'s expression,
    see the module docstring.
    """
    return _design("M-BC:TZ:TP", omega_n, distance, speed, delta_omega, attenuation, ts)


def m_tp_tz_bc(omega_n, distance, speed, *, delta_omega=None, attenuation=None, ts=None) -> TwinPulseProfile:
    """Twin pulse at omega_n - delta_omega, trapezoid at omega_n, boxcar at + (sect. III-G, eq. 22)."""
    return _design("M-TP:TZ:BC", omega_n, distance, speed, delta_omega, attenuation, ts)


#: Design functions by the paper's profile name, for the command line (``shapefmu profile KIND``).
TWIN_PULSE_PROFILES = {
    "TP": tp,
    "TP:BC": tp_bc,
    "M-TP:BC": m_tp_bc,
    "M-BC:TP": m_bc_tp,
    "BC:VR": bc_vr,
    "BC:TZ": bc_tz,
    "M-BC:TZ": m_bc_tz,
    "M-TZ:BC": m_tz_bc,
    "M-BC:TZ:TP": m_bc_tz_tp,
    "M-TP:TZ:BC": m_tp_tz_bc,
}
