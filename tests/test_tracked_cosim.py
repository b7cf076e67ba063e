"""The TrackedShaper FMU in closed loop with the printer-bed plant FMU through our master (issue 37): the
EKF inside watches the bed's accelerometer during the machine's own moves, from a guess 10 % off.

References: the residual of each move from the closed-form response of the true mode to the command the
plant FMU received (tests/test_moving_mode_cosim.py's ``vibration_left``), and the true frequency,
30 / sqrt(1 + grams / 1000) Hz (sqrt(k / m) of models/printer_bed.toml).
"""

import math

import numpy as np
import pytest
from test_fmu_scheduled_shaper import TS, player
from test_moving_mode_cosim import ONE, vibration_left

from shapefmu.plants import load_scheduled

MOVES = 6
GRAMS = 150.0  # on the bed from the start: 30 / sqrt(1.15) = 27.98 Hz
GUESS = 1.1 * 30.0 / math.sqrt(1.0 + GRAMS / 1000.0)  # 10 % off


def run_loop_in_master(folder, guess, commands, loads):
    """(command the bed received, the shaper's f) of the loop run in our master: the moves and the load
    played by ReferencePlayers, the bed's accelerometer fed back to the shaper, guessing ``guess`` Hz."""
    from shapefmu.cosim.master import simulate
    from shapefmu.fmi import build_fmu
    from shapefmu.fmi.native import build_plant_fmu, model_from_file
    from shapefmu.fmi.ssp import System

    system = (System("tracked")
              .add("command", player(folder, "command", commands))
              .add("load", player(folder, "load", loads))
              .add("shaper", build_fmu("TrackedShaper", folder / "TrackedShaper.fmu", f0=guess, Ts=TS))
              .add("bed", build_plant_fmu(model_from_file("printer_bed"), folder / "printer_bed.fmu"))
              .connect("command.y", "shaper.u").connect("bed.bed_acceleration", "shaper.measurement")
              .connect("shaper.y", "bed.acceleration").connect("load.y", "bed.added_mass"))
    result = simulate(system, (commands.size - 1) * TS, TS, record=["bed.acceleration", "shaper.f"])
    return np.asarray(result["bed.acceleration"], float), np.asarray(result["shaper.f"], float)


def residuals(received, commands, loads, moves):
    """Per move: the vibration the bed's command leaves on the true mode of the move's load, over that of
    the move unshaped (closed form). Row k + 1 of the bed's input is the command of the shaper's sample k
    (our master steps the bed first, with the shaper's output of the step before): one sample later."""
    bed = load_scheduled("printer_bed")
    result = []
    for i in range(moves):
        ((omega, zeta),) = bed.flexible_modes_at(loads[i * ONE.size + ONE.size // 2])
        move = commands[i * ONE.size:(i + 1) * ONE.size]
        shaped = received[i * ONE.size + 1:(i + 1) * ONE.size + 1]
        result.append(vibration_left(shaped, omega, zeta) / vibration_left(move, omega, zeta))
    return np.array(result)


@pytest.fixture(scope="module")
def loop(tmp_path_factory):
    """The guess 10 % off, 150 g on the bed from the first rest: (received, f, commands, loads)."""
    commands = np.concatenate([ONE * (-1) ** i for i in range(MOVES)])
    loads = np.where(np.arange(commands.size) < 5, 0.0, GRAMS)
    return (*run_loop_in_master(tmp_path_factory.mktemp("tracked"), GUESS, commands, loads), commands, loads)


def test_from_a_guess_10_percent_off_the_estimate_converges_in_the_first_move(loop):
    _, f, _, _ = loop
    truth = 30.0 / math.sqrt(1.0 + GRAMS / 1000.0)
    assert f[0] == pytest.approx(GUESS)
    end_of_first = ONE.size - 1
    assert abs(f[end_of_first] / truth - 1.0) < 2e-3
    # the later moves' rings move it by at most half a percent (0.5 % at the start of the sixth move)
    assert np.all(np.abs(f[end_of_first:] / truth - 1.0) < 1e-2)


def test_every_move_after_the_first_leaves_under_a_tenth_of_a_percent(loop):
    """The bed's command per move against the closed form of its true mode: the first move is shaped
    for the guess while the EKF learns (3.9 %), the others for the estimate (0.03 % each; the design
    layer: 4-5 % on the first move, then under 1 %, tests/test_tracked_shaper.py)."""
    received, _, commands, loads = loop
    left = residuals(received, commands, loads, MOVES)
    assert left[0] < 0.05
    assert max(left[1:]) < 1e-3


def test_300_g_put_on_mid_print_is_recovered_within_three_moves(tmp_path):
    """Three moves on the empty bed, its guess right, then 300 g on it (30 -> 26.3 Hz) during a rest:
    the move after the change is shaped for the old mode (8.1 %), the EKF learns the new one from its
    ring, and the next move leaves 0.12 %: recovered in one move, the issue asks for three (the design
    layer, with accelerometer noise: 7.6 % on the next move, about 1 % on the ones after)."""
    moves = 7
    commands = np.concatenate([ONE * (-1) ** i for i in range(moves)])
    loads = np.where(np.arange(commands.size) < 3 * ONE.size - 100, 0.0, 300.0)
    received, f = run_loop_in_master(tmp_path, 30.0, commands, loads)
    left = residuals(received, commands, loads, moves)
    assert max(left[:3]) < 1e-3 and left[3] > 0.05  # the old mode's shaper leaves what a fixed one would
    assert max(left[4:]) < 2e-3
    assert f[-1] == pytest.approx(30.0 / math.sqrt(1.3), rel=1e-4)
