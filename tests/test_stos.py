"""STOS (paper 002): switching curves against the paper's closed forms and exact simulation of the
shaped bang-bang, the law against eqs. (18)/(22), and the sampled loop on the disk drive of Table I
against the unshaped rigid bang-bang and the CasADi time-optimal move."""

import json
import math

import numpy as np
import pytest

from shapefmu.cli import main
from shapefmu.optimal import rigid_bang_bang, simulate, time_optimal
from shapefmu.plants import library
from shapefmu.runtime.stos import STOSKernel, locate, mid_curve, stos_curves, stos_fraction
from shapefmu.shapers import ImpulseShaper, convolve_modes, simultaneous, zvd
from shapefmu.stos import (
    design_settle,
    rigid_bang_bang_residual,
    simulate_stos,
    step,
    stos_law,
    with_mode_error,
)

B2, U = library.DISK_DRIVE_B2, library.DISK_DRIVE_U
BU = B2 * U
ZETA = library.DISK_DRIVE_ZETA
# Eq. (4) needs T1 < T2: "mode 1" of the convolution formulas is the higher (3 kHz) mode.
MODES = [(2 * math.pi * 3.0e3, ZETA), (2 * math.pi * 2.0e3, ZETA)]
X = 0.1  # rad: t1 = 1.83 ms > the shaper lengths (0.42 ms), the paper's assumption
VELOCITIES = np.linspace(0.0, 60.0, 25)


def _zv(zeta):
    K = math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2))
    return 1 / (1 + K), K / (1 + K)


def _close(a, b, rel=1e-12):
    assert a == pytest.approx(b, rel=rel, abs=rel * 1e-3)


# --------------------------------------------------------------------------------------------
# Switching curves against the closed forms of the paper


def test_convolution_curves_equal_eqs_7_to_16():
    a1, a2 = _zv(ZETA)
    a3, a4 = a1, a2
    T1, T2 = (math.pi / (w * math.sqrt(1 - z * z)) for w, z in MODES)
    shaper = convolve_modes(MODES)
    curves = stos_curves(B2, U, shaper.times, shaper.amplitudes)
    _close(curves["v_accel"][0], a1 * a3 * BU * T1)  # eq. (7)
    _close(curves["v_accel"][1], -a2 * a3 * BU * T1 + a3 * BU * T2)  # eq. (8)
    _close(curves["v_accel"][2], a1 * BU * T1 + a3 * BU * T2)  # eq. (9)
    _close(curves["v_decel"][0], a2 * BU * T1 + a4 * BU * T2)  # eq. (10)
    _close(curves["v_decel"][1], -a1 * a4 * BU * T1 + a4 * BU * T2)  # eq. (11)
    _close(curves["v_decel"][2], a2 * a4 * BU * T1)  # eq. (12)
    q = lambda v: -v * v / (2 * BU)  # noqa: E731
    paper = [
        lambda v: q(v) - 2 * (a2 * T1 + a4 * T2) * v - 2 * a2 * a4 * BU * T1 * T2  # eq. (13)
        - 0.5 * a2 * (3 * a2 - 1) * BU * T1**2 - 0.5 * a4 * (3 * a4 - 1) * BU * T2**2,
        lambda v: q(v) + 2 * a4 * (a1 * T1 - T2) * v  # eq. (14)
        + 0.5 * a1 * (a4 - a3) * (a2 - 2 * a1 * a4) * BU * T1**2 + 2 * a1 * a4 * (a4 - a3) * BU * T1 * T2
        + 0.5 * a4 * (1 - 3 * a4) * BU * T2**2,
        lambda v: q(v) - 2 * a2 * a4 * T1 * v - 0.5 * a3 * a4 * BU * T2**2  # eq. (15)
        + 0.5 * a2 * (a4 - a3) * (a1 - 2 * a2 * a4) * BU * T1**2,
        lambda v: q(v) - 0.5 * a1 * a2 * BU * T1**2 - 0.5 * a3 * a4 * BU * T2**2,  # eq. (16)
    ]
    for k, closed_form in enumerate(paper):
        for v in VELOCITIES:
            _close(mid_curve(curves, k, v), closed_form(v))


