"""The EKF-tracked shaper (issue 37) in closed loop with the shipped plants whose modes move.

The plant runs sample by sample (``plants.simulation``, exact zero-order-hold steps) and the kernel
reads its measured output with noise. The vibration each move leaves is computed independently of
the kernel: the closed-form response of the true mode of that move to the shaped command's steps
(Singer & Seering's sum, ``analysis.residual_vibration``), relative to the same move unshaped; one
test checks that closed form against the simulated plant's own ring."""

import math

import numpy as np
import pytest

from shapefmu.analysis import residual_vibration
from shapefmu.estimation import TrackedShaper
from shapefmu.plants import load_scheduled
from shapefmu.plants.simulation import run_loop
from shapefmu.runtime.ekf import ResonanceEKF
from shapefmu.runtime.tracked_shaper import TrackedShaperKernel, tracking_tuning
from shapefmu.shapers import zv

BED_FS, CRANE_FS = 2000.0, 50.0
G = 9.80665
# What each measurement settles to per unit of held trolley/carriage acceleration: the bed's
# accelerometer moves with the carriage (1), the load hangs back at theta = -a/g. None: watch at rest only.
BED_GAINS, CRANE_GAINS = (1.0, None), (-1.0 / G, None)
BED_NOISE = 0.05  # m/s^2 on the bed's accelerometer: the synthetic recordings' 50 mm/s^2
CRANE_NOISE = 2e-3  # rad on the swing angle
TARGET = 0.02


def moves(fs, acceleration, accelerating, coasting, resting, count):
    """Back-and-forth rest-to-rest moves: (acceleration per sample, first sample of each move)."""
    one = np.concatenate([np.full(round(accelerating * fs), acceleration), np.zeros(round(coasting * fs)),
                          np.full(round(accelerating * fs), -acceleration), np.zeros(round(resting * fs))])
    return np.concatenate([one * (-1) ** i for i in range(count)]), np.arange(count) * one.size


def bed_moves(count):
    return moves(BED_FS, 5.0, 0.02, 0.10, 0.20, count)


def crane_moves(count):
    return moves(CRANE_FS, 0.5, 1.0, 2.0, 6.0, count)


def vibration_left(command, fs, omega, zeta):
    """Amplitude of the mode's vibration once the held command has stopped changing (closed form)."""
    steps = np.diff(command, prepend=0.0)
    last = np.flatnonzero(np.abs(steps) > 1e-9 * np.abs(steps).max())[-1] + 1
    return residual_vibration((np.arange(last) / fs, steps[:last]), omega, zeta, "absolute")


def residual_per_move(plant, commands, shaped, values, starts, fs):
    ends = np.append(starts[1:], commands.size)
    out = []
    for start, end in zip(starts, ends):
        ((omega, zeta),) = plant.flexible_modes_at(values[start])
        out.append(vibration_left(shaped[start:end], fs, omega, zeta)
                   / vibration_left(commands[start:end], fs, omega, zeta))
    return np.array(out)


def track(plant, tracker, commands, values, fs, measure, noise, seed):
    kernel = tracker.kernel()
    run = run_loop(plant, commands, values, 1.0 / fs, lambda k, c, m: kernel.step(c, m), measure, noise, seed)
    return run, kernel


# Per shipped plant: its sampling, moves, scheduling value, what the tracker measures (output, noise,
# ring scale) and the damping ratio the guess assumes.
PLANTS = {
    "printer_bed": (BED_FS, lambda: bed_moves(6), 150.0, "bed_acceleration", BED_NOISE, 2.0, 0.05, 11),
    "gantry_crane": (CRANE_FS, lambda: crane_moves(5), 1.0, "swing_angle", CRANE_NOISE, 0.05, 0.01, 5),
}


