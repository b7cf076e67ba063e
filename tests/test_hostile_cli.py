"""Every command fed malformed values: exit 2 for what was given wrong, 1 for work that failed, one line
on stderr naming the culprit, no traceback, nothing written outside the output path, a bounded run
time. Table-driven per command (design, plant, optimal, stos, build, simulate, sweep), property-based
for the numbers of design and simulate, and SIGTERM to a running simulate, which saves its results."""

import math
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hostile_support import guarded
from support.run_watch import OutputWatch

from shapefmu.fmi.ssp import System

MODELS = Path(__file__).resolve().parents[1] / "models"
DISK = str(MODELS / "disk_drive.toml")


@pytest.fixture(scope="module")
def shaper_ssp(tmp_path_factory, shaper_fmu):
    """The ZV Shaper FMU of fixtures_fmi (10 Hz, Ts = 1 ms) alone in a system, as Shaper.fmu."""
    folder = tmp_path_factory.mktemp("cli_alone")
    fmu = folder / "Shaper.fmu"
    shutil.copy(shaper_fmu, fmu)  # the session's build has a file name of its own
    return System("alone").add("shaper", fmu).write_ssp(folder / "alone.ssp")


def assert_refused(argv, code, words, workdir):
    """The command exits ``code`` with one line naming ``words``, and writes nothing in ``workdir``
    (the current folder) nor at the output paths it names."""
    before = sorted(workdir.rglob("*"))
    got, _, err = guarded(argv)
    assert got == code, err
    assert "Traceback" not in err and err.count("\n") == 1, err
    assert err.startswith(f"shapefmu {argv[0]}") and words in err, err
    assert sorted(workdir.rglob("*")) == before


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    return tmp_path


DESIGN = [
    (["design", "zv", "--mode", "x"], "--mode must be HZ or HZ:ZETA"),
    (["design", "zv", "--mode", "nan"], "--mode frequency must be > 0 Hz"),
    (["design", "zv", "--mode", "5:inf"], "--mode damping ratio must be in [0, 1)"),
    (["design", "ei", "--mode", "5", "--vtol", "inf"], "vtol must be a finite real number, got inf"),
    (["design", "zv_dn", "--mode", "5", "--n", "1.5"], "argument --n: invalid int value: '1.5'"),
    (["design", "zv_dn", "--mode", "5", "--n", "-1"], "n must be an integer >= 0, got -1"),
    (["design", "hanning", "--mode", "5", "--ts", "-1"], "ts must be > 0, got -1.0"),
    (["design", "hanning", "--mode", "5", "--order", "0"], "order must be an integer >= 1, got 0"),
    (["design", "hanning", "--mode", "5", "--mode", "6"], "takes exactly one --mode, got 2"),
    (["design", "simultaneous", "--mode", "5", "--mode", "5"], "distinct frequencies"),
    (["design", "kaiser", "--mode", "5"], "argument kind: invalid choice: 'kaiser'"),
    (["sensitivity", "zv", "--mode", "5", "--plot", "curve.txt"], "the plot name must end in"),
    (["profile", "TP", "--mode", "1", "--distance", "nan", "--speed", "1"], "distance must be a finite real number"),
]
PLANT = [
    (["plant", "show", "missing.toml"], "missing.toml: no such file, and no shipped plant model of that name (shipped: disk_drive,"),
    (["plant", "show", "results/missing.toml"], "results/missing.toml: cannot read plant model: No such file or directory"),
    (["plant", "show", "."], ".: cannot read plant model: Is a directory"),
    (["plant", "build", DISK, "-o", "out/plant.zip"], "the FMU name must end in .fmu"),
    (["plant", "build", "missing.toml", "-o", "out/P.fmu"], "missing.toml: no such file, and no shipped plant model of that name"),
    (["plant", "build", "out/missing.toml", "-o", "out/P.fmu"], "model file 'out/missing.toml' does not exist"),
]
MOVES = [
    (["optimal", DISK, "--distance", "nan"], "distance must be a finite real number, got nan"),
    (["optimal", DISK, "--distance", "0"], "distance must be non-zero"),
    (["optimal", DISK, "--distance", "0.05", "--u-max", "-1"], "u_max must be > 0, got -1.0"),
    (["optimal", DISK, "--distance", "0.05", "--json", "out/s.txt"], "the solution file name must end in .json"),
    (["optimal", DISK, "--distance", "0.05", "--csv", "out/u.json"], "the signal table name must end in .csv"),
    (["optimal", DISK, "--distance", "0.05", "--plot", "."], "'.': the plot name must end in"),
    (["optimal", DISK, "--distance", "1e-30"], "no time-optimal move found for distance = 1e-30 with u_max = 11.0"),
    (["stos", DISK, "--distance", "1e-300"], "no time-optimal move found for distance = 1e-300"),
    (["optimal", DISK, "--distance", "0.05", "--u-max", "1e30"],
     "no time-optimal move found for distance = 0.05 with u_max = 1e+30"),
    (["stos", DISK, "--distance", "0.05", "--ts", "0"], "Ts must be > 0, got 0.0"),
    (["stos", DISK, "--distance", "0.05", "--t-end", "-1"], "t_end must be > 0, got -1.0"),
    (["stos", DISK, "--distance", "0.05", "--shaper", "zv"], "argument --shaper: invalid choice: 'zv'"),
    (["stos", str(MODELS / "ten_pendula.toml"), "--distance", "0.05"], "declares no limit for input 'acceleration'"),
]
BUILD = [
    (["build", "shaper", "--mode", "10", "--ts", "0", "-o", "out/S.fmu"], "ts must be > 0, got 0.0"),
    (["build", "shaper", "--mode", "10", "--kind", "zv_dn", "--n", "5000", "-o", "out/S.fmu"], "n must be in [0, 100]"),
    (["build", "shaper", "--mode", "10", "-o", "out/S.txt"], "the FMU name must end in .fmu"),
    (["build", "shaper", *["--mode", "10"] * 5, "-o", "out/S.fmu"], "--mode may be given at most 4 times, got 5"),
    (["build", "shape-filter", "--kind", "hanning", "--mode", "10", "--order", "1000", "--adjust-ts",
      "-o", "out/F.fmu"], "multiply-adds, more than the limit of 50,000,000"),
    (["build", "reference", "missing.json", "-o", "out/R.fmu"], "missing.json: cannot read signal table: No such file"),
    (["build", "all", "-o", DISK], "is a file; give a folder"),
]


