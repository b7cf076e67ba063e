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
from dataclasses import dataclass, fields

import numpy as np

from shapefmu.runtime import twin_pulse
from shapefmu.runtime.checks import check_count, check_positive
from shapefmu.runtime.units import RadPerSecond
from shapefmu.shapers.profile import MotionProfile
from shapefmu.shapers.sampled import SampledShaper


@dataclass(frozen=True)
class TwinPulseProfile(twin_pulse.TwinPulseTiming):
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
    duration : float
        Length of the whole move, t_tp + t_bc + t_tz, s.

    The timing fields are those of ``shapefmu.runtime.twin_pulse.TwinPulseTiming``, declared once.

    Examples
    --------
    >>> d = bc_tz(3.5, 1.7, 0.7, ts=0.01)
    >>> d.kind, round(d.kernel_length, 6), round(d.profile.distance, 9)  # the move covers d
    ('BC:TZ', 1.795196, 1.7)
    """

    profile: MotionProfile

    @property
    def kernel_length(self) -> float:
        """Length of TP * BC (eq. 4, 7, 8); add t_tz for the whole move (eq. 12, 15, 16, 20, 21)."""
        return self.t_tp + self.t_bc

    def spectrum(self, omega: RadPerSecond) -> np.ndarray:
        """Acceleration spectrum per unit slew speed, TP(w) BC(w) TZ(w), exact and vectorised."""
        w = np.asarray(omega, dtype=float)
        return _tp(w, self.t_tp) * _bc(w, self.t_bc) * _tz(w, self.t_tz)

    def magnitude(self, omega: RadPerSecond) -> np.ndarray:
        """The paper's normalised magnitude: |TP BC| (and |TZ| / 2 where a trapezoid is aligned)."""
        w = np.asarray(omega, dtype=float)
        m = np.abs(_tp(w, self.t_tp) * _bc(w, self.t_bc))
        return m * np.abs(_tz(w, self.t_tz)) / 2.0 if self.trapezoid_aligned else m

    def residual_swing(self, omega: RadPerSecond, gravity: float = 9.81) -> np.ndarray:
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


# --- the design: the runtime's, sampled here -------------------------------------------------


def _design(kind, omega_n, distance, speed, delta_omega, attenuation, ts, tp_null=None, pulse_width=None):
    """The runtime's design of ``kind`` (what a ProfileGenerator FMU plays) with its sampled profile.

    ``shapefmu.runtime.twin_pulse`` validates the parameters, places the nulls (eq. 2-4, 7-8,
    11-17, 20-21), finds delta_omega for an ``attenuation`` (section III-C, scan and bisection;
    see its ``_offset_for``) and integrates the kernel TP * BC over each sample period.
    """
    move = twin_pulse.twin_pulse_profile(
        kind, omega_n, distance, speed, delta_omega=delta_omega, attenuation=attenuation, ts=ts, null=tp_null,
        pulse_width=pulse_width,
    )
    profile = _sample(move.t_tp, move.t_bc, move.t_tz, move.slew_speed, move.ts, move.kernel)
    timing = {field.name: getattr(move, field.name) for field in fields(twin_pulse.TwinPulseTiming)}
    return TwinPulseProfile(**timing, profile=profile)


def _sample(t_tp, t_bc, t_tz, slew, ts, kernel):
    """Exact a, v, p of v_slew (TP * BC * TZ)(t) on t = k ts, with the runtime's sampled ``kernel``.

    Closed form, vectorised: the move is four boxcars of width t_BC starting at 0, t_TP, t_TZ and
    t_TZ + t_TP with weights +-v_slew / 2, so v and p are sums of clipped ramps. (The runtime plays
    the same move as a ``motion.PiecewiseAcceleration``; tests/test_runtime_profiles.py checks both
    agree.) The velocity after the move is exactly 0.
    """
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
    return MotionProfile(t, a, v, p, SampledShaper(kernel, ts))


# --- designs: one function per profile, signature (omega_n, distance, speed, *, ...) -----------


