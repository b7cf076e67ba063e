"""Sweeps on Dask: grids, metrics, failures as rows, a killed worker, resume, and the analytic path
against the co-simulation path on the ten pendula of paper 003."""

import json
import math
import os
import signal
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

pytest.importorskip("distributed")
from distributed import Client, LocalCluster  # noqa: E402

from shapefmu import sweep as sweeps  # noqa: E402
from shapefmu.cli import main  # noqa: E402
from shapefmu.cosim import Master  # noqa: E402
from shapefmu.plants import load  # noqa: E402
from shapefmu.shapers.twin_pulse import m_bc_tz_tp  # noqa: E402
from shapefmu.sweep.analytic import pendula_swing, shaper_residual  # noqa: E402

TEN_PENDULA = Path(__file__).resolve().parents[1] / "models" / "ten_pendula.toml"
STEP, STOP = 0.01, 12.0
RECORD = ["profile.y", "plant.cart_position", *[f"plant.theta_{i}" for i in range(1, 11)]]
SWING = sweeps.residual("plant.theta_*", command="profile.y")


def ten_pendula_profile(ts):
    """Paper 003, Sec. IV: M-BC:TZ:TP at 3.5 rad/s, delta-omega 0.05 rad/s, 1.7 m at 0.7 m/s."""
    return m_bc_tz_tp(3.5, 1.7, 0.7, delta_omega=0.05, ts=ts).profile


def ten_pendula_lengths():
    return -1.0 / load(TEN_PENDULA).B[3::2, 0]  # B = -1/L on each swing rate (plants.pendula)


def analytic_swing():
    return pendula_swing(ten_pendula_profile(STEP).acceleration, STEP, ten_pendula_lengths(), STOP)


@pytest.fixture(scope="module")
def ten_pendula_ssp(tmp_path_factory):
    """The ten-pendula system of paper 003: ReferencePlayer -> native plant FMU (shapefmu.fmi.native).

    The player holds the sampled cart acceleration, y(t) = a[floor(t / STEP)] (0 after the last
    sample), the zero-order hold that ``pendula_swing`` integrates in closed form.
    """
    from shapefmu.fmi import build_fmu
    from shapefmu.fmi.native.build import build_plant_fmu
    from shapefmu.fmi.ssp import System

    folder = tmp_path_factory.mktemp("ten_pendula")
    samples = [float(a) for a in ten_pendula_profile(STEP).acceleration]
    table = {"kind": "signal_table", "interpolation": "hold", "time": [k * STEP for k in range(len(samples) + 1)],
             "value": [*samples, 0.0]}
    player = build_fmu("ReferencePlayer", folder / "profile.fmu", table=json.dumps(table))
    plant = build_plant_fmu(TEN_PENDULA, folder / "ten_pendula.fmu")
    system = System("ten_pendula").add("profile", player).add("plant", plant).connect("profile.y", "plant.acceleration")
    return system.write_ssp(folder / "ten_pendula.ssp")


class CountingMaster(Master):
    """The master, counting per worker process how often it is opened and reset."""

    opened = 0
    resets = 0

    def __init__(self, *args, **kwargs):
        type(self).opened += 1
        super().__init__(*args, **kwargs)

    def reset(self):
        type(self).resets += 1
        super().reset()


def opened_and_reset():
    return CountingMaster.opened, CountingMaster.resets


def ten_pendula_cosim(ssp, opener=None):
    # Jacobi: the plant steps [t_k, t_k+h] on the player's output at t_k, a zero-order hold.
    return sweeps.cosim(ssp, step=STEP, stop_time=STOP, record=RECORD, algorithm="jacobi", opener=opener)


def square_plus(parameters):
    """A run whose result is known in closed form, x^2 + z, with failures at chosen points."""
    x = parameters["x"]
    if x == 3.0:
        raise RuntimeError("no convergence at x = 3")
    if x == 4.0:
        return {"y": math.nan}
    if x == 5.0:
        end = time.perf_counter() + 60.0
        while time.perf_counter() < end:  # a run that hangs in Python code
            pass
    return {"y": x * x + parameters["z"]}


@pytest.fixture(scope="module")
def cluster():
    """A cluster a user would run: two single-threaded worker processes behind a scheduler."""
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as local:
        yield local


@pytest.fixture
def address(cluster):
    with Client(cluster.scheduler_address) as client:
        client.wait_for_workers(2, timeout=60)
    return cluster.scheduler_address


# --- parameter points ------------------------------------------------------------------------


