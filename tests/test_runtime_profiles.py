"""Standard-library profile and filter construction (runtime/) against scipy, closed forms and the design layer.

The design layer calls these runtime functions for every design (window filters, twin-pulse and
time-frequency profiles), so the designs themselves are checked against independent references:
scipy.signal.windows, the paper's closed forms, scipy's quadrature nodes and bounded minimisation.
Where the two layers still compute differently (the design layer samples a move with numpy, the
runtime plays it as a ``motion.PiecewiseAcceleration``) they are compared with each other.
"""

import functools
import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import bisect as scipy_bisect
from scipy.optimize import minimize_scalar
from scipy.signal import windows
from scipy.special import roots_legendre

from shapefmu.optimal import Command, rigid_bang_bang, simulate
from shapefmu.plants import rigid_flexible
from shapefmu.runtime import motion, scalar_search, shaped_bang_bang, time_frequency, twin_pulse, window_filters
from shapefmu.shapers import profile as design_profile
from shapefmu.shapers import simultaneous as design_simultaneous
from shapefmu.shapers import time_frequency as design_time_frequency
from shapefmu.shapers import twin_pulse as design_twin_pulse
from shapefmu.shapers import window as design_window

# Paper 004's hard-disk seek: Omega_0 = 9.68e3 rad/s, Ts = 2e-5 s, move 2.5 ms.
OMEGA_0, TS, MOVE = 9.68e3, 2e-5, 2.5e-3
# Paper 003's ten-pendula experiment: 3.36-3.66 rad/s, 1.7 m at 0.7 m/s.
PENDULUM, DISTANCE, SPEED = 3.5, 1.7, 0.7


def assert_close_relative(got, expected, tolerance):
    expected = np.asarray(expected, dtype=float)
    got = np.asarray(got, dtype=float)
    assert got.shape == expected.shape
    assert np.max(np.abs(got - expected)) <= tolerance * np.max(np.abs(expected))


# --- window filters (paper 000) ----------------------------------------------------------------


def paper_000_taps(kind, omega_n, zeta, ts, order):
    """Taps of paper 000's filters built independently: scipy.signal.windows, then numpy.

    The base window of M + 1 samples (M from the ts used: the null 2 pi m0 / M at omega_d ts;
    three-Hanning's M from eq. (6) as printed), damping compensation and normalisation
    (section 3), and the n-fold self-convolution of eq. (1). Default weights of the paper.
    """
    u = omega_n * math.sqrt(1.0 - zeta * zeta) * ts  # omega_d Ts

    def length(m0):
        return round(2.0 * math.pi * m0 / u)

    if kind == "rectangle":
        h = np.ones(length(1))
    elif kind == "hanning":
        h = windows.hann(length(2) + 1)
    elif kind == "blackman":
        h = windows.blackman(length(3) + 1)
    elif kind == "hamming":
        h = windows.general_hamming(length(2) + 1, 25.0 / 46.0)
    elif kind == "three-hanning":
        c, y = 0.25, math.cos(u)
        b = c * c * y * y + 2 * c * c * y + c * c + 2 * c + 6 * c * y + 2 + 2 * y
        m = round(math.pi / math.acos((c * y - c + math.sqrt(b)) / (2 * c + 2)))
        short = windows.hann(m + 1)
        h = windows.hann(2 * m + 1) + c * np.concatenate([short, short[1:]])
    else:
        m = length(2)
        g = windows.hann(m + 1)
        if kind == "differenced":  # k1 g + k2 dg on 0..M + 1, k1 = 1, k2 = -25 (section 8.1)
            padded = np.append(g, 0.0)
            h = padded - 25.0 * np.diff(padded, prepend=0.0)
        else:  # convolved: k1 g[k - M] + k2 (g * g)[k], k1 = 1, k2 = 1/125 (section 8.2)
            h = np.convolve(g, g) / 125.0
            h[m : 2 * m + 1] += g
    f = h * np.exp(-zeta * omega_n * ts * np.arange(h.size))
    f = f / f.sum()
    return functools.reduce(np.convolve, [f] * order)


