"""``shapefmu compare``: the co-simulated candidates against the design layer's exact moves.

Disk drive (paper 002, Table I), X = 0.05 rad: bang-bang pulses of 1.30 ms, longer than the
0.40 ms shaper (tests/test_optimal.py's LONG distance). FMUs stepped at h = 1 us.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from shapefmu.compare import compare, move_metrics
from shapefmu.optimal import compare_moves
from shapefmu.plants import load
from shapefmu.shapers import zvd
from shapefmu.stos import simulate_stos, stos_law

MODEL = Path(__file__).resolve().parent.parent / "models" / "disk_drive.toml"
X, H, U = 0.05, 1e-6, 11.0
OPEN_LOOP = {"bang-bang": "rigid bang-bang", "convolution": "bang-bang * convolution (ZV per mode)",
             "simultaneous": "bang-bang * simultaneous", "time-optimal": "time-optimal"}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("compare_fmus")


@pytest.fixture(scope="module")
def runs(cache):
    return compare(MODEL, X, candidates=(*OPEN_LOOP, "stos-convolution", "stos-simultaneous", "ekf-tuned"), step=H, cache=cache)


@pytest.fixture(scope="module")
def design():
    comparison = compare_moves(load(MODEL), X)
    return {move.name: move for move in comparison.moves}


def sampling_bound(command) -> float:
    """Largest residual (relative to X) that sampling at H can add to an exact move.

    The players hand the plant the mean of the command over each step, so a level change of du
    inside a step keeps the impulse and moves every state x_i'' = ... + g_i u by at most
    |g_i| du h^2 / 8 (the position of a zero-mean doublet, alpha (1 - alpha) / 2 <= 1/8; for
    omega h = 0.02 the mode's own response changes this by (omega h)^2 ~ 4e-4). The Shaper FMU's
    split of an off-grid impulse keeps its area and centroid: the same second-order doublet, once
    per level change of the shaped command. Summed over the command's total variation, with the
    largest input gain of the disk drive, |b2| = |b4i| = 2.7e3 /(V s^2)."""
    levels = np.array([0.0, *command.levels, command.final])
    return 2.7e3 * np.sum(np.abs(np.diff(levels))) * H**2 / 8 / X


@pytest.mark.parametrize("name", OPEN_LOOP)
def test_open_loop_move_time_is_the_exact_one_rounded_up_to_the_step(runs, design, name):
    exact = design[OPEN_LOOP[name]].duration
    assert exact <= runs.run(name).metrics.move_time < exact + H * (1 + 1e-9)


@pytest.mark.parametrize("name", OPEN_LOOP)
def test_open_loop_residual_agrees_with_the_exact_simulation_within_the_sampling_bound(runs, design, name):
    move = design[OPEN_LOOP[name]]
    # The design layer reads the free response at 400 points of one period of the 2 kHz mode, we at
    # every step (500): a sampled maximum of the 3 kHz component falls short by up to
    # 1 - cos(pi * 1.5 / 399) = 7e-5 of it.
    allowed = sampling_bound(move.command) + 7e-5 * move.residual
    assert runs.run(name).metrics.residual == pytest.approx(move.residual, rel=0, abs=allowed)
    assert runs.run(name).metrics.peak == pytest.approx(move.peak, rel=1e-12)


def test_shaped_and_optimal_moves_leave_only_sampling_residual_and_unshaped_leaves_vibration(runs, design):
    assert runs.run("bang-bang").metrics.residual > 1e-2
    for name in ("convolution", "simultaneous", "time-optimal"):
        assert runs.run(name).metrics.residual < sampling_bound(design[OPEN_LOOP[name]].command)


def test_ratio_is_against_the_co_simulated_time_optimal_move(runs, design):
    optimal = runs.run("time-optimal").metrics.move_time
    for run in runs.runs:
        assert run.ratio == pytest.approx(run.metrics.move_time / optimal, rel=1e-15)
    assert optimal == pytest.approx(design["time-optimal"].duration, abs=H)


@pytest.mark.parametrize("shaper", ["convolution", "simultaneous"])
def test_stos_row_is_the_design_layers_sampled_loop_measured_the_same_way(runs, shaper):
    plant = load(MODEL)
    stos = runs.run(f"stos-{shaper}")
    t = stos.results["time"]
    reference = simulate_stos(plant, stos_law(plant, shaper, H), X, H, t[-1])
    expected = move_metrics(reference.t, reference.u, reference.x[:, 0], reference.x[:, [2, 4]].T, X, U, 1 / 2000.0)
    # Same sampled semantics (tests/test_cosim_stos.py): equal up to rounding in the states.
    assert stos.metrics.move_time == expected.move_time
    assert stos.metrics.residual == pytest.approx(expected.residual, rel=0, abs=1e-12 / X)
    assert stos.metrics.peak == pytest.approx(U, rel=1e-12)
    # STOS is the shaped bang-bang in closed loop: it ends with that open-loop move.
    assert stos.metrics.move_time == runs.run(shaper).metrics.move_time


def test_simultaneous_stos_is_faster_than_convolution_stos(runs):
    assert runs.run("stos-simultaneous").metrics.move_time < runs.run("stos-convolution").metrics.move_time


def test_ekf_tuned_row_is_the_bang_bang_shaped_by_zvd_for_the_estimate_it_converged_to(runs):
    # The tuner designs a ZVD for its estimate when the EKF first converges (it re-designs only for a
    # change beyond 5 %) and switches it in while the command rests before the second move; the
    # design layer shapes the same bang-bang with that ZVD and simulates it exactly.
    run = runs.run("ekf-tuned")
    first = np.flatnonzero(run.results["tuner.converged"] == 1.0)[0]
    assert run.results["time"][first] < run.start
    omega, zeta = run.results["tuner.omega_est"][first], run.results["tuner.zeta_est"][first]
    # The mode it watched, within 2 % (it started 10 % low; paper 001 asks 1 % after five periods,
    # and the tuner converges on its own tolerances sooner).
    assert omega == pytest.approx(2 * np.pi * 2000.0, rel=2e-2)
    (move,) = [m for m in compare_moves(load(MODEL), X, U, {"ekf": zvd(omega, zeta)}).moves if m.name.endswith("ekf")]
    # The tuner's output changes only in doStep (no feed-through): the plant gets it one step late.
    assert move.duration + H <= run.metrics.move_time < move.duration + 2 * H * (1 + 1e-9)
    allowed = sampling_bound(move.command) + 7e-5 * move.residual
    assert run.metrics.residual == pytest.approx(move.residual, rel=0, abs=allowed)


def test_cli_compare_prints_the_table_and_writes_the_plot(cache, tmp_path, capsys):
    from shapefmu.cli import main

    plot = tmp_path / "compare_disk_drive.png"
    assert main(["compare", str(MODEL), "--distance", str(X), "--candidate", "bang-bang", "--candidate", "time-optimal",
                 "--fmus", str(cache), "--plot", str(plot)]) == 0
    out = capsys.readouterr().out
    assert "bang-bang" in out and "time-optimal" in out and "vs optimal" in out
    assert plot.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("argv, message", [
    (["--distance", "0"], "distance must be non-zero"),
    (["--distance", "0.05", "--step=-1e-6"], "step must be > 0, got -1e-06"),
])
def test_cli_compare_refuses_bad_input(cache, capsys, argv, message):
    from shapefmu.cli import main

    with pytest.raises(SystemExit) as exit_:
        main(["compare", str(MODEL), "--fmus", str(cache), *argv])
    assert exit_.value.code == 2
    assert message in capsys.readouterr().err


def test_native_twins_print_the_demos_table_to_its_printed_digits(runs, cache, capsys):
    """Every command FMU as its native C twin (shapefmu compare --native): the same table."""
    from shapefmu.cli import main

    candidates = [run.name for run in runs.runs]
    argv = ["compare", str(MODEL), "--distance", str(X), "--fmus", str(cache), "--native"]
    for name in candidates:
        argv += ["--candidate", name]
    assert main(argv) == 0
    printed = capsys.readouterr().out.strip()
    assert printed == runs.table().strip()
    import zipfile

    built = [path for path in (Path(cache) / "native").iterdir() if path.suffix == ".fmu"]
    models = {zipfile.ZipFile(path).read("sources/buildDescription.xml").decode().split('modelIdentifier="')[1].split('"')[0]
              for path in built}
    assert models == {"ReferencePlayer", "Shaper", "STOSController", "EKFTuner"}  # every command FMU, native
    assert not any("resources/slavemodule.txt" in zipfile.ZipFile(path).namelist() for path in built)


def test_fmi3_native_fmus_print_the_demos_table_to_its_printed_digits(runs, cache, capsys):
    """Every FMU as FMI 3.0 (the native twins and the plant; shapefmu compare --native --fmi-version 3.0)."""
    from shapefmu.cli import main

    argv = ["compare", str(MODEL), "--distance", str(X), "--fmus", str(cache), "--native", "--fmi-version", "3.0"]
    for run in runs.runs:
        argv += ["--candidate", run.name]
    assert main(argv) == 0
    assert capsys.readouterr().out.strip() == runs.table().strip()
    from fmpy import read_model_description

    built = [path for path in (Path(cache) / "native3").iterdir() if path.suffix == ".fmu"]
    assert built and all(read_model_description(str(path)).fmiVersion == "3.0" for path in built)


@pytest.mark.parametrize("name", ["convolution", "simultaneous"])
def test_an_fmi3_shaper_fed_its_modes_by_an_array_parameter_set_gives_the_demos_shaped_row(runs, cache, tmp_path, name):
    """The FMI 3.0 native Shaper and plant, the modes reaching the Shaper as the array parameters f and
    zeta of an .ssv parameter set (closed-form zv: re-designed in C from them; the build had other
    modes), run by the master from the .ssp: the demo's row, to its printed digits."""
    from shapefmu.compare import Comparison, CandidateRun, FMUCache
    from shapefmu.compare.systems import mode_arrays, modes_hz, signal_table
    from shapefmu.cosim.master import Master
    from shapefmu.fmi.ssp import System, read_ssp, write_system
    from shapefmu.optimal import rigid_bang_bang

    plant = load(MODEL)
    fmus = FMUCache(cache, native=True, fmi_version="3.0")
    modes = modes_hz(plant)
    built_for = modes if name == "simultaneous" else {"n_modes": 2, "f[1]": 1000.0, "f[2]": 1500.0}  # zv: other modes
    kind = {"convolution": "zv", "simultaneous": "simultaneous"}[name]
    shaper = fmus.slave("Shaper", kind=kind, Ts=H, **built_for)
    player = fmus.slave("ReferencePlayer", table=signal_table(rigid_bang_bang(plant, X, U)))
    arrays = mode_arrays(modes, shaper)
    assert len(arrays["f"]) == 4 and arrays["f"][:2] == [modes["f[1]"], modes["f[2]"]]
    system = (System("shaped").add("plant", fmus.plant(plant)).add("player", player)
              .add("shaper", shaper, arrays)
              .connect("player.y_mean", "shaper.u").connect("shaper.y", "plant.voltage"))
    stop = runs.run(name).results["time"][-1]
    path = write_system(system.for_experiment(stop), tmp_path / "shaped.ssp")
    outputs = ["plant.position", "plant.deflection_1", "plant.deflection_2"]
    with Master(read_ssp(path), H, record=["plant.voltage", *outputs]) as master:
        results = master.run(stop)
    applied = np.append(results["plant.voltage"][1:], results["plant.voltage"][-1])
    metrics = move_metrics(results["time"], applied, results["plant.position"], [results[o] for o in outputs[1:]], X, U,
                           1 / 2000.0)
    demo = runs.run(name)
    row = CandidateRun(name, metrics, metrics.move_time / runs.run("time-optimal").metrics.move_time, results, 0.0)
    table = Comparison(runs.plant, X, U, H, runs.optimal_time, (row, *runs.runs), runs.command).table().splitlines()
    assert table[2] == next(line for line in runs.table().splitlines() if line.startswith(f"{name} "))
    assert metrics.residual < 1e-6 and demo.metrics.residual < 1e-6
    if name == "convolution":  # the parameter set is what designed it: without it the build's modes ring
        system.components["shaper"].parameters.clear()
        with Master(system, H, record=["plant.voltage", *outputs]) as master:
            unbound = master.run(stop)
        ringing = move_metrics(unbound["time"], unbound["plant.voltage"], unbound["plant.position"],
                               [unbound[o] for o in outputs[1:]], X, U, 1 / 2000.0)
        assert ringing.residual > 1e-3