def test_simultaneous_curves_equal_S1_to_S7():
    shaper = simultaneous(MODES)
    a1, a2, a3 = shaper.amplitudes
    T1, T2 = shaper.times[1], shaper.times[2] - shaper.times[1]
    curves = stos_curves(B2, U, shaper.times, shaper.amplitudes)
    _close(curves["v_accel"][0], a1 * BU * T1)  # S1
    _close(curves["v_accel"][1], a1 * BU * T1 + (a1 + a2) * BU * T2)  # S2
    _close(curves["v_decel"][0], (1 - a1) * BU * T1 + a3 * BU * T2)  # S6
    _close(curves["v_decel"][1], a3 * BU * T2)  # S7
    q = lambda v: -v * v / (2 * BU)  # noqa: E731
    paper = [
        lambda v: q(v) + 2 * ((a1 - 1) * T1 - a3 * T2) * v + 0.5 * (a1 - 1) * (2 - 3 * a1) * BU * T1**2  # S3
        + 0.5 * a3 * (1 - 3 * a3) * BU * T2**2 + a3 * (3 * a1 - 2) * BU * T1 * T2,
        lambda v: q(v) - 2 * a3 * T2 * v + 0.5 * a1 * (a1 - 1) * BU * T1**2  # S4
        + 0.5 * a3 * (1 - 3 * a3) * BU * T2**2 - a1 * a3 * BU * T1 * T2,
        lambda v: q(v) + 0.5 * a1 * (a1 - 1) * BU * T1**2 - 0.5 * a3 * (a1 + a2) * BU * T2**2  # S5
        - a1 * a3 * BU * T1 * T2,
    ]
    for k, closed_form in enumerate(paper):
        for v in VELOCITIES:
            _close(mid_curve(curves, k, v), closed_form(v))


SHAPERS = {
    "convolution": convolve_modes(MODES),
    "simultaneous": simultaneous(MODES),
    "zvd per mode": convolve_modes(MODES, base=zvd),
}


def _shaped_bang_bang(shaper, damping, distance):
    rigid = library.rigid_flexible(B2, [], damping, u_max=U)
    command = rigid_bang_bang(rigid, distance)
    return rigid, command, command.shaped(shaper)


@pytest.mark.parametrize("damping", [0.0, library.DISK_DRIVE_KT**2 / (library.DISK_DRIVE_R * library.DISK_DRIVE_J)])
@pytest.mark.parametrize("name", list(SHAPERS))
def test_curves_hold_the_states_of_the_exactly_simulated_shaped_bang_bang(name, damping):
    """The second method: every switching state of the shaped bang-bang (exact matrix exponentials),
    for two move lengths, lies on its curve, also with back EMF where no closed form is printed."""
    shaper = SHAPERS[name]
    curves = stos_curves(B2, U, shaper.times, shaper.amplitudes, damping)
    for distance in (X, 3 * X):
        _, command, shaped = _shaped_bang_bang(shaper, damping, distance)
        t1, t2 = command.breaks[1], command.breaks[2]
        states = simulate(library.rigid_flexible(B2, [], damping, u_max=U), shaped)
        at = dict(zip(np.round(np.array(shaped.breaks) * 1e9), states))
        for k, tau in enumerate(shaper.times):
            x_e, v = at[round((t1 + tau) * 1e9)] - [distance, 0.0]
            assert mid_curve(curves, k, v) == pytest.approx(x_e, abs=1e-11 * distance)
            v_tail = at[round((t2 + tau) * 1e9)][1]
            assert curves["v_decel"][k] == pytest.approx(v_tail, abs=1e-9 * BU * shaper.duration)
            if k:
                assert curves["v_accel"][k - 1] == pytest.approx(at[round(tau * 1e9)][1], rel=1e-10)
        assert curves["min_distance"] <= distance