@pytest.mark.parametrize("kind", sorted(window_filters.WINDOW_FILTERS))
@pytest.mark.parametrize(("zeta", "order"), [(0.0, 1), (0.05, 2), (0.2, 3)])
def test_window_filter_taps_equal_scipy_windows_compensated_and_convolved(kind, zeta, order):
    taps, ts = window_filters.WINDOW_FILTERS[kind](2.0, zeta, 0.02, order, adjust_ts=True)
    reference = paper_000_taps(kind, 2.0, zeta, ts, order)
    assert_close_relative(taps, reference, 1e-12)
    # The design layer: the runtime's order-1 taps, raised to the order with numpy.
    design = design_window.WINDOW_FILTERS[kind](2.0, zeta, 0.02, order, adjust_ts=True)
    assert design.ts == ts
    assert_close_relative(design.taps, reference, 1e-12)


def test_hanning_filter_with_exact_ts_has_the_papers_length():
    # M = 4 pi / (omega_d Ts) = 400 (paper 000, eq. 2): M + 1 taps.
    taps, ts = window_filters.hanning_filter(1.0, 0.0, math.pi / 100)
    assert len(taps) == 401 and ts == math.pi / 100


def test_window_filter_refuses_a_ts_that_makes_m_fractional_naming_the_nearest_valid_ts():
    # M = 4 pi / (omega_d ts) = 417.49: the nearest valid periods are 4 pi / 417 and 4 pi / 418.
    with pytest.raises(ValueError) as runtime_error:
        window_filters.hanning_filter(1.0, 0.0, 0.0301)
    assert str(runtime_error.value) == (
        f"ts = 0.0301 s gives M = 4*pi/(omega_d*ts) = {4 * math.pi / 0.0301:.6g}, which is not an integer; "
        f"valid ts make M an integer >= 4, the nearest are {4 * math.pi / 417:.10g} s (M = 417), "
        f"{4 * math.pi / 418:.10g} s (M = 418); or pass adjust_ts=True"
    )


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: window_filters.hanning_filter(-1.0, 0.0, 0.01), "omega_n must be > 0, got -1.0"),
        (lambda: window_filters.hanning_filter(1.0, 1.0, 0.01), r"zeta must be in \[0, 1\), got 1.0"),
        (lambda: window_filters.hanning_filter(1.0, 0.0, math.pi / 100, 0), "order must be an integer >= 1, got 0"),
        (lambda: window_filters.convolved_filter(1.0, 0.0, math.pi / 100, base="kaiser"), "base must be one of"),
        (lambda: window_filters.three_hanning_filter(1.0, 0.0, 0.01, c=-1.0), "c must be >= 0, got -1.0"),
    ],
)
def test_window_filter_bad_parameters_are_named(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_hanning_velocity_profile_equals_the_design_layer():
    taps, ts = window_filters.hanning_filter(1.0, 0.0, math.pi / 100)
    move = motion.velocity_profile(taps, ts, 2.0)
    reference = design_profile.velocity_profile(design_window.hanning_filter(1.0, 0.0, math.pi / 100), 2.0)
    t, acceleration, velocity, position = move.sample(ts, reference.t.size)
    assert_close_relative(t, reference.t, 1e-15)
    assert_close_relative(velocity, reference.velocity, 1e-12)
    assert_close_relative(position, reference.position, 1e-12)
    assert_close_relative(acceleration, reference.acceleration, 1e-12)


# --- twin-pulse family (paper 003) -------------------------------------------------------------


def _design_options(kind):
    return {"attenuation": 0.05} if kind.startswith("M-") else {}


def paper_003_timing(kind, delta_omega):
    """(t_TP, t_BC, t_TZ, k) written out per profile from paper 003's equations.

    A twin pulse with its null at w has t_TP = pi / w (k-th null: (2k - 1) pi / w, eq. 3), a boxcar
    t_BC = 2 pi / w (eq. 2), an aligned trapezoid t_TZ = 2 pi k / w with k = ceil(d w / (2 pi v))
    (eq. 12-17); "M-" puts the first-named component at omega_n - delta_omega and the last at
    omega_n + delta_omega, the triple profiles keep the trapezoid at omega_n (III-G). Without a
    boxcar the pulses are one default sample (2 pi / omega_n / 1000) wide; without a trapezoid
    t_TZ = d / v.
    """
    wn, low, high = PENDULUM, PENDULUM - delta_omega, PENDULUM + delta_omega

    def k(w):
        return math.ceil(DISTANCE * w / (2.0 * math.pi * SPEED))

    pi, free = math.pi, DISTANCE / SPEED
    return {
        "TP": (pi / wn, 2 * pi / wn / 1000, free, 0),
        "TP:BC": (3 * pi / wn, 2 * pi / wn, free, 2),  # eq. (2)-(4), k = 2
        "M-TP:BC": (pi / low, 2 * pi / high, free, 0),  # eq. (5), (7)
        "M-BC:TP": (pi / high, 2 * pi / low, free, 0),  # eq. (6), (8)
        "BC:VR": (0.0, 2 * pi / wn, free, 0),  # eq. (9)-(11)
        "BC:TZ": (0.0, 2 * pi / wn, 2 * pi * k(wn) / wn, k(wn)),  # eq. (12)-(14)
        "M-BC:TZ": (0.0, 2 * pi / low, 2 * pi * k(high) / high, k(high)),  # eq. (15), (18)
        "M-TZ:BC": (0.0, 2 * pi / high, 2 * pi * k(low) / low, k(low)),  # eq. (16)-(17), (19)
        "M-BC:TZ:TP": (pi / high, 2 * pi / low, 2 * pi * k(wn) / wn, k(wn)),  # eq. (21)
        "M-TP:TZ:BC": (pi / low, 2 * pi / high, 2 * pi * k(wn) / wn, k(wn)),  # eq. (20), (22)
    }[kind]


def paper_003_magnitude(kind, t_tp, t_bc, t_tz):
    """At omega_n: |BC TZ| / 2 where the trapezoid is mis-aligned (eq. 18-19), else |TP BC| (eq. 5-6)."""
    w = PENDULUM
    tp, tz = abs(1 + np.exp(-1j * w * t_tp)) / 2, abs(1 - np.exp(-1j * w * t_tz))
    bc = abs(np.sinc(w * t_bc / (2 * math.pi)))
    return bc * tz / 2 if kind in ("M-BC:TZ", "M-TZ:BC") else tp * bc


@pytest.mark.parametrize("kind", twin_pulse.KINDS)
def test_twin_pulse_profile_follows_the_paper_and_the_design_layer_samples_the_played_move(kind):
    design = twin_pulse.twin_pulse_profile(kind, PENDULUM, DISTANCE, SPEED, **_design_options(kind))
    t_tp, t_bc, t_tz, k = paper_003_timing(kind, design.delta_omega)
    assert design.null == k and design.trapezoid_aligned == ("TZ" in kind)
    for name, expected in [("t_tp", t_tp), ("t_bc", t_bc), ("t_tz", t_tz), ("slew_speed", DISTANCE / t_tz)]:
        assert getattr(design, name) == pytest.approx(expected, rel=1e-12, abs=1e-15)
    if kind.startswith("M-"):  # the offset meets the requested attenuation at omega_n
        assert paper_003_magnitude(kind, t_tp, t_bc, t_tz) == pytest.approx(0.05, rel=1e-12)
    # The kernel is TP * BC integrated over each sample period: differences of the ramps of its two
    # boxcars, unit area.
    edges = np.arange(len(design.kernel) + 1) * design.ts
    ramps = 0.5 * np.clip(edges / t_bc, 0.0, 1.0) + 0.5 * np.clip((edges - t_tp) / t_bc, 0.0, 1.0)
    assert_close_relative(design.kernel, np.diff(ramps), 1e-12)
    # What the FMU plays (the runtime's PiecewiseAcceleration) against the design layer's exact
    # samples of the same move (numpy, sums of clipped boxcar ramps).
    t, acceleration, velocity, position = design.sample()
    profile = design_twin_pulse.TWIN_PULSE_PROFILES[kind](PENDULUM, DISTANCE, SPEED, **_design_options(kind)).profile
    assert_close_relative(t, profile.t, 1e-15)
    assert_close_relative(velocity, profile.velocity, 1e-12)
    assert_close_relative(position, profile.position, 1e-12)
    assert_close_relative(acceleration, profile.acceleration, 1e-12)


def test_twin_pulse_given_offset_equals_the_design_layer():
    design = twin_pulse.twin_pulse_profile("M-BC:TZ:TP", PENDULUM, DISTANCE, SPEED, delta_omega=0.2, ts=1e-3)
    reference = design_twin_pulse.m_bc_tz_tp(PENDULUM, DISTANCE, SPEED, delta_omega=0.2, ts=1e-3)
    assert_close_relative(design.sample()[3], reference.profile.position, 1e-12)


def test_twin_pulse_move_is_rest_to_rest_over_the_distance():
    move = twin_pulse.twin_pulse_profile("M-BC:TZ:TP", PENDULUM, DISTANCE, SPEED, attenuation=0.05).motion
    assert move.distance == pytest.approx(DISTANCE, rel=1e-13)
    assert abs(move.final_velocity) <= 1e-13 * SPEED


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"kind": "XX"}, "kind must be one of"),
        ({"kind": "M-TP:BC"}, "needs exactly one of delta_omega or attenuation"),
        ({"kind": "M-TP:BC", "delta_omega": 4.0}, r"delta_omega must be in \[0, omega_n\)"),
        ({"kind": "TP", "null": 2}, "null applies to the TP:BC profile only"),
        ({"kind": "TP", "speed": 0.0}, "speed must be > 0, got 0.0"),
    ],
)
def test_twin_pulse_bad_parameters_are_named(options, message):
    arguments = {"kind": "TP", "omega_n": PENDULUM, "distance": DISTANCE, "speed": SPEED} | options
    with pytest.raises(ValueError, match=message):
        twin_pulse.twin_pulse_profile(**arguments)