@pytest.mark.parametrize("name, gain", [("printer_bed", g) for g in BED_GAINS] + [("gantry_crane", g) for g in CRANE_GAINS])
@pytest.mark.parametrize("start", [0.9, 1.1])
def test_the_tracker_converges_within_one_move_from_a_10_percent_wrong_start(name, gain, start):
    fs, moving, value, measure, noise, amplitude, zeta0, seed = PLANTS[name]
    plant = load_scheduled(name)
    commands, starts = moving()
    ((omega, zeta),) = plant.flexible_modes_at(value)
    tracker = TrackedShaper(fs, start * omega, noise=noise, amplitude=amplitude, zeta0=zeta0, gain=gain)
    run, kernel = track(plant, tracker, commands, value, fs, measure, noise, seed)
    residuals = residual_per_move(plant, commands, run.inputs, np.full(commands.size, value), starts, fs)
    assert residual_vibration(zv(start * omega, zeta0), omega, zeta) > 0.1  # the guess alone: ~15 % a move
    assert np.all(residuals[1:] <= TARGET), residuals
    assert kernel.mode[0] == pytest.approx(omega, rel=0.01)


@pytest.mark.parametrize("gain", BED_GAINS)
def test_a_mass_added_mid_print_is_recovered_within_three_moves(gain):
    """300 g put on the bed between two moves (30 -> 26.3 Hz): the move after the step begins with the
    old design, and the EKF, watching its rings, brings the shaper back within three moves."""
    bed = load_scheduled("printer_bed")
    commands, starts = bed_moves(10)
    values = np.where(np.arange(commands.size) < starts[4], 0.0, 300.0)
    ((omega, _),) = bed.flexible_modes_at(0.0)
    tracker = TrackedShaper(BED_FS, omega, noise=BED_NOISE, amplitude=2.0, zeta0=0.05, gain=gain)
    run, kernel = track(bed, tracker, commands, values, BED_FS, "bed_acceleration", BED_NOISE, seed=2)
    residuals = residual_per_move(bed, commands, run.inputs, values, starts, BED_FS)
    assert np.all(residuals[:4] <= TARGET)
    assert residuals[4] > TARGET  # the step: the move begins shaped for 30 Hz, the bed now at 26.3 Hz
    assert np.all(residuals[4 + 3:] <= TARGET), residuals
    assert kernel.mode[0] == pytest.approx(bed.flexible_modes_at(300.0)[0][0], rel=0.01)


def test_the_closed_form_residual_is_the_simulated_plants_ring():
    """Second method: the amplitude of the bed's own ring after a shaped move (deflection e and its
    rate from the simulated outputs: acceleration = -(omega^2 e + 2 zeta omega e')), shaped over
    unshaped, equals the closed-form ratio."""
    bed = load_scheduled("printer_bed")
    commands, _ = bed_moves(1)
    ((omega, zeta),) = bed.flexible_modes_at(120.0)
    kernel = TrackedShaper(BED_FS, 1.05 * omega, noise=BED_NOISE, amplitude=2.0, zeta0=zeta).kernel()
    shaped = np.array([kernel.step(c, None) for c in commands])

    def ring(command):
        outputs = run_loop(bed, command, 120.0, 1.0 / BED_FS).outputs
        e, acceleration = outputs[-1, 1], outputs[-1, 2]
        rate = -(acceleration + omega**2 * e) / (2 * zeta * omega)
        sigma, omega_d = zeta * omega, omega * math.sqrt(1 - zeta**2)
        return math.hypot(e, (rate + sigma * e) / omega_d)

    simulated = ring(shaped) / ring(commands)
    t_end = (commands.size - 1) / BED_FS
    # the closed form gives each amplitude just after its last step: bring both to the end of the run
    decay = {name: math.exp(-zeta * omega * (t_end - (np.flatnonzero(np.abs(np.diff(c, prepend=0.0)) > 1e-12)[-1]) / BED_FS))
             for name, c in (("shaped", shaped), ("unshaped", commands))}
    closed = (vibration_left(shaped, BED_FS, omega, zeta) * decay["shaped"]
              / (vibration_left(commands, BED_FS, omega, zeta) * decay["unshaped"]))
    assert simulated == pytest.approx(closed, rel=1e-6)
    assert 0.05 < closed < 0.15  # a ZV 5 % off leaves about (pi/2) 5 %


