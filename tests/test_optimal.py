"""Time-optimal rest-to-rest moves and their comparison with shaped bang-bang moves (paper 002)."""

import csv
import io
import json
import math
import warnings
from pathlib import Path

import control
import numpy as np
import pytest
from scipy.linalg import expm

from shapefmu.optimal import (Command, check_optimality, compare_moves, optimal_report, refine_transcription,
                              time_optimal, transcribe)
from shapefmu.plants import Plant, disk_drive, load, pendula, rigid_flexible, ten_pendula
from shapefmu.shapers import convolve_modes, simultaneous

MODELS = Path(__file__).resolve().parent.parent / "models"

# Paper 002, Table I: b2 = -b4i = 2.7e3 /(V s^2), U = 11 V, 2.0 and 3.0 kHz, zeta = 0.01.
B2, U = 2.7e3, 11.0
W1, W2 = 2 * math.pi * 2.0e3, 2 * math.pi * 3.0e3
ZETA = 0.01
# Bang-bang pulses sqrt(X / (U b2)) longer (1.30 ms) and shorter (0.18 ms) than the 0.40 ms shaper.
LONG, SHORT = 0.05, 1e-3


def eq1_matrices(modes):
    """A, B of eq. (1) of paper 002 written out from the paper, for (omega, zeta) modes."""
    n = 2 + 2 * len(modes)
    A = np.zeros((n, n))
    A[0, 1] = 1.0
    B = np.zeros(n)
    B[1] = B2
    for i, (w, z) in enumerate(modes):
        k = 2 + 2 * i
        A[k, k + 1] = 1.0
        A[k + 1, k], A[k + 1, k + 1] = -w * w, -2 * z * w
        B[k + 1] = -B2
    return A, B


def expm_final_state(A, B, solution):
    """Independent exact simulation: e^{A dt} and its integral from scipy's expm of Van Loan's
    block matrix [[A dt, B dt], [0, 0]], segment by segment through the switch instants."""
    n = A.shape[0]
    x = np.zeros(n)
    edges = [0.0, *solution.switch_times, solution.T]
    for level, t0, t1 in zip(solution.levels, edges, edges[1:]):
        block = np.zeros((n + 1, n + 1))
        block[:n, :n], block[:n, n] = A * (t1 - t0), B * (t1 - t0)
        E = expm(block)
        x = E[:n, :n] @ x + E[:n, n] * level
    return x


def assert_at_rest(x, distance, T):
    """Positions (even states) within 1e-9 X of the target, velocities within 1e-9 X / T of 0."""
    target = np.zeros_like(x)
    target[0] = distance
    error = np.abs(x - target)
    assert np.max(error[0::2]) / distance < 1e-9
    assert np.max(error[1::2]) * T / distance < 1e-9


def test_rigid_body_time_is_closed_form():
    X = 0.05
    solution = time_optimal(disk_drive(n_modes=0), X, U)
    assert solution.T == pytest.approx(2 * math.sqrt(X / (U * B2)), rel=1e-9)


def test_rigid_body_switches_once_at_half_time():
    solution = time_optimal(disk_drive(n_modes=0), 0.05, U)
    (switch,) = solution.switch_times
    assert switch == pytest.approx(solution.T / 2, rel=1e-9)
    assert solution.levels == (U, -U)


def test_rigid_plus_one_undamped_mode_ends_at_rest_in_closed_form():
    X = LONG
    solution = time_optimal(rigid_flexible(B2, [(W1, 0.0, -B2)]), X, U)
    # Closed form per constant-input segment: rigid body x += v dt + b u dt^2 / 2, and the undamped
    # mode q'' = -w^2 q - b u oscillating about its static deflection -b u / w^2.
    x, v, q, dq = 0.0, 0.0, 0.0, 0.0
    edges = [0.0, *solution.switch_times, solution.T]
    for u, t0, t1 in zip(solution.levels, edges, edges[1:]):
        dt = t1 - t0
        x, v = x + v * dt + B2 * u * dt * dt / 2, v + B2 * u * dt
        static = -B2 * u / W1**2
        c, s = math.cos(W1 * dt), math.sin(W1 * dt)
        q, dq = static + (q - static) * c + dq / W1 * s, -(q - static) * W1 * s + dq * c
    assert_at_rest(np.array([x, v, q, dq]), X, solution.T)