def test_grid_is_the_product_of_linspace_and_list_axes_first_slowest():
    points = sweeps.grid("plant.wn=3.36:3.66:10", "plant.zeta=0.005,0.01,0.02")
    assert points.names == ("plant.wn", "plant.zeta")
    assert len(points) == 30
    np.testing.assert_array_equal(points.values[::3, 0], np.linspace(3.36, 3.66, 10))
    np.testing.assert_array_equal(points.values[:3, 1], [0.005, 0.01, 0.02])
    assert points.parameters(4) == {"plant.wn": points.values[4, 0], "plant.zeta": 0.01}


@pytest.mark.parametrize("spec", ["plant.wn", "plant.wn=3:4", "plant.wn=3:4:0", "plant.wn=a,b", "=1,2"])
def test_bad_grid_spec_is_a_value_error_naming_it(spec):
    with pytest.raises(ValueError, match="plant.wn|NAME"):
        sweeps.grid(spec)


def test_random_samples_repeat_with_their_seed_and_stay_in_range():
    first = sweeps.random_samples(200, ["plant.wn=3.3:3.7", "plant.zeta=0:0.02"], seed=7)
    again = sweeps.random_samples(200, {"plant.wn": (3.3, 3.7), "plant.zeta": (0.0, 0.02)}, seed=7)
    other = sweeps.random_samples(200, ["plant.wn=3.3:3.7", "plant.zeta=0:0.02"], seed=8)
    np.testing.assert_array_equal(first.values, again.values)
    assert not np.array_equal(first.values, other.values)
    assert np.all((first.values >= [3.3, 0.0]) & (first.values < [3.7, 0.02]))
    with pytest.raises(ValueError, match="plant.zeta"):
        sweeps.random_samples(5, ["plant.zeta=0.02:0"])


# --- metrics ---------------------------------------------------------------------------------


def assert_same_rows(actual, expected):
    assert actual.dtype.names == expected.dtype.names
    for name in expected.dtype.names:
        np.testing.assert_array_equal(actual[name], expected[name], err_msg=name)


def recorded(t, **signals):
    record = np.empty(t.size, dtype=[("time", float), *[(name, float) for name in signals]])
    record["time"] = t
    for name, values in signals.items():
        record[name] = values
    return record


def test_metrics_of_a_decaying_oscillation_match_their_closed_forms():
    # A command on [0, 1), then y = 1 + 0.2 e^{-s} cos(2 pi s), s = t - 1: the residual from the
    # move's end is its first peak 0.2. The trough at s = 2.5 leaves the band 0.015 (0.2 e^{-2.5} =
    # 0.0164) and every later extremum stays inside (0.2 e^{-s} < 0.0101 from s = 2.98 on), so the
    # move ends where 0.2 e^{-s} |cos 2 pi s| = 0.015 in (2.5, 2.75).
    t = np.arange(0, 8.0 + 1e-9, 1e-3)
    command = np.where(t < 1.0, np.where(t < 0.5, 2.0, -2.5), 0.0)
    y = np.where(t < 1.0, t, 1.0 + 0.2 * np.exp(-(t - 1.0)) * np.cos(2 * np.pi * (t - 1.0)))
    record = recorded(t, **{"shaper.y": command, "plant.y": y, "plant.z": 0.5 * (y - 1.0)})
    assert sweeps.move_end(record, "shaper.y") == pytest.approx(1.0)
    assert sweeps.residual("plant.*", command="shaper.y", final=0.0)(record) == pytest.approx(1.2)
    assert sweeps.residual("plant.z", command="shaper.y")(record) == pytest.approx(0.1)
    assert sweeps.residual(["plant.y"], after=2.0, final=1.0)(record) == pytest.approx(0.2 * math.exp(-1.0))
    crossing = brentq(lambda s: 0.2 * math.exp(-s) * abs(math.cos(2 * math.pi * s)) - 0.015, 2.5, 2.75)
    settled = sweeps.move_time("plant.y", target=1.0, tolerance=0.015)(record)
    assert 1.0 + crossing <= settled <= 1.0 + crossing + 1e-3  # the first sample inside the band
    assert sweeps.peak("shaper.y")(record) == 2.5
    with pytest.raises(ValueError, match="plant.q"):
        sweeps.residual("plant.q", after=0.0)(record)


# --- the sweep on a cluster given by its address ----------------------------------------------