@pytest.mark.parametrize("argv, words", DESIGN + PLANT + MOVES + BUILD, ids=lambda v: " ".join(v)[:60]
                         if isinstance(v, list) else None)
def test_design_plant_moves_and_build_refuse_malformed_values(workdir, argv, words):
    assert_refused(argv, 2, words, workdir)


def simulate_cases(ssp):
    run = ["simulate", str(ssp), "--stop", "0.01", "--step", "1e-3"]
    return [
        (run[:2] + ["--stop", "nan", "--step", "1e-3"], 2, "stop_time must be a finite number > start time"),
        (run[:4] + ["--step", "inf"], 2, "step must be a finite number > 0 s, got inf"),
        (run + ["--output-interval", "nan"], 2, "output_interval must be a finite whole multiple"),
        (run + ["--record", "shaper.nope"], 2, "component 'shaper' (Shaper.fmu) has no variable 'nope'"),
        (run + ["--set", "shaper.u0=abc"], 2, "parameter shaper.u0 must be a number (Real), got 'abc'"),
        (run + ["--set", "shaper.u0"], 2, "--set must be component.variable=VALUE"),
        (run + ["--set", "shaper.n=1e30"], 2, "parameter shaper.n must be an integer in [-2147483648, 2147483647] (Integer), got '1e30'"),
        (run + ["--set", "shaper.zeta[1]=1.5"], 1, "zeta[1] must be in [0, 1), got 1.5"),
        (run + ["--set", "shaper.u=nan"], 1, "u must be a finite real number, got nan"),
        (run + ["--out", "out/r.txt"], 2, "the results file name must end in .csv, .parquet"),
        (run + ["--out", "."], 2, "the results file name must end in"),
        (run + ["--plot", "out/p.data"], 2, "the plot name must end in"),
        (run + ["--model-exchange", "shaper"], 2, "Shaper.fmu has no Model Exchange interface"),
        (["simulate", "missing.ssp", "--stop", "1", "--step", "1"], 2, "missing.ssp: no such file, and no shipped SSP system"),
        (["simulate", "out/missing.ssp", "--stop", "1", "--step", "1"], 2, "SSP file not found: out/missing.ssp"),
    ]


def test_simulate_refuses_malformed_values(shaper_ssp, workdir):
    for argv, code, words in simulate_cases(shaper_ssp):
        assert_refused(argv, code, words, workdir)


def test_sweep_refuses_malformed_values(shaper_ssp, workdir):
    base = ["sweep", str(shaper_ssp), "--metric", "peak", "--command", "shaper.y", "--step", "1e-3",
            "--stop-time", "0.01"]
    for extra, words in [
        (["--vary", "shaper.u0=0:1"], "--vary must be NAME=START:STOP:N"),
        (["--vary", "shaper.u0=0:1:0"], "the number of points of shaper.u0 must be >= 1"),
        (["--sample", "shaper.u0=1:0", "--samples", "3"], "finite LOW < HIGH"),
        (["--vary", "shaper.u0=0:1:2", "--timeout", "-1"], "timeout must be > 0"),
        (["--vary", "shaper.u0=0:1:2", "--workers", "-1"], "--workers must be an integer >= 1"),
        (["--vary", "shaper.u0=0:1:2", "--plot", "map.csv"], "the plot name must end in"),
    ]:
        assert_refused(base + extra, 2, words, workdir)


