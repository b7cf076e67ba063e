"""``shapefmu recommend REC... --schedule NAME=V1,V2,...`` (issue 37): the table of a scheduled shaper from
recordings at several values of a scheduling input.

Reference: the modes the recordings were made with (``identification.synthetic``'s Klipper resonance
test of the bed of models/printer_bed.toml with 0 and 300 g on it: 30 Hz, zeta 0.05 and 30 / sqrt(1.3)
Hz, zeta 0.05 / sqrt(1.3)), to 1e-4 in frequency and 1 % in damping.
"""

import json
import math

import pytest

from shapefmu.cli import main

BED = {0.0: (30.0, 0.05), 300.0: (30.0 / math.sqrt(1.3), 0.05 / math.sqrt(1.3))}


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    """Klipper raw recordings of the bed at 300 g and at 0 g (listed in that order)."""
    from shapefmu.identification import synthetic

    folder = tmp_path_factory.mktemp("schedule")
    paths = []
    for grams in (300.0, 0.0):
        t, xyz = synthetic.record([synthetic.SyntheticMode(*BED[grams])], seed=int(grams))
        path = folder / f"resonances_{grams:.0f}g.csv"
        synthetic.write_klipper_raw(path, t, xyz)
        paths.append(str(path))
    return paths


def test_the_table_holds_each_recordings_mode_at_its_value_sorted(recordings, capsys):
    assert main(["recommend", *recordings, "--axis", "x", "--schedule", "mass=300,0", "--json", "-q"]) == 0
    table = json.loads(capsys.readouterr().out)
    assert table["scheduling"] == "mass"
    assert [row["value"] for row in table["rows"]] == [0.0, 300.0]
    for row in table["rows"]:
        hz, zeta = BED[row["value"]]
        assert row["frequency_hz"] == pytest.approx(hz, rel=1e-4)
        assert row["zeta"] == pytest.approx(zeta, rel=0.01)
    starts = table["start_values"]
    assert starts["n_rows"] == 2 and starts["values[2]"] == 300.0
    assert starts["f[2]"] == table["rows"][1]["frequency_hz"]


def test_build_writes_the_scheduled_shaper_fmu_holding_the_table(recordings, tmp_path, capsys):
    from fmpy import read_model_description

    out = tmp_path / "Bed.fmu"
    assert main(["recommend", *recordings, "--axis", "x", "--schedule", "mass=300,0", "--build", str(out), "-q"]) == 0
    printed = capsys.readouterr().out
    assert "mass = 300" in printed and "ScheduledShaper start values: n_rows=2" in printed
    starts = {v.name: v.start for v in read_model_description(str(out)).modelVariables}
    assert float(starts["values[1]"]) == 0.0 and float(starts["f[1]"]) == pytest.approx(30.0, rel=1e-4)
    assert starts["n_rows"] == "2"


@pytest.mark.parametrize("arguments, message", [
    (["--schedule", "mass=100"], "2 to 8 values"),
    (["--schedule", "mass=1,1"], "finite and distinct"),
    (["--schedule", "=1,2"], "NAME=V1,V2"),
    (["--schedule", "mass=1,x"], "must be numbers"),
])
def test_a_bad_schedule_is_refused_in_one_line(recordings, capsys, arguments, message):
    with pytest.raises(SystemExit) as stop:
        main(["recommend", *recordings, *arguments])
    assert stop.value.code != 0
    assert message in capsys.readouterr().err


def test_one_value_per_recording_is_required(recordings, capsys):
    with pytest.raises(SystemExit):
        main(["recommend", *recordings, "--axis", "x", "--schedule", "mass=0,100,300", "-q"])
    assert "lists 3 values for 2 recordings" in capsys.readouterr().err
