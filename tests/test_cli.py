"""The command line prints what the design layer computes, and refuses bad input clearly."""

import json
import math

import pytest

from shapefmu.cli import main
from shapefmu.shapers import simultaneous


def test_design_json_is_the_simultaneous_shaper(capsys):
    assert main(["design", "simultaneous", "--mode", "2000:0.01", "--mode", "3000:0.01", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    want = simultaneous([(2 * math.pi * 2000, 0.01), (2 * math.pi * 3000, 0.01)])
    assert record["times"] == pytest.approx(want.times, rel=1e-12)
    assert record["amplitudes"] == pytest.approx(want.amplitudes, rel=1e-12)
    assert all(mode["residual"] < 1e-9 for mode in record["modes"])


def test_design_table_lists_every_impulse(capsys):
    assert main(["design", "zvd", "--mode", "10"]) == 0
    rows = [line.split() for line in capsys.readouterr().out.splitlines() if line.strip()[:1].isdigit()]
    assert [float(a) for _, a in rows] == pytest.approx([0.25, 0.5, 0.25], abs=1e-6)
    assert [float(t) for t, _ in rows] == pytest.approx([0.0, 0.05, 0.1], abs=1e-9)


def test_sensitivity_writes_a_png_and_reports_the_band(tmp_path, capsys):
    out = tmp_path / "curve.png"
    assert main(["sensitivity", "zv", "--mode", "1", "--plot", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"I = {4 * math.asin(0.05) / math.pi:.4f}" in capsys.readouterr().out


@pytest.mark.parametrize(
    "argv, message",
    [
        (["design", "zv", "--mode", "-5"], "--mode frequency must be > 0 Hz"),
        (["design", "zv", "--mode", "5:1.5"], "--mode damping ratio must be in [0, 1)"),
        (["design", "ei", "--mode", "5", "--vtol", "2"], "vtol must be in (0, 1), got 2.0"),
    ],
)
def test_bad_input_exits_2_naming_the_parameter(argv, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err


def test_design_window_filter_reports_paper_length_and_zero_residual(capsys):
    # omega = 1 rad/s, zeta = 0.2 and the default ts = pi/(100 omega_d): Hanning M = 400 (paper 000).
    assert main(["design", "hanning", "--mode", f"{1 / (2 * math.pi)}:0.2"]) == 0
    out = capsys.readouterr().out
    assert "401 taps" in out
    assert float(out.split("residual vibration ")[1].split(" %")[0]) < 1e-7


def test_profile_reaches_the_distance_at_the_papers_slew_speed(capsys):
    argv = ["profile", "M-BC:TZ:TP", "--mode", f"{3.5 / (2 * math.pi)}", "--distance", "1.7", "--speed", "0.7",
            "--delta-omega", "0.05", "--json"]
    assert main(argv) == 0
    profile = json.loads(capsys.readouterr().out)
    assert profile["position"][-1] == pytest.approx(1.7, rel=1e-9)
    assert max(profile["velocity"]) == pytest.approx(0.4735, abs=5e-5)


def test_plant_show_lists_the_disk_drive_modes_of_table_1(capsys):
    assert main(["plant", "show", "models/disk_drive.toml"]) == 0
    rows = [line.split() for line in capsys.readouterr().out.splitlines()]
    modes = [(float(r[0]), float(r[2])) for r in rows if len(r) >= 4 and r[0] in ("2000", "3000")]
    assert modes == [(2000.0, 0.01), (3000.0, 0.01)]


@pytest.mark.parametrize("quiet", [False, True])
def test_optimal_tells_a_terminal_each_solver_phase_and_quiet_silences_it(quiet, monkeypatch, capsys):
    monkeypatch.setattr("sys.stderr.isatty", lambda: True, raising=False)
    assert main(["optimal", "disk_drive", "--distance", "0.05"] + ["--quiet"] * quiet) == 0
    out, err = capsys.readouterr()
    if quiet:
        assert err == ""
        return
    phases = [line.split("] ", 1)[1] for line in err.splitlines()]
    assert [p.split(":")[0].split(" of ")[0] for p in phases] == [
        "rigid bang-bang", "time-optimal move", "time-optimal move", "simulating 4 moves on the full plant"]
    grid_T = float(phases[2].split("grid's ")[1].split(" s")[0])
    printed = float(out.split("transcription T = ")[1].split(" s")[0])
    assert grid_T == pytest.approx(printed, rel=1e-5)