def tp(omega_n: RadPerSecond, distance, speed, *, ts=None, pulse_width=None) -> TwinPulseProfile:
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

    Examples
    --------
    >>> d = tp(3.5, 1.7, 0.7)  # paper 003's pendula: t_TP = pi / omega_n, t_TZ = d / v
    >>> math.isclose(d.t_tp, math.pi / 3.5), math.isclose(d.t_tz, 1.7 / 0.7)
    (True, True)
    """
    return _design("TP", omega_n, distance, speed, None, None, ts, pulse_width=pulse_width)


def tp_bc(omega_n: RadPerSecond, distance, speed, *, null=2, ts=None) -> TwinPulseProfile:
    """Twin pulse with its null ``null`` = k aligned on a boxcar's first null (eq. 1-4).

    t_BC = 2 pi / omega_n (eq. 2), t_TP = (2k - 1) pi / omega_n (eq. 3), kernel (2k + 1) pi /
    omega_n (eq. 4). Other parameters as :func:`tp`.

    Examples
    --------
    >>> d = tp_bc(3.5, 1.7, 0.7)  # k = 2: t_TP = 3 pi / omega_n, t_BC = 2 pi / omega_n
    >>> math.isclose(d.t_tp, 3 * math.pi / 3.5), math.isclose(d.t_bc, 2 * math.pi / 3.5), float(d.magnitude(3.5)) < 1e-15
    (True, True, True)
    """
    return _design("TP:BC", omega_n, distance, speed, None, None, ts, tp_null=check_count(null, "null", 1))


def m_tp_bc(omega_n: RadPerSecond, distance, speed, *, delta_omega: RadPerSecond | None = None, attenuation=None, ts=None) -> TwinPulseProfile:
    """Mis-aligned TP:BC, twin pulse null at omega_n - delta_omega, boxcar at + (eq. 5, 7).

    Give ``delta_omega`` (rad/s, in [0, omega_n)) or ``attenuation`` (the magnitude at omega_n, in
    (0, 1)) to find it by bisection (section III-C). Other parameters as :func:`tp`.

    Examples
    --------
    >>> d = m_tp_bc(3.5, 1.7, 0.7, delta_omega=0.2)
    >>> math.isclose(d.t_tp, math.pi / 3.3), math.isclose(d.t_bc, 2 * math.pi / 3.7)
    (True, True)
    """
    return _design("M-TP:BC", omega_n, distance, speed, delta_omega, attenuation, ts)


def m_bc_tp(omega_n: RadPerSecond, distance, speed, *, delta_omega: RadPerSecond | None = None, attenuation=None, ts=None) -> TwinPulseProfile:
    """Mis-aligned BC:TP, boxcar null at omega_n - delta_omega, twin pulse at + (eq. 6, 8).

    Examples
    --------
    >>> d = m_bc_tp(3.5, 1.7, 0.7, delta_omega=0.2)
    >>> math.isclose(d.t_bc, 2 * math.pi / 3.3), math.isclose(d.t_tp, math.pi / 3.7)
    (True, True)
    """
    return _design("M-BC:TP", omega_n, distance, speed, delta_omega, attenuation, ts)


def bc_vr(omega_n: RadPerSecond, distance, speed, *, ts=None) -> TwinPulseProfile:
    """Boxcar / velocity ramp: one boxcar of 2 pi / omega_n, acceleration v omega_n / 2 pi (eq. 9-11).

    Examples
    --------
    >>> d = bc_vr(3.5, 1.7, 0.7)
    >>> math.isclose(d.t_bc, 2 * math.pi / 3.5), d.t_tp, float(d.magnitude(3.5)) < 1e-15
    (True, 0.0, True)
    """
    return _design("BC:VR", omega_n, distance, speed, None, None, ts)


def bc_tz(omega_n: RadPerSecond, distance, speed, *, ts=None) -> TwinPulseProfile:
    """Boxcar / trapezoid with nulls aligned at omega_n: k by eq. (13), slew speed by eq. (14).

    Examples
    --------
    >>> d = bc_tz(3.5, 1.7, 0.7)  # k = 2: t_TZ = 2 pi k / omega_n, slew d / t_TZ
    >>> d.null, math.isclose(d.t_tz, 4 * math.pi / 3.5), math.isclose(d.slew_speed, 1.7 / d.t_tz)
    (2, True, True)
    """
    return _design("BC:TZ", omega_n, distance, speed, None, None, ts)


def m_bc_tz(omega_n: RadPerSecond, distance, speed, *, delta_omega: RadPerSecond | None = None, attenuation=None, ts=None) -> TwinPulseProfile:
    """Mis-aligned BC:TZ: boxcar at omega_n - delta_omega, trapezoid at + (eq. 15, 18).

    k = ceil(d (omega_n + delta_omega) / (2 pi v)), the analogue of eq. (17) for this ordering.

    Examples
    --------
    >>> d = m_bc_tz(3.5, 1.7, 0.7, delta_omega=0.2)  # k = ceil(1.7 * 3.7 / (2 pi 0.7)) = 2
    >>> d.null, math.isclose(d.t_bc, 2 * math.pi / 3.3), math.isclose(d.t_tz, 4 * math.pi / 3.7)
    (2, True, True)
    """
    return _design("M-BC:TZ", omega_n, distance, speed, delta_omega, attenuation, ts)


def m_tz_bc(omega_n: RadPerSecond, distance, speed, *, delta_omega: RadPerSecond | None = None, attenuation=None, ts=None) -> TwinPulseProfile:
    """Mis-aligned TZ:BC: trapezoid at omega_n - delta_omega, boxcar at + (eq. 16, 17, 19).

    Examples
    --------
    >>> d = m_tz_bc(3.5, 1.7, 0.7, delta_omega=0.2)
    >>> math.isclose(d.t_bc, 2 * math.pi / 3.7), math.isclose(d.t_tz, 2 * math.pi * d.null / 3.3)
    (True, True)
    """
    return _design("M-TZ:BC", omega_n, distance, speed, delta_omega, attenuation, ts)


def m_bc_tz_tp(omega_n: RadPerSecond, distance, speed, *, delta_omega: RadPerSecond | None = None, attenuation=None, ts=None) -> TwinPulseProfile:
    """Boxcar at omega_n - delta_omega, trapezoid at omega_n (k by eq. 13), twin pulse at + (sect. III-G).

    The profile of the ten-pendula experiment (section IV). Its length is eq. (21)'s expression,
    see the module docstring.

    Examples
    --------
    >>> d = m_bc_tz_tp(3.5, 1.7, 0.7, delta_omega=0.2)  # the trapezoid keeps omega_n's null
    >>> float(d.magnitude(3.5)) < 1e-15, d.null
    (True, 2)
    """
    return _design("M-BC:TZ:TP", omega_n, distance, speed, delta_omega, attenuation, ts)


def m_tp_tz_bc(omega_n: RadPerSecond, distance, speed, *, delta_omega: RadPerSecond | None = None, attenuation=None, ts=None) -> TwinPulseProfile:
    """Twin pulse at omega_n - delta_omega, trapezoid at omega_n, boxcar at + (sect. III-G, eq. 22).

    Examples
    --------
    >>> d = m_tp_tz_bc(3.5, 1.7, 0.7, delta_omega=0.2)
    >>> math.isclose(d.t_tp, math.pi / 3.3), math.isclose(d.t_bc, 2 * math.pi / 3.7), float(d.magnitude(3.5)) < 1e-15
    (True, True, True)
    """
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
