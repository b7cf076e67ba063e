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


def run_loop_in_master(folder, guess, commands, loads, plant="printer_bed", measure="bed_acceleration", ts=TS,
                       build="pythonfmu", **tracking):
    """(command the plant received, the shaper's f) of the loop run in our master: the moves (and the
    load, unless ``loads`` is None: the scheduling input then holds its start) played by ReferencePlayers,
    the plant's ``measure`` fed back to the TrackedShaper guessing ``guess`` Hz (``tracking``: its other
    start values), the pythonfmu FMU or (``build="native"``) its native C twin."""
    from shapefmu.cosim.master import simulate
    from shapefmu.fmi import build_fmu
    from shapefmu.fmi.native import build_plant_fmu, model_from_file
    from shapefmu.fmi.native.twins import build_native
    from shapefmu.fmi.ssp import System

    builder = build_native if build == "native" else build_fmu
    shaper = builder("TrackedShaper", folder / "TrackedShaper.fmu", f0=guess, Ts=ts, **tracking)
    system = (System("tracked")
              .add("command", player(folder, "command", commands, ts))
              .add("shaper", shaper)
              .add("plant", build_plant_fmu(model_from_file(plant), folder / f"{plant}.fmu"))
              .connect("command.y", "shaper.u").connect(f"plant.{measure}", "shaper.measurement")
              .connect("shaper.y", "plant.acceleration"))
    if loads is not None:
        system.add("load", player(folder, "load", loads, ts)).connect("load.y", "plant.added_mass")
    result = simulate(system, (commands.size - 1) * ts, ts, record=["plant.acceleration", "shaper.f"])
    return np.asarray(result["plant.acceleration"], float), np.asarray(result["shaper.f"], float)


def residuals(received, commands, loads, moves, plant="printer_bed", one=ONE, ts=TS):
    """Per move (``one`` long): the vibration the plant's command leaves on the true mode of the move's
    scheduling value, over that of the move unshaped (closed form). Row k + 1 of the plant's input is the
    command of the shaper's sample k (our master steps the plant first, with the shaper's output of the
    step before): one sample later."""
    scheduled = load_scheduled(plant)
    result = []
    for i in range(moves):
        ((omega, zeta),) = scheduled.flexible_modes_at(loads[i * one.size + one.size // 2])
        move = commands[i * one.size:(i + 1) * one.size]
        shaped = received[i * one.size + 1:(i + 1) * one.size + 1]
        result.append(vibration_left(shaped, omega, zeta, fs=1.0 / ts) / vibration_left(move, omega, zeta, fs=1.0 / ts))
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


@pytest.mark.parametrize("build", ["pythonfmu", "native"])
def test_300_g_put_on_mid_print_is_recovered_within_three_moves(tmp_path, build):
    """Three moves on the empty bed, its guess right, then 300 g on it (30 -> 26.3 Hz) during a rest:
    the move after the change is shaped for the old mode (8.1 %), the EKF learns the new one from its
    ring, and the next move leaves 0.12 %: recovered in one move, the issue asks for three (the design
    layer, with accelerometer noise: 7.6 % on the next move, about 1 % on the ones after). The same with the
    native C TrackedShaper, to the printed digits."""
    moves = 7
    commands = np.concatenate([ONE * (-1) ** i for i in range(moves)])
    loads = np.where(np.arange(commands.size) < 3 * ONE.size - 100, 0.0, 300.0)
    received, f = run_loop_in_master(tmp_path, 30.0, commands, loads, build=build)
    left = residuals(received, commands, loads, moves)
    assert max(left[:3]) < 1e-3 and left[3] > 0.05  # the old mode's shaper leaves what a fixed one would
    assert max(left[4:]) < 2e-3
    assert f[-1] == pytest.approx(30.0 / math.sqrt(1.3), rel=1e-4)


@pytest.mark.parametrize("build", ["pythonfmu", "native"])
def test_the_crane_from_a_guess_10_percent_off_converges_in_the_first_move(tmp_path, build):
    """The gantry crane at 1 m of rope (sqrt(g / L) = 3.13 rad/s), its swing angle fed back (gain -1/g:
    the load hangs back at theta = -a/g), sampled at 50 Hz; moves of 1 s at 0.5 m/s^2, 2 s coasting,
    1 s braking, 6 s at rest (tests/test_tracked_shaper.py's). The first move, shaped for the guess,
    leaves 14 %; the EKF has the frequency to 2e-4 by its end, and every later move leaves 0.015 %. The
    same with the native C TrackedShaper: one FMU, no Python on the host."""
    g, moves, ts = 9.80665, 4, 0.02
    one = np.concatenate([np.zeros(5), np.full(50, 0.5), np.zeros(100), np.full(50, -0.5), np.zeros(295)])
    commands = np.concatenate([one * (-1) ** i for i in range(moves)])
    truth = math.sqrt(g) / (2.0 * math.pi)
    received, f = run_loop_in_master(tmp_path, 1.1 * truth, commands, None, "gantry_crane", "swing_angle", ts, build,
                                     zeta0=0.01, noise=2e-3, amplitude=0.05, gain=-1.0 / g)
    left = residuals(received, commands, np.full(commands.size, 1.0), moves, "gantry_crane", one, ts)
    assert left[0] > 0.05 and max(left[1:]) < 1e-3, left
    assert f[one.size - 1] == pytest.approx(truth, rel=1e-3)