# --- time-frequency profile (paper 004) --------------------------------------------------------


@functools.lru_cache(maxsize=None)
def _legendre(count):
    return roots_legendre(count)


def scipy_leakage(n, move_time):
    """1 - J (eq. 18-19) as the energy of g_{phi,n} above omega_0 over pi sum g^2, with numpy.

    |G(omega)|^2 is a trigonometric polynomial of degree M; scipy's Gauss-Legendre rule of M + 32
    nodes on [omega_0, pi] integrates it to rounding (a sum of positive terms: no cancellation
    however small 1 - J is). g from the design layer's numpy phi (eq. 12, 15).
    """
    m = round(move_time / TS)
    g = design_time_frequency.phi((np.arange(m + 1) - m / 2.0) * TS, n)
    omega_0 = OMEGA_0 * TS
    nodes, weights = _legendre(m + 32)
    omega = omega_0 + 0.5 * (math.pi - omega_0) * (nodes + 1.0)
    power = np.abs(np.exp(-1j * np.outer(omega, np.arange(m + 1))) @ g) ** 2
    return 0.5 * (math.pi - omega_0) * float(weights @ power) / (math.pi * float(g @ g))


@pytest.mark.parametrize("n", [9.0, 11.4, 13.0])
def test_energy_leakage_equals_gauss_legendre_quadrature_with_scipy(n):
    got = time_frequency.energy_leakage(n, OMEGA_0, TS, MOVE)
    assert got == pytest.approx(scipy_leakage(n, MOVE), rel=0, abs=1e-12)