@pytest.mark.parametrize("name", list(SHAPERS))
def test_law_applies_the_shaped_bang_bang_along_its_own_trajectory(name):
    shaper = SHAPERS[name]
    curves = stos_curves(B2, U, shaper.times, shaper.amplitudes)
    rigid, _, shaped = _shaped_bang_bang(shaper, 0.0, X)
    mid = 0.5 * (np.array(shaped.breaks[:-1]) + np.array(shaped.breaks[1:]))
    _, states = simulate(rigid, shaped, mid)
    # The -U phase runs along the last middle curve itself (it is that curve), so rounding may
    # put the simulated state 1e-17 to either side: a margin of 1e-12 X settles it.
    margin = 1e-12 * X
    for level, (x_r, v) in zip(shaped.levels, states):
        assert U * stos_fraction(curves, x_r - X, v, margin) == pytest.approx(level, rel=1e-9, abs=1e-9)
        # eq. (19): the negative move is the mirror image
        assert U * stos_fraction(curves, X - x_r, -v, margin) == pytest.approx(-level, rel=1e-9, abs=1e-9)


# --------------------------------------------------------------------------------------------
# Eqs. (17), (18) and (22) as printed, and their two OCR'd coefficients


def _sgn(x):
    return float(np.sign(x))


def _eq18(curves, a, x_e, v, last_level):
    """f1 of eq. (18) for the convolution shaper, transcribed; ``last_level`` is its a2a3 (printed)
    or a2a4 (eq. 4)."""
    a1, a2, a3, a4 = a
    S = lambda k: mid_curve(curves, k, v)  # noqa: E731  S4..S7 = middle curves 0..3
    A, B, C = (_sgn(v - s) for s in curves["v_accel"])
    Q, R, Sv = (_sgn(v - s) for s in curves["v_decel"][:3])
    D, E, G, H = (_sgn(S(k) - x_e) for k in range(4))
    sg = _sgn
    return (U * D * sg(D + 1) * (sg(C + 1) + H * sg(H + 1) * ((a1 + a2 * a3) * C * sg(B + 1) * sg(C - 1)
                                                               + a3 * B * sg(A + 1) * sg(B - 1)
                                                               + a1 * a3 * A * sg(A - 1)))
            - U * Q * sg(Q + 1) * (-sg(H - 1) + (a4 - a3) * G * H * sg(E - 1) * sg(G + 1) * sg(H + 1)
                                   + (2 * a2 * a4 - 1) * H * sg(G - 1) * sg(H + 1))
            - (1 - 2 * a1 * a3) * U * B * E * H * sg(B + 1) * sg(D - 1) * sg(E + 1) * sg(H + 1)
            + U * H * sg(H - 1) * ((a2 * a3 + a4) * R * sg(Q - 1) * sg(R + 1) + a4 * Sv * sg(R - 1) * sg(Sv + 1)
                                   + last_level * sg(Sv - 1)))


def _eq22(curves, a, x_e, v, first_level):
    """f1 of eq. (22) for the simultaneous shaper; ``first_level`` is its (a2 + a3) (printed) or a1."""
    a1, a2, a3 = a
    sg = _sgn
    A, B = (_sgn(v - s) for s in curves["v_accel"])
    G, H = (_sgn(v - s) for s in curves["v_decel"][:2])
    C, D, E = (_sgn(mid_curve(curves, k, v) - x_e) for k in range(3))
    return (U * C * sg(C + 1) * (first_level * A * E * sg(A - 1) * sg(E + 1)
                                 + (a1 + a2) * B * E * sg(A + 1) * sg(B - 1) * sg(E + 1) + sg(B + 1))
            + U * G * sg(G + 1) * ((2 * a1 - 1) * D * E * sg(C - 1) * sg(D + 1) * sg(E + 1)
                                   + (1 - 2 * a3) * E * sg(D - 1) * sg(E + 1) + sg(E - 1))
            + U * E * sg(E - 1) * ((a2 + a3) * H * sg(G - 1) * sg(H + 1) + a3 * sg(H - 1)))


