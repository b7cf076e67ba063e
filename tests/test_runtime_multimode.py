"""The standard-library simultaneous shaper (runtime.multimode) against scipy's MINPACK and eq. (20).

runtime.multimode is the one implementation: a Shaper FMU runs it and the design layer
(shapers.multimode.simultaneous) returns its impulses. The independent reference is eq. (20)
solved by scipy's MINPACK Levenberg-Marquardt (``scipy.optimize.least_squares(method="lm")``,
numpy residuals and Jacobian) from the same grid of starts, keeping the shortest positive root,
and the residual vibration of shapefmu.analysis at every mode.
"""

import itertools
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.optimize import least_squares

from shapefmu.analysis import residual_vibration
from shapefmu.runtime import impulse_formulas
from shapefmu.runtime.least_squares import solve_least_squares
from shapefmu.runtime.multimode import simultaneous
from shapefmu.shapers import ImpulseShaper

DISK_DRIVE = [(2 * math.pi * 2000.0, 0.01), (2 * math.pi * 3000.0, 0.01)]
THREE_MODES = [(10.0, 0.02), (27.0, 0.05), (41.0, 0.01)]


def scipy_shortest_root(modes, starts_per_axis=10):
    """Eq. (20) by MINPACK from a grid of start times over (0, 1.5 T_conv], in time units 1/omega_max.

    Unknowns x = (a_1..a_{M+1}, tau_2..tau_{M+1}); residuals, for every mode, the real and
    imaginary parts of sum_i a_i e^{-sigma (tau_N - tau_i) + j omega_d tau_i}, and sum_i a_i - 1.
    Start amplitudes by linear least squares for the start times. Returns (times in s,
    amplitudes) of the shortest root with positive amplitudes and distinct times, or None.
    """
    scale = max(w for w, _ in modes)
    sigma = np.array([z * w for w, z in modes]) / scale
    omega_d = np.array([w * math.sqrt(1.0 - z * z) for w, z in modes]) / scale
    m = len(modes)

    def terms(tau):  # e^{-sigma (tau_N - tau_i) + j omega_d tau_i}, one row per mode
        return np.exp(np.outer(-sigma, tau[-1] - tau) + 1j * np.outer(omega_d, tau))

    def split(x):
        return x[: m + 1], np.concatenate([[0.0], x[m + 1 :]])

    def residuals(x):
        a, tau = split(x)
        r = terms(tau) @ a
        return np.concatenate([r.real, r.imag, [a.sum() - 1.0]])

    def jacobian(x):
        a, tau = split(x)
        e = terms(tau)
        d_tau = e[:, 1:] * a[1:] * (sigma + 1j * omega_d)[:, None]
        d_tau[:, -1] -= sigma * (e @ a)  # tau_N in every term's decay
        complex_rows = np.hstack([e, d_tau])
        gain = np.concatenate([np.ones(m + 1), np.zeros(m)])
        return np.vstack([complex_rows.real, complex_rows.imag, gain])

    t_conv = float(np.sum(math.pi / omega_d))
    best = None
    for times in itertools.combinations(np.linspace(0.0, 1.5 * t_conv, starts_per_axis + 1)[1:], m):
        e = terms(np.concatenate([[0.0], times]))
        rows = np.vstack([e.real, e.imag, np.ones(m + 1)])
        a0 = np.linalg.lstsq(rows, np.eye(2 * m + 1)[-1], rcond=None)[0]
        with np.errstate(over="ignore", invalid="ignore"):  # a long trial step may overflow: MINPACK rejects it
            fit = least_squares(
                residuals, np.concatenate([a0, times]), jac=jacobian, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15
            )
        if not np.max(np.abs(residuals(fit.x))) <= 1e-12:
            continue
        a, tau = split(fit.x)
        order = np.argsort(tau)
        a, tau = a[order], tau[order]
        if tau[0] != 0.0 or np.any(np.diff(tau) < 1e-6 * t_conv) or np.any(a <= 0):
            continue
        if best is None or tau[-1] < best[0][-1] - 1e-12 * t_conv:
            best = (tau, a)
    return None if best is None else (best[0] / scale, best[1])


def _undamped(modes):
    """Every zeta below 1e-12: the decay over the shaper is 1 to rounding."""
    return all(zeta < 1e-12 for _, zeta in modes)


def assert_same_shaper(modes):
    times, amplitudes = simultaneous(modes)
    reference_times, reference_amplitudes = scipy_shortest_root(modes)
    if _undamped(modes) and abs(times[1] - reference_times[1]) > abs(
        times[1] - (reference_times[-1] - reference_times[-2])
    ):
        # Undamped, eq. (20) holds for the impulses played backwards as well: the shortest roots
        # come in mirror pairs of one length, and which of the two a solver reaches first from
        # the grid of starts depends on its path. Compare with the mirror image then.
        reference_times = reference_times[-1] - reference_times[::-1]
        reference_amplitudes = reference_amplitudes[::-1]
    assert len(times) == len(reference_times) == len(modes) + 1
    # Times relative to the shaper's length (they scale with 1/omega), amplitudes absolute.
    np.testing.assert_allclose(times, reference_times, rtol=0, atol=1e-10 * reference_times[-1])
    np.testing.assert_allclose(amplitudes, reference_amplitudes, rtol=0, atol=1e-10)
    # And eq. (20) holds: no residual vibration at any mode.
    shaper = ImpulseShaper(tuple(times), tuple(amplitudes))
    for omega, zeta in modes:
        assert residual_vibration(shaper, omega, zeta) < 1e-12