def test_failures_are_rows_and_the_sweep_goes_on(address, tmp_path):
    rows = sweeps.sweep(square_plus, ["x=0:6:7", "z=1,2"], client=address, timeout=0.5, out=tmp_path / "rows.csv",
                        progress=False)
    status = dict(zip(zip(rows["x"], rows["z"]), rows["status"]))
    assert len(rows) == 14
    assert {status[(3.0, z)] for z in (1.0, 2.0)} == {"error"}
    assert {status[(4.0, z)] for z in (1.0, 2.0)} == {"non-finite"}
    assert {status[(5.0, z)] for z in (1.0, 2.0)} == {"timeout"}
    ok = rows["status"] == "ok"
    np.testing.assert_array_equal(rows["y"][ok], rows["x"][ok] ** 2 + rows["z"][ok])
    assert all("no convergence at x = 3" in e for e in rows["error"][rows["status"] == "error"])
    assert np.all(rows["wall_time"][rows["status"] == "timeout"] >= 0.5)
    assert_same_rows(sweeps.read_rows(tmp_path / "rows.csv"), rows)


def kill_worker_once(parameters, marker):
    """x^2, except that the first run at x = 5 kills the worker process running it."""
    if parameters["x"] == 5.0 and not os.path.exists(marker):
        Path(marker).touch()
        os._exit(1)
    time.sleep(0.02)
    return {"y": parameters["x"] ** 2}


def test_a_worker_killed_mid_sweep_loses_no_run(address, tmp_path):
    marker = tmp_path / "killed"
    rows = sweeps.sweep(lambda p: kill_worker_once(p, str(marker)), "x=0:39:40", client=address, batch_size=1,
                        out=tmp_path / "rows.parquet", progress=False)
    assert marker.exists()  # the worker did die mid-sweep
    np.testing.assert_array_equal(rows["x"], np.arange(40.0))
    assert list(rows["status"]) == ["ok"] * 40
    np.testing.assert_array_equal(rows["y"], np.arange(40.0) ** 2)
    assert_same_rows(sweeps.read_rows(tmp_path / "rows.parquet"), rows)


def evaluated(parameters, folder):
    Path(folder, f"{parameters['x']:g}").touch()
    return {"y": parameters["x"] ** 2}


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_resume_runs_only_the_points_without_a_row(address, tmp_path, suffix):
    out = tmp_path / f"rows{suffix}"
    journal = out if suffix == ".csv" else tmp_path / "rows.parquet.partial.csv"
    first = tmp_path / "first"
    first.mkdir()
    sweeps.sweep(lambda p: evaluated(p, str(first)), "x=0:19:20", client=address, out=out, progress=False)
    # A sweep killed after 8 rows: the rows so far are on disk, the last one half written (a
    # Parquet sweep keeps them in its journal until it ends).
    text = sweeps.read_rows(out)
    header = "run,x,y,status,error,wall_time\n"
    lines = [f"{r['run']},{float(r['x'])!r},{float(r['y'])!r},ok,,{float(r['wall_time'])!r}\n" for r in text[:8]]
    out.unlink()
    journal.write_text(header + "".join(lines) + "8,8.0,6")
    second = tmp_path / "second"
    second.mkdir()
    rows = sweeps.sweep(lambda p: evaluated(p, str(second)), "x=0:19:20", client=address, out=out, progress=False)
    assert sorted(float(p.name) for p in second.iterdir()) == list(np.arange(8.0, 20.0))
    np.testing.assert_array_equal(rows["y"], np.arange(20.0) ** 2)
    np.testing.assert_array_equal(rows["wall_time"][:8], text["wall_time"][:8])  # kept, not re-run
    assert_same_rows(sweeps.read_rows(out), rows)
    assert not (suffix == ".parquet" and journal.exists())


def test_resume_refuses_a_file_of_another_sweep(address, tmp_path):
    out = tmp_path / "rows.csv"
    sweeps.sweep(lambda p: {"y": p["x"]}, "x=0,1", client=address, out=out, progress=False)
    with pytest.raises(ValueError, match="cannot resume"):
        sweeps.sweep(lambda p: {"y": p["x"]}, "w=0,1", client=address, out=out, progress=False)


# --- co-simulation path against the analytic path -----------------------------------------------