# Up to 5 ms, where 1 - J falls to 2e-10: both compute it as the out-of-band energy, not 1 - J.
@pytest.mark.parametrize("move_time", [0.5e-3, 1e-3, 1.5e-3, 2e-3, 2.5e-3, 3e-3, 3.5e-3, 4e-3, 4.5e-3, 5e-3])
def test_optimal_scale_equals_scipys_bounded_minimisation(move_time):
    n, leakage = time_frequency.optimal_scale(OMEGA_0, TS, move_time)
    reference = minimize_scalar(
        lambda x: scipy_leakage(x, move_time),
        bounds=time_frequency.scale_bounds(TS, move_time),
        method="bounded",
        options={"xatol": 1e-6},
    )
    assert abs(n - reference.x) <= 1e-6
    assert leakage == pytest.approx(reference.fun, rel=1e-9)


def test_time_frequency_profile_at_a_given_scale_equals_the_design_layer():
    design = time_frequency.time_frequency_profile(OMEGA_0, TS, MOVE, 1e-3, n=11.4)
    reference = design_time_frequency.time_frequency_profile(OMEGA_0, TS, MOVE, 1e-3, n=11.4)
    m = round(MOVE / TS)  # eq. (15): g[k] = phi_n((k - M/2) Ts), k = 0..M
    assert_close_relative(design.kernel, design_time_frequency.phi((np.arange(m + 1) - m / 2.0) * TS, 11.4), 1e-12)
    # What the FMU plays (held acceleration as a PiecewiseAcceleration) against the design layer's
    # profile (the same held acceleration integrated with numpy).
    t, acceleration, velocity, position = design.sample()
    assert_close_relative(t, reference.profile.t, 1e-15)
    assert_close_relative(acceleration, reference.profile.acceleration, 1e-12)
    assert_close_relative(velocity, reference.profile.velocity, 1e-12)
    assert_close_relative(position, reference.profile.position, 1e-12)