def test_eq_18_last_level_is_a2a4_as_in_eq_4_not_the_printed_a2a3():
    a1, a2 = _zv(ZETA)
    a = (a1, a2, a1, a2)
    shaper = SHAPERS["convolution"]
    curves = stos_curves(B2, U, shaper.times, shaper.amplitudes)
    rigid, _, shaped = _shaped_bang_bang(shaper, 0.0, X)
    # The exact shaped bang-bang ends with -a2 a4 U (eq. 4), which brings S10 = a2 a4 U b2 T1 to rest.
    assert shaped.levels[-1] == pytest.approx(-a2 * a2 * U, rel=1e-12)
    assert simulate(rigid, shaped)[-1] == pytest.approx([X, 0.0], abs=1e-12)
    mid = 0.5 * (shaped.breaks[-2] + shaped.breaks[-1])
    x_r, v = simulate(rigid, shaped, [mid])[1][0]
    assert _eq18(curves, a, x_r - X, v, a2 * a2) == pytest.approx(shaped.levels[-1], rel=1e-12)
    assert _eq18(curves, a, x_r - X, v, a2 * a1) != pytest.approx(shaped.levels[-1], rel=1e-3)
    # With that coefficient eq. (18) is this law wherever eq. (18) assigns a level.
    rng = np.random.default_rng(6)
    compared = 0
    for x_e, v in zip(-rng.uniform(0, X, 4000), rng.uniform(0, 60, 4000)):
        paper = _eq18(curves, a, x_e, v, a2 * a2)
        if paper != 0.0:
            assert U * stos_fraction(curves, x_e, v) == pytest.approx(paper, rel=1e-12)
            compared += 1
    assert compared > 3000


def test_eq_22_first_level_is_a1_as_in_eq_21_not_the_printed_a2_plus_a3():
    shaper = SHAPERS["simultaneous"]
    a = shaper.amplitudes
    curves = stos_curves(B2, U, shaper.times, shaper.amplitudes)
    rigid, _, shaped = _shaped_bang_bang(shaper, 0.0, X)
    assert shaped.levels[0] == pytest.approx(a[0] * U, rel=1e-12)  # eq. (21); reaches S1 = a1 U b2 T1
    x_r, v = simulate(rigid, shaped, [0.5 * shaped.breaks[1]])[1][0]
    assert _eq22(curves, a, x_r - X, v, a[0]) == pytest.approx(shaped.levels[0], rel=1e-12)
    assert _eq22(curves, a, x_r - X, v, a[1] + a[2]) != pytest.approx(shaped.levels[0], rel=1e-3)
    rng = np.random.default_rng(22)
    compared = 0
    for x_e, v in zip(-rng.uniform(0, X, 4000), rng.uniform(0, 60, 4000)):
        paper = _eq22(curves, a, x_e, v, a[0])
        if paper != 0.0:
            assert U * stos_fraction(curves, x_e, v) == pytest.approx(paper, rel=1e-12)
            compared += 1
    assert compared > 3000


def test_first_and_third_quadrants_and_the_axes_follow_eq_17():
    curves = stos_curves(B2, U, *zip(*[(0.0, 0.5), (1e-4, 0.5)]))
    assert stos_fraction(curves, 1e-3, 1.0) == -1.0
    assert stos_fraction(curves, -1e-3, -1.0) == 1.0
    assert stos_fraction(curves, 0.0, 2.0) == -1.0
    assert stos_fraction(curves, 0.0, -2.0) == 1.0
    assert stos_fraction(curves, 0.0, 0.0) == 0.0
    assert locate(curves, 1e-3, 1.0)[0] == 0


# --------------------------------------------------------------------------------------------
# Sampled closed loop on the disk drive of Table I


@pytest.fixture(scope="module")
def disk_drive():
    return library.disk_drive()


@pytest.fixture(scope="module")
def nominal_runs(disk_drive):
    runs = {}
    for kind in ("convolution", "simultaneous"):
        law = stos_law(disk_drive, kind, Ts=1e-6)
        runs[kind] = (law, simulate_stos(disk_drive, law, X, 1e-6, 6.5e-3, tolerance=1e-5))
    return runs


@pytest.mark.parametrize("kind", ["convolution", "simultaneous"])
def test_residual_vibration_is_below_one_percent_of_the_unshaped_rigid_bang_bang(disk_drive, nominal_runs, kind):
    _, rigid = rigid_bang_bang_residual(disk_drive, X, 1e-6)
    _, run = nominal_runs[kind]
    # Unshaped, the modes are left ringing at the scale of b4 U / omega^2 (here ~1e-4 rad).
    assert min(rigid) > 1e-5
    ratios = np.array(run.metrics.residual_vibration) / np.array(rigid)
    assert np.all(ratios < 0.01), ratios
    assert not math.isnan(run.metrics.handover_time)