def test_rigid_plus_one_mode_switches_three_times():
    solution = time_optimal(rigid_flexible(B2, [(W1, 0.0, -B2)]), LONG, U)
    assert len(solution.switch_times) == 3


@pytest.mark.parametrize("distance", [LONG, SHORT])
def test_disk_drive_optimal_move_ends_at_rest_by_expm(distance):
    solution = time_optimal(load(MODELS / "disk_drive.toml"), distance)
    A, B = eq1_matrices([(W1, ZETA), (W2, ZETA)])
    assert_at_rest(expm_final_state(A, B, solution), distance, solution.T)


@pytest.mark.parametrize("n_modes", [3, 4])
def test_rigid_plus_three_and_four_modes_end_at_rest_by_expm(n_modes):
    modes = [(2 * math.pi * f, ZETA) for f in (2.0e3, 3.0e3, 4.5e3, 6.0e3)[:n_modes]]
    solution = time_optimal(rigid_flexible(B2, [(w, z, -B2) for w, z in modes]), SHORT, U)
    assert_at_rest(expm_final_state(*eq1_matrices(modes), solution), SHORT, solution.T)


def test_python_control_double_integrator_gives_closed_form_time():
    solution = time_optimal(control.tf([B2], [1.0, 0.0, 0.0]), LONG, U)
    assert solution.T == pytest.approx(2 * math.sqrt(LONG / (U * B2)), rel=1e-9)


def test_disk_drive_optimal_move_reports_its_residual():
    solution = time_optimal(disk_drive(), LONG, U)
    assert solution.residual < 1e-9
    assert len(solution.final_error) == 6


@pytest.mark.parametrize("distance", [LONG, SHORT])
def test_disk_drive_time_lies_between_rigid_and_simultaneous_shaped(distance):
    solution = time_optimal(disk_drive(), distance, U)
    rigid = 2 * math.sqrt(distance / (U * B2))
    shaper = simultaneous([(W1, ZETA), (W2, ZETA)])
    assert rigid < solution.T < rigid + shaper.duration


def test_back_emf_variant_ends_at_rest_by_expm():
    damping = 9.8e-2**2 / (7.25 * 5e-6)  # Kt^2 / (R J), paper 002 Table I
    solution = time_optimal(load(MODELS / "disk_drive_back_emf.toml"), LONG)
    A, B = eq1_matrices([(W1, ZETA), (W2, ZETA)])
    A[1, 1] = -damping
    assert_at_rest(expm_final_state(A, B, solution), LONG, solution.T)


def test_disk_drive_rigid_part_with_back_emf_switches_once_and_is_slower():
    # With back EMF the rigid body needs a longer push than pull, and more time than without.
    damped = time_optimal(disk_drive(back_emf=True, n_modes=0), LONG, U)
    (switch,) = damped.switch_times
    assert switch > damped.T / 2
    assert damped.T > 2 * math.sqrt(LONG / (U * B2))


def test_plant_without_integrator_holds_the_static_input_after_the_move():
    # Paper 001, eq. (33): closed-loop LSM with DC gain 9.687e7 / 1.016e8; 1 mm needs u = 1/G(0).
    solution = time_optimal(load(MODELS / "linear_synchronous_motor.toml"), 1.0, 2.0)
    assert solution.u_final == pytest.approx(1.016e8 / 9.687e7, rel=1e-12)
    assert solution.residual < 1e-9


@pytest.fixture(scope="module", params=[LONG, SHORT], ids=["long-pulses", "short-pulses"])
def comparison(request):
    modes = [(W1, ZETA), (W2, ZETA)]
    shapers = {"convolution": convolve_modes(modes), "simultaneous": simultaneous(modes)}
    return compare_moves(disk_drive(), request.param, U, shapers)


def _move(comparison, name):
    return next(m for m in comparison.moves if m.name == name)


def test_simultaneous_move_is_shorter_by_the_difference_of_shaper_lengths(comparison):
    modes = [(W1, ZETA), (W2, ZETA)]
    difference = convolve_modes(modes).duration - simultaneous(modes).duration
    conv = _move(comparison, "bang-bang * convolution").duration
    simul = _move(comparison, "bang-bang * simultaneous").duration
    assert conv - simul == pytest.approx(difference, rel=1e-9)