def test_cosim_sweep_opens_the_system_once_per_worker_and_agrees_with_the_closed_form(address, ten_pendula_ssp,
                                                                                        tmp_path):
    points = sweeps.grid("plant.g=9.0:10.6:5", "plant.zeta=0,0.01,0.02")
    with Client(address) as client:
        before = client.run(opened_and_reset)
    rows = sweeps.sweep(ten_pendula_cosim(ten_pendula_ssp, CountingMaster), points,
                        metrics=[SWING, sweeps.peak("profile.y")], client=address, out=tmp_path / "rows.csv",
                        progress=False)
    with Client(address) as client:
        after = client.run(opened_and_reset)
    opened = sum(after[w][0] - before.get(w, (0, 0))[0] for w in after)
    reused = sum(after[w][1] - before.get(w, (0, 0))[1] for w in after)
    assert 1 <= opened <= 2 and opened + reused == len(points)

    analytic = sweeps.sweep(analytic_swing(), points, vectorized=True)
    assert list(rows["status"]) == ["ok"] * len(points)
    np.testing.assert_allclose(rows["residual"], analytic["residual"], rtol=1e-7)
    np.testing.assert_array_equal(rows["peak"], np.max(np.abs(ten_pendula_profile(STEP).acceleration)))
    # Undamped at g = 9.81 the swing is paper 003's spectrum closed form, within the sampling.
    design = m_bc_tz_tp(3.5, 1.7, 0.7, delta_omega=0.05, ts=STEP)
    undamped = sweeps.sweep(analytic_swing(), sweeps.grid("plant.g=9.81", "plant.zeta=0"), vectorized=True)
    omegas = np.sqrt(9.81 / ten_pendula_lengths())
    assert undamped["residual"][0] == pytest.approx(np.max(design.residual_swing(omegas)), rel=0.05)


def test_an_ssd_sweep_ships_its_fmus_to_the_workers_and_equals_the_ssp_sweep(address, ten_pendula_ssp, tmp_path):
    # The .ssd names its FMUs relative to itself; the workers run in their own scratch folders.
    from shapefmu.fmi.ssp import read_ssp

    ssd = read_ssp(ten_pendula_ssp).write_ssd(tmp_path / "ten_pendula.ssd")
    points = "plant.zeta=0,0.02"
    rows = sweeps.sweep(ten_pendula_cosim(ssd), points, metrics=[SWING], client=address, progress=False)
    expected = sweeps.sweep(ten_pendula_cosim(ten_pendula_ssp), points, metrics=[SWING], client=address,
                            progress=False)
    assert list(rows["status"]) == ["ok", "ok"]
    np.testing.assert_array_equal(rows["residual"], expected["residual"])


def test_cosim_errors_of_a_run_are_rows(address, ten_pendula_ssp):
    # zeta = 1.5 is outside the plant FMU's damping-ratio range: that run fails, the others do not.
    rows = sweeps.sweep(ten_pendula_cosim(ten_pendula_ssp), "plant.zeta=0.01,1.5,0.02", metrics=[SWING],
                        client=address, progress=False)
    assert list(rows["status"]) == ["ok", "error", "ok"]
    assert "zeta" in rows["error"][1]
    expected = sweeps.sweep(analytic_swing(), sweeps.grid("plant.g=9.80665", "plant.zeta=0.01,0.02"), vectorized=True)
    np.testing.assert_allclose(rows["residual"][[0, 2]], expected["residual"], rtol=1e-7)


def test_killing_a_worker_process_mid_cosim_sweep_loses_no_run(address, ten_pendula_ssp, tmp_path):
    out = tmp_path / "rows.csv"
    with Client(address) as client:
        pids = client.run(os.getpid)
    victim = min(pids.values())

    def kill_when_rows_arrive():
        # Once 40 of the 200 rows are on disk, kill one worker process outright (no clean shutdown).
        deadline = time.monotonic() + 600.0  # a hang, not a slow machine
        while time.monotonic() < deadline:
            if out.exists() and out.read_text().count("\n") > 40:
                os.kill(victim, signal.SIGKILL)
                return
            time.sleep(0.005)

    killer = threading.Thread(target=kill_when_rows_arrive)
    killer.start()
    points = sweeps.grid("plant.g=9.0:10.6:20", "plant.zeta=0:0.02:10")
    rows = sweeps.sweep(ten_pendula_cosim(ten_pendula_ssp), points, metrics=[SWING], client=address, out=out,
                        batch_size=2, progress=False)
    killer.join()
    with Client(address) as client:
        client.wait_for_workers(2, timeout=60)
        assert victim not in client.run(os.getpid).values()  # the worker did die; the nanny restarted it
    assert len(rows) == 200 and list(rows["status"]) == ["ok"] * 200
    np.testing.assert_allclose(rows["residual"], sweeps.sweep(analytic_swing(), points, vectorized=True)["residual"],
                               rtol=1e-7)
    assert_same_rows(sweeps.read_rows(out), rows)


