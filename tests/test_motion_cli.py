"""``shapefmu motion plan`` prints the planner's move beside Ruckig's and writes its samples.

References: Ruckig's duration for the same move (pip ``ruckig``) and the issue's Ruckig + ZV figure.
"""

import csv
import json

import pytest

from shapefmu.cli import main
from shapefmu.runtime.jerk_profiles import Limits
from support.motion_cases import ruckig_trajectory

EXAMPLE = ["motion", "plan", "--axis", "x:0:0.01:0.3:5:2000", "--mode", "40:0.05", "--vtol", "0.01"]


def test_the_40_hz_example_is_printed_beside_ruckig(capsys, tmp_path):
    out = tmp_path / "traj.csv"
    assert main([*EXAMPLE, "--json", "--out", str(out), "--ts", "1e-3"]) == 0
    printed = capsys.readouterr()
    record = json.loads(printed.out)  # stdout holds the JSON alone; the file written is said on stderr
    assert f"written to {out}" in printed.err
    peer = ruckig_trajectory([(0.0, 0.0, 0.0)], [(0.01, 0.0, 0.0)], [Limits(0.3, 5.0, 2000.0)]).duration
    assert record["ruckig_duration"] == pytest.approx(peer, rel=1e-12)
    assert record["rigid_duration"] == pytest.approx(peer, rel=1e-9)
    assert record["ruckig_shaped_duration"] == pytest.approx(0.1045, abs=5e-5)  # the Ruckig + ZV
    assert record["ruckig_shapers"] == {"x": "zv"}
    assert record["duration"] <= 0.098
    mode, = record["modes"]
    assert mode["ratio"] <= 0.01 and mode["rigid_residual"] == pytest.approx(78e-6, rel=0.01)
    rows = list(csv.DictReader(out.open()))
    assert list(rows[0]) == ["time", "x.position", "x.velocity", "x.acceleration", "x.jerk"]
    assert float(rows[-1]["x.position"]) == pytest.approx(0.01, abs=1e-12)
    assert float(rows[-1]["time"]) >= record["duration"] > float(rows[-2]["time"])


def test_the_table_names_every_mode_and_ruckig(capsys):
    assert main(["motion", "plan", "--axis", "x:0:0.01:0.3:5:2000", "--axis", "y:0:-0.004:0.2:3:1000",
                 "--mode", "x:40:0.05"]) == 0
    text = capsys.readouterr().out
    assert "mode x 40 Hz zeta 0.05" in text and "mode y" not in text
    assert "Ruckig: " in text and "Ruckig + shortest shaper (x: zv)" in text


@pytest.mark.parametrize("argv, message", [
    (["--axis", "x:0:0.01:0.3:5"], "--axis must be NAME:FROM:TO:VMAX:AMAX:JMAX"),
    (["--axis", "x:0:0.01:0.3:5:-1"], "--axis JMAX must be > 0"),
    (["--axis", "x:0:0.01:0.3:5:2000", "--mode", "z:40:0.05"], "--mode names axis 'z'"),
    (["--axis", "x:0:0.01:0.3:5:2000", "--mode", "40:1.2"], "--mode damping ratio must be in [0, 1)"),
    (["--axis", "x:0:0.01:0.3:5:2000", "--axis", "x:0:0.02:0.3:5:2000"], "--axis names must differ"),
    (["--axis", "x:0:0.01:0.3:5:2000", "--mode", "40:0.05", "--band", "0.9"], "band must be in [0, 0.5)"),
])
def test_bad_input_exits_2_with_one_line(argv, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["motion", "plan", *argv])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