def test_rigid_bang_bang_is_the_closed_form_eq2(comparison):
    rigid = _move(comparison, "rigid bang-bang")
    assert rigid.duration == pytest.approx(2 * math.sqrt(comparison.distance / (U * B2)), rel=1e-9)


def test_unshaped_bang_bang_leaves_vibration_and_shaped_ones_do_not(comparison):
    assert _move(comparison, "rigid bang-bang").residual > 1e-3
    assert _move(comparison, "bang-bang * convolution").residual < 1e-9
    assert _move(comparison, "bang-bang * simultaneous").residual < 1e-9


def test_no_resting_shaped_move_within_the_limit_beats_the_optimum(comparison):
    optimal = _move(comparison, "time-optimal")
    assert optimal.residual < 1e-9
    for move in comparison.moves:
        if move.peak <= U * (1 + 1e-12) and move.residual < 1e-9:
            assert move.duration >= optimal.duration * (1 - 1e-12)


def test_short_move_shaping_costs_more_than_long_move():
    # Pulses shorter than the shaper (paper 002, Sec. II remark after eq. 4) lose more time.
    ratios = {}
    for distance in (LONG, SHORT):
        c = compare_moves(disk_drive(), distance, U, {"simultaneous": simultaneous([(W1, ZETA), (W2, ZETA)])})
        ratios[distance] = _move(c, "bang-bang * simultaneous").duration / c.optimal.T
    assert ratios[SHORT] > ratios[LONG]


def test_shaped_bang_bang_has_the_levels_of_eq21():
    # Long move, simultaneous shaper a1, a2, a3 at 0, T1, T1 + T2: eq. (21) of paper 002.
    shaper = simultaneous([(W1, ZETA), (W2, ZETA)])
    a1, a2, a3 = shaper.amplitudes
    t1 = math.sqrt(LONG / (U * B2))
    command = Command((0.0, t1, 2 * t1), (U, -U)).shaped(shaper)
    expected = [a1, a1 + a2, 1, 1 - 2 * a1, 2 * a3 - 1, -1, -(a2 + a3), -a3]
    assert np.array(command.levels) / U == pytest.approx(expected, rel=1e-12, abs=1e-12)
    assert command.breaks[-1] == pytest.approx(2 * t1 + shaper.duration, rel=1e-15)


def test_csv_signal_table_holds_exact_switch_instants():
    solution = time_optimal(disk_drive(n_modes=1), LONG, U)
    rows = list(csv.DictReader(io.StringIO(solution.to_csv())))
    times = [float(r["time"]) for r in rows]
    assert times == [0.0, *solution.switch_times, solution.T]
    assert [float(r["u"]) for r in rows] == [*solution.levels, 0.0]


def test_json_export_carries_the_switching_structure():
    solution = time_optimal(disk_drive(n_modes=1), LONG, U)
    data = json.loads(solution.to_json())
    assert data["T"] == solution.T and data["switch_times"] == list(solution.switch_times)
    assert data["levels"] == list(solution.levels) and data["residual"] == solution.residual


def test_uncontrollable_plant_is_refused():
    # Two identical modes driven by one input: their difference cannot be controlled.
    plant = rigid_flexible(B2, [(W1, 0.0, -B2), (W1, 0.0, -B2)])
    with pytest.raises(ValueError, match="not controllable"):
        time_optimal(plant, LONG, U)


def test_target_without_rest_state_is_refused():
    # A velocity output cannot rest at a non-zero value.
    plant = Plant([[0, 1], [0, 0]], [[0], [B2]], [[0, 1]], [[0]])
    with pytest.raises(ValueError, match="unreachable target"):
        time_optimal(plant, LONG, U)


def test_target_needing_more_than_u_max_to_hold_is_refused():
    with pytest.raises(ValueError, match="unreachable target.*u_max"):
        time_optimal(load(MODELS / "linear_synchronous_motor.toml"), 10.0, 2.0)


@pytest.mark.parametrize("u_max", [0.0, -1.0, math.nan])
def test_non_positive_u_max_is_refused(u_max):
    with pytest.raises(ValueError, match="u_max"):
        time_optimal(disk_drive(), LONG, u_max)


def test_optimal_report_prints_table_and_switches(tmp_path):
    text = optimal_report(MODELS / "disk_drive.toml", LONG, plot=tmp_path / "moves.png")
    assert "time-optimal" in text and "5 switches" in text
    assert (tmp_path / "moves.png").stat().st_size > 0