def test_an_unwritable_output_is_refused_before_the_run(shaper_ssp, workdir):
    blocker = workdir / "blocker"
    blocker.write_text("a file where a folder is expected")
    argv = ["simulate", str(shaper_ssp), "--stop", "0.01", "--step", "1e-3", "--out", "blocker/r.csv"]
    assert_refused(argv, 2, "'blocker' on its path is a file, not a folder", workdir)


def test_outputs_in_missing_folders_are_written_after_the_run(shaper_ssp, workdir):
    code, out, err = guarded(["simulate", str(shaper_ssp), "--stop", "0.01", "--step", "1e-3",
                              "--out", "new/r.csv", "--plot", "new/deeper/p.png"])
    assert code == 0, err
    saved = np.genfromtxt(workdir / "new" / "r.csv", delimiter=",", names=True)
    assert saved.size == 11 and (workdir / "new" / "deeper" / "p.png").read_bytes()[:4] == b"\x89PNG"


FINITE_OR_NOT = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**30, 10**30),
                          st.sampled_from(["", "x", "1e999", "-0", "0x10", "1_000", " 5 "]))


@settings(max_examples=40, deadline=None, database=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(kind=st.sampled_from(["zv", "zvd", "zv_dn", "mzv", "hanning", "rectangle"]), mode=FINITE_OR_NOT,
       zeta=FINITE_OR_NOT, option=st.sampled_from(["--n", "--vtol", "--ts", "--order"]), value=FINITE_OR_NOT)
def test_design_never_crashes_on_any_number(workdir, kind, mode, zeta, option, value):
    argv = ["design", kind, "--mode", f"{mode}:{zeta}", option, str(value)]
    code, _, err = guarded(argv)
    assert code in (0, 2), err
    if code == 2:
        assert err.count("\n") == 1 and "Traceback" not in err and err.startswith("shapefmu design")
    assert list(workdir.iterdir()) == []


# Times that are malformed, absurd or short: a long legitimate run is not what this test is about.
TIMES = st.sampled_from(["nan", "inf", "-1", "0", "1e400", "1e-300", "x", "", "1e12", "0.003", "0.01", "1e-3"])


@settings(max_examples=20, deadline=None, database=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(stop=TIMES, step=TIMES, parameter=st.sampled_from(["n_modes", "n", "Ts", "f[1]", "u0", "kind"]),
       value=FINITE_OR_NOT)
def test_simulate_never_crashes_on_any_number(shaper_ssp, workdir, stop, step, parameter, value):
    argv = ["simulate", str(shaper_ssp), "--stop", str(stop), "--step", str(step), "--set", f"shaper.{parameter}={value}"]
    code, _, err = guarded(argv)
    assert code in (0, 1, 2), err
    if code:
        assert "Traceback" not in err and err.splitlines()[-1].startswith("shapefmu simulate")
        assert len(err.splitlines()) <= 2  # the error; a warning line at most (a mode above Nyquist)
    assert list(workdir.iterdir()) == []


def test_sigterm_stops_simulate_and_saves_what_it_recorded(shaper_ssp, tmp_path):
    # A batch system's kill, `timeout`, `kill PID`: like Ctrl-C, the records so far are saved.
    out = tmp_path / "partial.csv"
    process = subprocess.Popen(
        [sys.executable, "-m", "shapefmu", "simulate", str(shaper_ssp), "--stop", "1e4", "--step", "1e-3",
         "--output-interval", "1e-2", "--progress", "--out", str(out), "--set", "shaper.u0=0"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    watch = OutputWatch(process)
    watch.wait_for("steps/s")  # running, past its first progress update
    process.send_signal(signal.SIGTERM)
    stdout, stderr = watch.finish()
    assert process.returncode == 143, stderr
    assert "shapefmu simulate: co-simulation interrupted at t = " in stderr and "(SIGTERM)" in stderr
    assert "Traceback" not in stderr
    saved = np.genfromtxt(out, delimiter=",", names=True)
    assert 2 <= saved.size < 1_000_001 and f"results written to {out}" in stdout
    # The ZV shaper (u0 = 0, input u = 0) outputs 0 throughout; its records are every 10 ms.
    np.testing.assert_allclose(np.diff(saved["time"]), 0.01, rtol=1e-9)
    assert not np.any(saved["shapery"]) and math.isclose(saved["time"][0], 0.0)