def test_a_timed_out_cosim_run_is_a_row_and_the_next_runs_start_afresh(address, ten_pendula_ssp):
    # 1200 s of 10 ms steps take seconds: each run is interrupted after 0.2 s.
    endless = sweeps.cosim(ten_pendula_ssp, step=STEP, stop_time=1200.0, record=RECORD, algorithm="jacobi")
    rows = sweeps.sweep(endless, "plant.zeta=0,0.01,0.02", metrics=[SWING], client=address, timeout=0.2,
                        progress=False)
    assert list(rows["status"]) == ["timeout"] * 3
    assert np.all(rows["wall_time"] >= 0.2)
    after = sweeps.sweep(ten_pendula_cosim(ten_pendula_ssp), "plant.zeta=0,0.01,0.02", metrics=[SWING],
                         client=address, timeout=60.0, progress=False)
    expected = sweeps.sweep(analytic_swing(), sweeps.grid("plant.g=9.80665", "plant.zeta=0,0.01,0.02"),
                            vectorized=True)
    assert list(after["status"]) == ["ok"] * 3
    np.testing.assert_allclose(after["residual"], expected["residual"], rtol=1e-7)


def test_thousand_run_ten_pendula_sweep_completes_on_the_default_local_cluster(ten_pendula_ssp, tmp_path):
    points = sweeps.grid("plant.g=9.0:10.6:40", "plant.zeta=0:0.02:25")
    rows = sweeps.sweep(ten_pendula_cosim(ten_pendula_ssp), points, metrics=[SWING], out=tmp_path / "rows.csv",
                        progress=False)
    assert len(rows) == 1000 and list(rows["status"]) == ["ok"] * 1000
    analytic = sweeps.sweep(analytic_swing(), points, vectorized=True)
    np.testing.assert_allclose(rows["residual"], analytic["residual"], rtol=1e-7)


def test_cli_sweep_writes_rows_and_the_robustness_map(address, ten_pendula_ssp, tmp_path, capsys):
    out, png = tmp_path / "rows.parquet", tmp_path / "map.png"
    code = main(["sweep", str(ten_pendula_ssp), "--vary", "plant.g=9.5:10.1:3", "--vary", "plant.zeta=0,0.02",
                 "--metric", "residual", "--metric", "peak", "--outputs", "plant.theta_*", "--command", "profile.y",
                 "--record", "profile.y", *[a for i in range(1, 11) for a in ("--record", f"plant.theta_{i}")],
                 "--algorithm", "jacobi", "--step", str(STEP), "--stop-time", str(STOP), "--out", str(out),
                 "--scheduler", address, "--plot", str(png)])
    assert code == 0
    printed = capsys.readouterr().out
    assert "6 runs: 6 ok" in printed and str(png) in printed
    rows = sweeps.read_rows(out)
    expected = sweeps.sweep(analytic_swing(), sweeps.grid("plant.g=9.5:10.1:3", "plant.zeta=0,0.02"), vectorized=True)
    np.testing.assert_allclose(rows["residual"], expected["residual"], rtol=1e-7)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_shaper_residual_analytic_path_is_analysis_residual_vibration():
    from shapefmu.analysis import residual_vibration
    from shapefmu.shapers import design

    shaper = design("zvd", [(2 * np.pi * 2000, 0.01)])
    points = sweeps.grid("plant.wn=11000:14000:31", "plant.zeta=0,0.01,0.05")
    rows = sweeps.sweep(shaper_residual(shaper), points, vectorized=True)
    expected = [residual_vibration(shaper, w, z) for w, z in points.values]
    np.testing.assert_allclose(rows["residual"], expected, rtol=1e-12)


# --- command line ------------------------------------------------------------------------------


def test_cli_sweep_rejects_bad_input_with_exit_code_2(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["sweep", str(TEN_PENDULA), "--vary", "plant.g=9:10", "--metric", "peak", "--command", "u",
              "--step", "0.01", "--stop-time", "1"])
    assert exit_.value.code == 2
    assert "plant.g=9:10" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit_:
        main(["sweep", str(TEN_PENDULA), "--vary", "plant.g=9:10:3", "--metric", "residual", "--step", "0.01",
              "--stop-time", "1"])
    assert exit_.value.code == 2
    assert "--outputs" in capsys.readouterr().err


def test_robustness_map_is_written_for_one_and_two_parameters(tmp_path):
    points = sweeps.grid("plant.wn=11000:14000:31", "plant.zeta=0,0.01,0.05")
    rows = sweeps.sweep(shaper_residual(sweeps_shaper()), points, vectorized=True)
    for y in (None, "plant.zeta"):
        path = sweeps.plot_map(rows, "residual", tmp_path / f"map_{y}.png", x="plant.wn", y=y)
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ValueError, match="plant.q"):
        sweeps.plot_map(rows, "residual", tmp_path / "map.png", x="plant.q")


def sweeps_shaper():
    from shapefmu.shapers import design

    return design("zv", [(2 * np.pi * 2000, 0.01)])
