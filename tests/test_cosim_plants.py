"""The master on the project's own FMUs: shaper -> disk-drive plant, Model Exchange plant."""

from __future__ import annotations

import signal
import subprocess
import sys

import numpy as np
import pytest
import scipy.linalg
from support.run_watch import OutputWatch
from support.ssp_hosts import run_ecos, run_libcosim

from shapefmu.cosim import Master, simulate
from shapefmu.fmi.ssp import System
from shapefmu.plants import load

MODEL = "models/disk_drive.toml"
VOLTS = 11.0
PLANT_OUTPUTS = ["plant.position", "plant.deflection_1", "plant.deflection_2"]


@pytest.fixture(scope="module")
def disk_drive_fmu(tmp_path_factory):
    from shapefmu.fmi.native import build_plant_fmu

    return build_plant_fmu(MODEL, tmp_path_factory.mktemp("cosim_plant") / "DiskDrive.fmu")


@pytest.fixture(scope="module")
def shaper_fmu_2khz(tmp_path_factory):
    from shapefmu.fmi import build_fmu

    return build_fmu("Shaper", tmp_path_factory.mktemp("cosim_shaper") / "Shaper.fmu")


def shaped_seek(shaper_fmu, plant_fmu) -> System:
    """A ZVD shaper for the 2 kHz mode shaping a unit step command, scaled to 11 V on the plant."""
    return (System("shaped_seek")
            .add("shaper", shaper_fmu, {"kind": "zvd", "f[1]": 2000.0, "zeta[1]": 0.01, "Ts": 1e-6, "u": 1.0})
            .add("plant", plant_fmu, {"f[1]": 2100.0})
            .connect("shaper.y", "plant.voltage", factor=VOLTS))


def test_shaper_to_plant_jacobi_equals_libcosim_and_ecos(shaper_fmu_2khz, disk_drive_fmu, tmp_path):
    ssp = shaped_seek(shaper_fmu_2khz, disk_drive_fmu).write_ssp(tmp_path / "seek.ssp")
    variables = ["shaper.y", *PLANT_OUTPUTS]
    h, n = 1e-6, 600
    ours = simulate(ssp, n * h, h, algorithm="jacobi", record=variables)
    ours = np.column_stack([ours[v] for v in variables])
    assert np.ptp(ours[:, 1]) > 1e-4 and np.ptp(ours[:, 2]) > 1e-7  # the move and the vibration happen
    np.testing.assert_allclose(ours[1:], run_libcosim(ssp, h, n, variables)[1:], rtol=0, atol=1e-9)
    np.testing.assert_allclose(ours, run_ecos(ssp, h, n, variables), rtol=0, atol=1e-9)



def test_two_instances_of_one_native_fmu_run_in_ecos_as_in_our_master(disk_drive_fmu, tmp_path, capfd):
    # ecos loads one copy of an FMU's library per instance and may call an instance through another
    # copy's functions: the instances' liveness must not be kept per library (it once was, and every
    # call of the second plant was refused with "not live").
    system = (System("chain").add("first", disk_drive_fmu, {"voltage": VOLTS}).add("second", disk_drive_fmu)
              .connect("first.position", "second.voltage"))
    ssp = system.write_ssp(tmp_path / "chain.ssp")
    variables = ["first.position", "second.position"]
    h, n = 1e-6, 300
    ours = simulate(ssp, n * h, h, algorithm="jacobi", record=variables)
    ours = np.column_stack([ours[v] for v in variables])
    theirs = run_ecos(ssp, h, n, variables)
    assert np.ptp(ours[:, 1]) > 0.0
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12 * np.max(np.abs(ours)))
    assert "not live" not in capfd.readouterr().err


def exact_step_response(t: np.ndarray, volts: float) -> np.ndarray:
    """Outputs of the disk drive under a constant input, by the augmented matrix exponential."""
    system = load(MODEL).to_statespace()
    A, B, C, D = (np.asarray(m, dtype=float) for m in (system.A, system.B, system.C, system.D))
    n = A.shape[0]
    augmented = np.zeros((n + 1, n + 1))
    augmented[:n, :n], augmented[:n, n:] = A, B
    rows = []
    for instant in t:
        x = scipy.linalg.expm(augmented * instant)[:n, n:] @ [volts]
        rows.append(C @ x + D @ [volts])
    return np.array(rows)


def test_model_exchange_plant_in_a_cosimulation_matches_the_exact_solution(disk_drive_fmu):
    system = System().add("plant", disk_drive_fmu, {"voltage": VOLTS})
    with Master(system, 1e-5, model_exchange=["plant"], tolerance=1e-10, record=PLANT_OUTPUTS) as master:
        assert master.units[0].interface == "ModelExchange"
        result = master.run(2e-3)
    want = exact_step_response(result["time"], VOLTS)
    for j, name in enumerate(PLANT_OUTPUTS):
        scale = np.max(np.abs(want[:, j]))
        np.testing.assert_allclose(result[name], want[:, j], rtol=0, atol=1e-6 * scale, err_msg=name)


def test_ctrl_c_stops_a_long_run_cleanly_and_keeps_the_partial_results(disk_drive_fmu, tmp_path):
    # A user's Ctrl-C: SIGINT to `shapefmu simulate` while it runs 10^9 steps with a progress bar.
    ssp = System("plant_alone").add("plant", disk_drive_fmu, {"voltage": 1.0}).write_ssp(tmp_path / "plant.ssp")
    out = tmp_path / "partial.csv"
    process = subprocess.Popen(
        [sys.executable, "-m", "shapefmu", "simulate", str(ssp), "--stop", "1000", "--step", "1e-6",
         "--record", "plant.position", "--output-interval", "1e-3", "--progress", "--out", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    watch = OutputWatch(process)
    watch.wait_for("steps/s")  # start-up, then at least one progress update: not a fixed time
    process.send_signal(signal.SIGINT)
    stdout, stderr = watch.finish()
    assert process.returncode == 130, stderr
    assert "steps/s\nshapefmu simulate: co-simulation interrupted at t = " in stderr  # the bar, then the message
    saved = np.genfromtxt(out, delimiter=",", names=True)
    assert 2 <= saved.size < 1_000_001  # some records, not all of them
    # What was recorded is the plant's exact response to 1 V: x_r = b2 t^2 / 2 (b2 = 2.7e3), to the
    # rounding that ~1e8 exact ZOH steps accumulate (N eps ~ 1e-8).
    np.testing.assert_allclose(saved["plantposition"], 2.7e3 * saved["time"] ** 2 / 2, rtol=1e-7, atol=1e-15)
    assert f"results written to {out}" in stdout