def test_time_frequency_optimal_design_reproduces_paper_004():
    design = time_frequency.time_frequency_profile(OMEGA_0, TS, MOVE, 1.0)
    assert round(design.n, 1) == 11.4  # paper 004, section IV
    assert design.motion.distance == pytest.approx(1.0, rel=1e-12)


def test_time_frequency_refuses_a_fractional_sample_count_naming_the_nearest_move_times():
    # 2.511 ms / 20 us = 125.55 samples: the nearest whole counts are 125 (2.5 ms) and 126 (2.52 ms).
    with pytest.raises(ValueError) as runtime_error:
        time_frequency.time_frequency_profile(OMEGA_0, TS, 2.51e-3 + 1e-6, 1.0)
    assert str(runtime_error.value) == (
        "move_time / ts must be an integer M >= 2, got 0.002511 / 2e-05 = 125.55; the nearest valid move "
        "times are 0.0025 s (M = 125) and 0.00252 s (M = 126)"
    )


# --- shaped bang-bang (paper 002, eq. 2, 4, 21) -----------------------------------------------


DOUBLE_INTEGRATOR = rigid_flexible(1.0)
DISK_DRIVE_MODES = [(2 * math.pi * 2000.0, 0.01), (2 * math.pi * 3000.0, 0.01)]


def test_bang_bang_equals_the_time_optimal_rigid_body_move():
    reference = rigid_bang_bang(DOUBLE_INTEGRATOR, 0.05, 11.0)
    breaks, levels = shaped_bang_bang.bang_bang(0.05, 11.0)
    np.testing.assert_allclose(breaks, reference.breaks, rtol=1e-12, atol=0)
    np.testing.assert_allclose(levels, reference.levels, rtol=1e-12, atol=0)


def test_shaped_bang_bang_equals_the_design_layers_shaped_command_and_its_exact_simulation():
    shaper = design_simultaneous(DISK_DRIVE_MODES)
    move = shaped_bang_bang.shaped_bang_bang(0.05, 11.0, shaper.times, shaper.amplitudes)
    half = math.sqrt(0.05 / 11.0)
    reference = Command((0.0, half, 2 * half), (11.0, -11.0)).shaped(shaper)
    np.testing.assert_allclose(move.breaks, reference.breaks, rtol=0, atol=1e-15)
    np.testing.assert_allclose(move.levels, reference.levels, rtol=1e-12, atol=1e-12)
    # Position and velocity between breaks against the matrix-exponential simulation of optimal/.
    t = np.linspace(0.0, 1.2 * move.breaks[-1], 97)
    _, states = simulate(DOUBLE_INTEGRATOR, reference, t)
    got = np.array([move.state(x)[:2] for x in t])
    np.testing.assert_allclose(got[:, 0], states[:, 0], rtol=0, atol=1e-12 * 0.05)
    np.testing.assert_allclose(got[:, 1], states[:, 1], rtol=0, atol=1e-12 * np.max(np.abs(states[:, 1])))