def test_disk_drive_matches_scipys_minpack_root():
    assert_same_shaper(DISK_DRIVE)


def test_three_modes_match_scipys_minpack_root():
    assert_same_shaper(THREE_MODES)


@settings(max_examples=12, deadline=None)
@given(
    omega=st.floats(0.5, 2000.0),
    ratio=st.floats(1.1, 5.0),
    zeta_1=st.floats(0.0, 0.3),
    zeta_2=st.floats(0.0, 0.3),
)
def test_random_two_mode_cases_match_scipys_minpack_root(omega, ratio, zeta_1, zeta_2):
    # Modes an odd ratio apart: undamped, a whole family of shortest roots (see the test below);
    # lightly damped, two impulses nearly merge and their amplitude split is ill-conditioned (two
    # solvers agree to ~1e-6 only). The impulses are compared where they are well defined.
    assume(not (round(ratio) % 2 == 1 and abs(ratio - round(ratio)) <= 1e-9 * ratio))
    assert_same_shaper([(omega, zeta_1), (omega * ratio, zeta_2)])


@pytest.mark.parametrize("ratio", [3.0, 5.0])
def test_undamped_modes_an_odd_ratio_apart_are_cancelled_by_the_zv_length(ratio):
    # The ZV shaper of the lower mode nulls every odd multiple of it, so the shortest roots of
    # eq. (20) include ZV's 1/2, 1/2 at 0 and pi / omega with a third impulse of amplitude 0
    # anywhere between: which one a solver returns is not defined, their length and nulls are.
    modes = [(2.0, 0.0), (2.0 * ratio, 0.0)]
    times, amplitudes = simultaneous(modes)
    assert times[-1] == pytest.approx(math.pi / 2.0, rel=1e-12)
    shaper = ImpulseShaper(tuple(times), tuple(amplitudes))
    for omega, zeta in modes:
        assert residual_vibration(shaper, omega, zeta) < 1e-12


def test_disk_drive_shaper_leaves_no_vibration_at_either_mode():
    shaper = ImpulseShaper(*map(tuple, simultaneous(DISK_DRIVE)))
    for omega, zeta in DISK_DRIVE:
        assert residual_vibration(shaper, omega, zeta) < 1e-12


def test_one_mode_gives_the_closed_form_zv_shaper():
    times, amplitudes = simultaneous([(5.0, 0.1)])
    zv_times, zv_amplitudes = impulse_formulas.zv_dn(5.0, 0.1, 0)
    np.testing.assert_allclose(times, zv_times, rtol=1e-13, atol=0)
    np.testing.assert_allclose(amplitudes, zv_amplitudes, rtol=1e-13, atol=0)


def test_modes_may_be_given_in_any_order():
    assert simultaneous(DISK_DRIVE[::-1]) == simultaneous(DISK_DRIVE)


@pytest.mark.parametrize(
    ("modes", "message"),
    [
        ([], "modes must hold at least 1"),
        ([(1.0, 0.0), (1.0, 0.1)], "modes must have distinct frequencies"),
        ([(1.0, 0.0), (-2.0, 0.0)], r"modes\[1\] omega must be > 0, got -2.0"),
        ([(1.0, 1.2)], r"modes\[0\] zeta must be in \[0, 1\), got 1.2"),
        ([(1.0, float("nan"))], r"modes\[0\] zeta must be a finite real number"),
        ([(1.0,)], r"modes\[0\] must be an \(omega, zeta\) pair"),
        (5.0, "modes must be a sequence of"),
    ],
)
def test_bad_modes_are_refused_naming_the_entry(modes, message):
    with pytest.raises(ValueError, match=message):
        simultaneous(modes)


def test_modes_too_close_for_positive_impulses_are_refused_as_scipy_finds_no_positive_root():
    close = [(1.0, 0.0), (1.00001, 0.0)]
    assert scipy_shortest_root(close) is None
    with pytest.raises(ValueError, match="no simultaneous shaper with 3 positive impulses"):
        simultaneous(close)


def test_least_squares_matches_numpy_on_an_overdetermined_system():
    rng = np.random.default_rng(7)
    a = rng.normal(size=(9, 5))
    b = rng.normal(size=9)
    x = solve_least_squares(a.tolist(), b.tolist())
    np.testing.assert_allclose(x, np.linalg.lstsq(a, b, rcond=None)[0], rtol=1e-12, atol=1e-13)


def test_least_squares_reports_a_rank_deficient_matrix():
    assert solve_least_squares([[1.0, 2.0], [2.0, 4.0], [3.0, 6.0]], [1.0, 2.0, 3.0]) is None