@pytest.mark.parametrize("kind", ["convolution", "simultaneous"])
def test_move_time_is_within_rigid_optimum_plus_shaper_plus_two_samples(disk_drive, nominal_runs, kind):
    law, run = nominal_runs[kind]
    rigid_T = 2 * math.sqrt(X / BU)  # eq. (2)
    assert run.metrics.move_time <= rigid_T + law.shaper.duration + 2e-6
    # It cannot beat the rigid optimum by more than the time the tight band forgives.
    assert run.metrics.move_time > rigid_T
    assert run.metrics.peak_u == pytest.approx(U)


def test_simultaneous_stos_is_faster_than_convolution_stos(nominal_runs):
    fast, slow = nominal_runs["simultaneous"][1].metrics, nominal_runs["convolution"][1].metrics
    lengths = nominal_runs["convolution"][0].shaper.duration - nominal_runs["simultaneous"][0].shaper.duration
    assert fast.move_time < slow.move_time
    # The difference is the difference of the shaper lengths (16.7 us), to a few samples.
    assert slow.move_time - fast.move_time == pytest.approx(lengths, abs=3e-6)


def test_stos_is_slower_than_the_casadi_time_optimal_move_of_the_full_plant(disk_drive, nominal_runs):
    optimal = time_optimal(disk_drive, X)
    for law, run in nominal_runs.values():
        ratio = run.metrics.move_time / optimal.T
        assert 1.0 < ratio < (2 * math.sqrt(X / BU) + law.shaper.duration + 2e-6) / optimal.T


def test_negative_move_mirrors_the_positive_one(disk_drive, nominal_runs):
    law, run = nominal_runs["simultaneous"]
    mirrored = simulate_stos(disk_drive, law, -X, 1e-6, 6.5e-3, tolerance=1e-5)
    np.testing.assert_allclose(mirrored.x, -run.x, atol=1e-12)
    assert mirrored.metrics.move_time == run.metrics.move_time


def test_back_emf_stos_removes_the_vibration_of_its_own_rigid_bang_bang():
    plant = library.disk_drive(back_emf=True)
    rigid_T, rigid = rigid_bang_bang_residual(plant, X, 1e-6)
    law = stos_law(plant, "convolution", Ts=1e-6)
    run = simulate_stos(plant, law, X, 1e-6, 6e-3, tolerance=1e-5)
    assert np.all(np.array(run.metrics.residual_vibration) < 0.01 * np.array(rigid))
    assert rigid_T < run.metrics.move_time <= rigid_T + law.shaper.duration + 2e-6


@pytest.fixture(scope="module")
def coarse_law(disk_drive):
    return stos_law(disk_drive, "simultaneous", Ts=20e-6)


@pytest.mark.parametrize("factor", [0.95, 1.05])
@pytest.mark.parametrize("torque", [1.1, -1.1])
def test_settles_to_a_tenth_of_a_percent_under_sampling_mode_error_and_torque_step(
        disk_drive, coarse_law, factor, torque):
    plant = with_mode_error(disk_drive, factor)
    run = simulate_stos(plant, coarse_law, X, 20e-6, 0.03, disturbance=step(2.01e-3, torque))
    m = run.metrics
    assert m.final_error < 1e-3
    assert m.move_time < 0.02
    assert m.chattering == 0
    # The settle controller holds the 10 % torque step with its integrator: u -> -torque.
    assert run.u[-1] == pytest.approx(-torque, rel=1e-3)


def test_without_the_settle_controller_the_sampled_law_chatters(disk_drive, coarse_law):
    bare = type(coarse_law)(coarse_law.shaper, coarse_law.curves, None)
    run = simulate_stos(with_mode_error(disk_drive, 1.05), bare, X, 20e-6, 0.03, disturbance=step(2.01e-3, 1.1))
    assert run.metrics.chattering > 50
    assert np.count_nonzero(np.abs(run.u[-500:]) == U) > 100


@pytest.mark.parametrize("new_target", [0.15, 0.04])
def test_set_point_change_mid_move_is_followed_without_redesign(disk_drive, coarse_law, new_target):
    run = simulate_stos(disk_drive, coarse_law, X, 20e-6, 0.03, setpoint_changes=[(1.5e-3, new_target)])
    assert abs(run.x_r[-1] - new_target) < 1e-3 * new_target
    assert run.metrics.final_error < 1e-3
    assert run.metrics.chattering == 0