def test_with_a_gain_the_ekf_sees_the_measurement_from_its_equilibrium_and_restarts_at_each_change():
    """An accelerometer that reads exactly the held carriage acceleration (no ring at all): referred to
    its equilibrium, gain 1 times the last shaped command, every sample is 0 and the phasor stays 0."""
    kernel = TrackedShaper(BED_FS, 2 * math.pi * 30, noise=BED_NOISE, amplitude=2.0, zeta0=0.05, gain=1.0).kernel()
    restarts = []
    kernel.ekf.restart_phasor = lambda restart=kernel.ekf.restart_phasor: restarts.append(1) or restart()
    commands, _ = bed_moves(1)
    shaped, changes = 0.0, 0
    for command in commands:
        now = kernel.step(command, shaped)
        assert kernel.watching and kernel.ekf.x[:2] == [0.0, 0.0]
        changes += now != shaped
        shaped = now
    assert len(restarts) == changes + 1  # one ring per held stretch, the first at the start
    assert kernel.ekf.missing == 0


def test_without_a_gain_the_ekf_looks_away_while_the_shaped_command_moves():
    kernel = TrackedShaper(BED_FS, 2 * math.pi * 30, noise=BED_NOISE, amplitude=2.0, zeta0=0.05).kernel()
    commands, _ = bed_moves(1)
    watched = []
    for command in commands:
        kernel.step(command, 0.0)
        watched.append(kernel.watching)
    span = kernel.shaper.span  # ZV at 30 Hz on 2 kHz: 35 samples
    accelerating, coasting = 40, 200
    # watching resumes one shaper length after the command comes to rest, not before
    assert not any(watched[1:accelerating + span])
    assert all(watched[accelerating + span + 1:accelerating + coasting])
    assert kernel.ekf.missing == commands.size - sum(watched)


def test_an_estimate_that_has_not_converged_keeps_the_last_good_design():
    """Noise alone never converges; a clean ring at 3x the guess converges outside the band: in both
    the shaper keeps its design (the guess)."""
    fs, omega0 = 2000.0, 2 * math.pi * 30
    rng = np.random.default_rng(0)
    p0, q, r = tracking_tuning(fs, omega0, 1.0, 0.05)
    for signal in (rng.normal(0.0, 0.05, 4000),
                   np.sin(3 * omega0 * np.arange(4000) / fs) * np.exp(-np.arange(4000) / 4000)):
        kernel = TrackedShaperKernel(fs, omega0, 0.05, p0=p0, q=q, r=r, omega_tol=1e-2, sigma_tol=4e-3,
                                     band=(0.5, 2.0))
        for sample in signal:
            kernel.step(0.0, float(sample))
        assert kernel.mode == (omega0, 0.05)
        assert kernel.shaper.designs == 1


def test_restarting_the_phasor_keeps_what_the_filter_knows_of_the_mode():
    ekf = ResonanceEKF(1000.0, 100.0)
    for k in range(300):
        ekf.step(math.sin(100.0 * k / 1000.0))
    omega, sigma, p_omega = ekf.omega_d, ekf.sigma, ekf.P[2][2]
    ekf.restart_phasor()
    assert (ekf.x[0], ekf.x[1]) == (0.0, 0.0) and (ekf.omega_d, ekf.sigma) == (omega, sigma)
    assert ekf.P[2][2] == p_omega and ekf.P[0][0] == ekf.p0[0] and ekf.P[0][2] == ekf.P[2][1] == 0.0


@pytest.mark.parametrize("arguments, message", [
    ({"band": (1.2, 2.0)}, r"band must be \(low, high\) with 0 < low < 1 < high"),
    ({"zeta0": 1.0}, r"zeta0 must be in \[0, 1\), got 1.0"),
    ({"noise": 0.0}, "noise must be > 0, got 0.0"),
    ({"drift": -1.0}, "drift must be > 0, got -1.0"),
])
def test_a_bad_tracker_setting_is_refused_naming_it(arguments, message):
    settings = {"fs": 2000.0, "omega0": 188.0, "noise": 0.05, "amplitude": 1.0} | arguments
    with pytest.raises(ValueError, match=message):
        TrackedShaper(**settings)