@pytest.mark.parametrize("distance", [LONG, SHORT])
def test_disk_drive_move_passes_pontryagin_and_no_shorter_move_exists(distance):
    solution = time_optimal(disk_drive(), distance, U)
    check = check_optimality(disk_drive(), solution, shorter=1e-4)
    assert check.sigma_at_switches < 1e-9  # sigma vanishes at every switch ...
    assert check.sign_margin > 1e-6  # ... and has the sign of u on every arc
    assert check.dual_peak_at_shorter > U  # weak duality: T (1 - 1e-4) needs more than U
    assert check.lp_peak_at_shorter > U  # and a fine grid LP finds no such move either


def test_casadi_transcription_refines_to_the_same_move():
    # Second method for the structure: free-final-time CasADi transcription, refined the same way.
    casadi = refine_transcription(disk_drive(), transcribe(disk_drive(), LONG, U, 100), n_samples=2)
    lp = time_optimal(disk_drive(), LONG, U, n_samples=2)
    assert casadi.T == pytest.approx(lp.T, rel=1e-12)
    assert casadi.switch_times == pytest.approx(lp.switch_times, rel=1e-10)


# Ten-pendula comb (paper 003): 1.7 m at the peak acceleration of its M-BC:TZ:TP profile.
PENDULA_U = 0.26


def pendula_matrices():
    """A, B of the comb written out from L theta'' + g theta = -a, x'' = a."""
    from shapefmu.plants.library import TEN_PENDULA_LENGTHS

    n = 2 + 2 * len(TEN_PENDULA_LENGTHS)
    A, B = np.zeros((n, n)), np.zeros(n)
    A[0, 1], B[1] = 1.0, 1.0
    for i, length in enumerate(TEN_PENDULA_LENGTHS):
        k = 2 + 2 * i
        A[k, k + 1], A[k + 1, k], B[k + 1] = 1.0, -9.80665 / length, -1.0 / length
    return A, B


@pytest.fixture(scope="module", params=[1.7, 3.0], ids=["1.7m-21-switches", "3.0m-23-switches"])
def ten_pendula_move(request):
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # neither off rest nor longer than the grid's move
        return request.param, time_optimal(ten_pendula(), request.param, PENDULA_U)


def test_ten_pendula_move_ends_at_rest_by_expm(ten_pendula_move):
    distance, solution = ten_pendula_move
    assert_at_rest(expm_final_state(*pendula_matrices(), solution), distance, solution.T)
    # 22 states: 21 switches; the longer move adds a short pulse pair (sigma vanishes at 23 points).
    assert len(solution.switch_times) == {1.7: 21, 3.0: 23}[distance]


def test_ten_pendula_move_is_antisymmetric_about_half_time(ten_pendula_move):
    # Undamped plant, rest to rest: -u(T - t) is also optimal (time reversal), and the optimum is
    # unique, so u(T - t) = -u(t): switches mirror about T / 2 and the levels alternate in sign.
    _, solution = ten_pendula_move
    switches = np.array(solution.switch_times)
    assert switches + switches[::-1] == pytest.approx(np.full(switches.size, solution.T), abs=1e-9 * solution.T)
    assert solution.levels == tuple(PENDULA_U * (-1) ** k for k in range(switches.size + 1))


def test_ten_pendula_move_passes_pontryagin_and_no_shorter_move_exists(ten_pendula_move):
    distance, solution = ten_pendula_move
    check = check_optimality(ten_pendula(), solution, shorter=1e-4)
    assert check.sigma_at_switches < 1e-9
    assert check.sign_margin > 1e-6
    assert check.dual_peak_at_shorter > PENDULA_U  # weak duality: T (1 - 1e-4) needs more than U
    assert check.lp_peak_at_shorter > PENDULA_U
    # The grid's move is feasible, so the optimum is no longer than it.
    assert solution.T <= solution.transcription_T


def test_three_pendula_move_passes_pontryagin_and_no_shorter_move_exists():
    plant = pendula([0.7, 0.8, 0.9])
    solution = time_optimal(plant, 1.0, 0.5)
    check = check_optimality(plant, solution)
    assert solution.residual < 1e-9
    assert check.sign_margin > 0 and check.dual_peak_at_shorter > 0.5 and check.lp_peak_at_shorter > 0.5