def test_speed_limit_gives_the_closed_form_bang_coast_bang():
    # d = 1, a = 2, v = 1: ramps of v/a = 0.5 s, T = d/v + v/a = 1.5 s, peak speed v.
    move = shaped_bang_bang.shaped_bang_bang(1.0, 2.0, speed=1.0)
    assert move.breaks == [0.0, 0.5, 1.0, 1.5]
    assert move.state(0.75) == pytest.approx((0.5, 1.0, 0.0), rel=1e-15)
    assert move.distance == pytest.approx(1.0, rel=1e-15)


def test_shaped_move_keeps_the_distance_and_the_acceleration_limit():
    shaper = design_simultaneous(DISK_DRIVE_MODES)
    move = shaped_bang_bang.shaped_bang_bang(0.05, 11.0, shaper.times, shaper.amplitudes)
    assert move.distance == pytest.approx(0.05, rel=1e-12)
    assert max(abs(a) for a in move.levels) <= 11.0 * (1 + 1e-12)


def test_piecewise_acceleration_velocity_integrates_to_its_position():
    move = shaped_bang_bang.shaped_bang_bang(0.05, 11.0, [0.0, 2e-4], [0.5, 0.5])
    end = move.breaks[-1]
    for t in (0.3 * end, 0.77 * end, end):
        integral, _ = quad(lambda x: move.state(x)[1], 0.0, t, points=move.breaks[1:-1], epsabs=1e-16, limit=200)
        assert move.state(t)[0] == pytest.approx(integral, rel=1e-10)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: shaped_bang_bang.bang_bang(-1.0, 1.0), "distance must be > 0, got -1.0"),
        (lambda: shaped_bang_bang.bang_bang(1.0, float("nan")), "acceleration must be a finite real number"),
        (lambda: shaped_bang_bang.shaped_bang_bang(1.0, 1.0, [0.0, -1.0], [0.5, 0.5]), "impulse times must be >= 0"),
        (lambda: shaped_bang_bang.shaped_bang_bang(1.0, 1.0, [0.0], [0.5, 0.5]), "equal length"),
    ],
)
def test_shaped_bang_bang_bad_parameters_are_named(call, message):
    with pytest.raises(ValueError, match=message):
        call()


# --- the scalar searches behind them ----------------------------------------------------------


@pytest.mark.parametrize(
    ("function", "bounds"),
    [
        (lambda x: (x - 0.3) ** 2 + math.sin(5 * x), (-1.0, 2.0)),
        (lambda x: math.cosh(x - 1.7), (0.0, 1.0)),  # minimum on the bound
        (lambda x: abs(x - math.pi), (0.0, 10.0)),  # kink: golden-section steps
    ],
)
def test_bounded_minimisation_matches_scipy(function, bounds):
    x, fx = scalar_search.minimize_bounded(function, *bounds, xatol=1e-8)
    reference = minimize_scalar(function, bounds=bounds, method="bounded", options={"xatol": 1e-8})
    assert abs(x - reference.x) <= 2e-8
    assert fx == pytest.approx(reference.fun, rel=1e-12, abs=1e-15)


def test_bisection_matches_scipy():
    function = lambda x: math.cos(x) - x  # noqa: E731
    assert scalar_search.bisect(function, 0.0, 1.0, xtol=1e-14) == pytest.approx(
        scipy_bisect(function, 0.0, 1.0, xtol=1e-14), abs=2e-14
    )


def test_bisection_refuses_an_interval_without_a_sign_change():
    with pytest.raises(ValueError, match="function must change sign"):
        scalar_search.bisect(lambda x: x * x + 1.0, -1.0, 1.0, xtol=1e-12)
