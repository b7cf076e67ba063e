"""Sweeps that lose nothing: an output file cut empty or inside its header resumes, failed runs can be
run again with retry_failed (--retry-failed), no rerun writes a point twice, and a sweep that cannot
succeed says so before starting a cluster, or exits 1 when every run failed."""

import functools
import uuid
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("distributed")
from distributed import LocalCluster  # noqa: E402
from hostile_support import guarded, time_limit  # noqa: E402

from shapefmu import sweep as sweeps  # noqa: E402
from shapefmu.fmi.ssp import System  # noqa: E402

POINTS = "x=1:5:5"


def flaky(parameters, folder):
    """{"y": x^2}, except that x = 3 fails until ``folder`` holds a file "fixed"; every run leaves a
    file "ran_<x>_<id>" in ``folder``, so a test counts the runs."""
    x = parameters["x"]
    Path(folder, f"ran_{x:g}_{uuid.uuid4().hex}").touch()
    if x == 3.0 and not Path(folder, "fixed").exists():
        raise RuntimeError("diverged at x = 3")
    return {"y": x * x}


def runs(folder) -> list[str]:
    return sorted(p.name.split("_")[1] for p in Path(folder).glob("ran_*"))


@pytest.fixture(scope="module")
def address():
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
        yield cluster.scheduler_address


@pytest.fixture(autouse=True)
def bounded_time():
    with time_limit(120):
        yield


def run(folder, out, address, **options):
    target = functools.partial(flaky, folder=str(folder))
    return sweeps.sweep(target, POINTS, out=out, client=address, progress=False, **options)


@pytest.mark.parametrize("damage", ["", "run,x,y,sta"], ids=["empty", "cut inside the header"])
def test_an_output_file_cut_empty_or_inside_its_header_resumes(address, tmp_path, damage):
    (tmp_path / "fixed").touch()
    out = tmp_path / "rows.csv"
    out.write_text(damage)  # what a sweep killed while it started leaves
    rows = run(tmp_path, out, address)
    assert list(rows["status"]) == ["ok"] * 5 and rows.resumed == 0
    assert out.read_text().splitlines()[0] == "run,x,y,status,error,wall_time"
    again = run(tmp_path, out, address)  # the next resume reads it back and runs nothing
    assert again.resumed == 5 and runs(tmp_path) == ["1", "2", "3", "4", "5"]
    np.testing.assert_array_equal(sweeps.read_rows(out)["y"], [1.0, 4.0, 9.0, 16.0, 25.0])


def test_failed_rows_are_kept_on_resume_and_run_again_with_retry_failed(address, tmp_path):
    out = tmp_path / "rows.csv"
    first = run(tmp_path, out, address)
    assert list(first["status"]) == ["ok", "ok", "error", "ok", "ok"]
    (tmp_path / "fixed").touch()
    kept = run(tmp_path, out, address)
    assert kept.resumed == 5 and kept.resumed_failed == 1 and runs(tmp_path) == ["1", "2", "3", "4", "5"]
    assert "5 of them resumed from the output file, not run again; 1 of those are errors or timeouts: " \
           "--retry-failed runs them again" in sweeps.summary(kept, ["y"])
    retried = run(tmp_path, out, address, retry_failed=True)
    assert runs(tmp_path) == ["1", "2", "3", "3", "4", "5"]  # x = 3 alone ran again
    assert retried.resumed == 4 and list(retried["status"]) == ["ok"] * 5
    saved = sweeps.read_rows(out)
    assert list(saved["x"]) == [1.0, 2.0, 3.0, 4.0, 5.0]  # one row per point: the new one replaced the error
    np.testing.assert_array_equal(saved["y"], [1.0, 4.0, 9.0, 16.0, 25.0])


def test_reruns_never_write_a_point_twice(address, tmp_path):
    out = tmp_path / "rows.csv"
    for _ in range(3):
        run(tmp_path, out, address, retry_failed=True)
    assert len(out.read_text().splitlines()) == 1 + 5


@pytest.mark.parametrize("spec", ["x=1,1,2", "x=2,1,2"])
def test_a_grid_value_given_twice_is_refused(spec):
    with pytest.raises(ValueError, match=r"parameter points must be distinct, but \{'x': [12].0\} appears 2 times"):
        sweeps.grid(spec)


# --- the command line --------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def shaper_ssp(tmp_path_factory, shaper_fmu):
    return System("alone").add("shaper", shaper_fmu).write_ssp(tmp_path_factory.mktemp("sweep_alone") / "alone.ssp")


def sweep_cli(ssp, *extra):
    return ["sweep", str(ssp), "--metric", "peak", "--command", "shaper.y", "--step", "1e-3", "--stop-time", "0.01",
            *extra]


@pytest.mark.parametrize("extra, words", [
    (["--vary", "shaper.u0=0:1:2", "--workers", "-1"], "--workers must be an integer >= 1"),
    (["--vary", "shaper.u0=0:1:2", "--workers", "0"], "--workers must be an integer >= 1"),
    (["--vary", "shaper.u0=0:1:2", "--workers", "500"], "--workers must be at most"),
    (["--vary", "shaper.nope=0:1:2"], "component 'shaper' of "),
    (["--vary", "plant.u0=0:1:2"], "must be component.variable with a component of"),
    (["--vary", "shaper.u0=0:1:2", "--algorithm", "newton"], "argument --algorithm: invalid choice: 'newton'"),
    (["--vary", "shaper.u0=1,1"], "parameter points must be distinct"),
    (["--vary", "shaper.u0=0:1:1000000000"], "1,000,000,000 points, more than the limit of 10,000,000"),
    (["--vary", "shaper.u0=0:1:2", "--out", "rows.txt"], "the rows file name must end in .csv, .parquet"),
])
def test_a_sweep_that_cannot_succeed_is_refused_before_any_run(shaper_ssp, extra, words):
    code, _, err = guarded(sweep_cli(shaper_ssp, *extra))
    assert code == 2 and err.count("\n") == 1 and err.startswith("shapefmu sweep: error: ") and words in err


def test_a_sweep_whose_every_run_failed_exits_1(shaper_ssp, address, tmp_path):
    out = tmp_path / "rows.csv"
    code, printed, err = guarded(sweep_cli(shaper_ssp, "--vary", "shaper.zeta[1]=1.5,2", "--scheduler", address,
                                          "--out", str(out)))
    assert code == 1 and "2 runs: 2 error" in printed
    last = err.splitlines()[-1]  # after the progress bar
    assert last.startswith("shapefmu sweep: error: none of the 2 runs succeeded (first error: ") and "zeta[1]" in last
    assert [r for r in sweeps.read_rows(out)["status"]] == ["error", "error"]