# --------------------------------------------------------------------------------------------
# Kernel state, serialisation, settle design


def test_kernel_state_round_trip_reproduces_the_run(coarse_law):
    """get_state / set_state capture everything: a fresh kernel (built from the JSON of the law)
    restored to the state before any sample gives that sample's output exactly."""
    kernel = coarse_law.kernel()
    x, v, record = -X, 0.0, []
    for _ in range(400):
        before = kernel.get_state()
        u = kernel.control(0.0, x, v)
        record.append((before, x, v, u))
        x, v = x + v * 2e-5 + 0.5 * B2 * u * 4e-10, v + B2 * u * 2e-5
    assert kernel.get_state()[0] == 1.0 and kernel.get_state()[1] != 0.0  # settle controller reached
    law = json.loads(coarse_law.to_json())
    replay = STOSKernel(law["curves"], law["settle"])
    for before, x, v, u in record[::7]:
        replay.set_state(before)
        assert replay.control(0.0, x, v) == u
    replay.reset()
    assert replay.get_state() == [0.0, 0.0]
    with pytest.raises(ValueError, match="state"):
        replay.set_state([0.5, 0.0])


def test_settle_poles_sit_at_the_designed_place():
    settle = design_settle(B2, U, 20e-6, bandwidth=1000.0)
    Ts = settle["Ts"]
    A = np.array([[1.0, Ts, 0.0], [0.0, 1.0, 0.0], [Ts, 0.0, 1.0]])  # exact ZOH of b/s^2 + integrator
    B = np.array([B2 * Ts**2 / 2, B2 * Ts, 0.0])
    K = np.array([settle["kp"], settle["kd"], settle["ki"]])
    poles = np.linalg.eigvals(A - np.outer(B, K))
    np.testing.assert_allclose(poles, math.exp(-1000.0 * Ts), atol=1e-4)
    assert settle["kp"] * settle["x_enter"] == pytest.approx(0.5 * U)


# --------------------------------------------------------------------------------------------
# Bad input


def test_negative_shaper_amplitude_is_refused():
    with pytest.raises(ValueError, match=r"amplitudes\[1\]"):
        stos_curves(B2, U, [0.0, 1e-4, 2e-4], [0.6, -0.2, 0.6])
    with pytest.raises(ValueError, match="shaper must be"):
        stos_law(library.disk_drive(), "no-such-shaper")


@pytest.mark.parametrize("b, u_max, name", [(0.0, U, "b"), (B2, -1.0, "U")])
def test_non_positive_gain_or_limit_is_refused(b, u_max, name):
    with pytest.raises(ValueError, match=f"^{name} must be > 0"):
        stos_curves(b, u_max, [0.0], [1.0])


def test_zero_move_and_bad_sampling_period_are_refused(disk_drive, coarse_law):
    with pytest.raises(ValueError, match="X must be non-zero"):
        simulate_stos(disk_drive, coarse_law, 0.0, 1e-6, 1e-3)
    with pytest.raises(ValueError, match="Ts must be > 0"):
        simulate_stos(disk_drive, coarse_law, X, 0.0, 1e-3)
    with pytest.raises(ValueError, match="Ts must be > 0"):
        stos_law(disk_drive, "simultaneous", Ts=-1e-6)


def test_plant_without_rigid_body_mode_is_refused():
    with pytest.raises(ValueError, match="no rigid-body mode"):
        stos_law(library.linear_synchronous_motor(), ImpulseShaper((0.0,), (1.0,)), u_max=1.0)


def test_cli_prints_the_move_and_plots(tmp_path, capsys):
    png = tmp_path / "stos.png"
    assert main(["stos", "models/disk_drive.toml", "--distance", "0.1", "--shaper", "simultaneous",
                 "--plot", str(png)]) == 0
    out = capsys.readouterr().out
    assert "move time" in out and "/ unshaped rigid bang-bang" in out
    assert png.stat().st_size > 10_000
    with pytest.raises(SystemExit) as exit_:
        main(["stos", "models/disk_drive.toml", "--distance", "0", "--shaper", "convolution"])
    assert exit_.value.code == 2
