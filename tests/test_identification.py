"""From a recording to its modes (issue 25): modes of known machines recorded as Klipper and
RepRapFirmware record them, and bad recordings refused in one line. The recommendation made from them
is tests/test_recommend.py's."""


import numpy as np
import pytest
from hostile_support import guarded

from shapefmu.identification import identify, metrics
from shapefmu.identification import synthetic as syn

MACHINES = {
    "one mode": [syn.SyntheticMode(40.0, 0.05)],
    "lightly damped": [syn.SyntheticMode(30.0, 0.02)],
    "heavily damped": [syn.SyntheticMode(45.0, 0.2)],
    "two modes": [syn.SyntheticMode(25.0, 0.05, 0.6), syn.SyntheticMode(62.0, 0.08, 0.4)],
    "three modes": [syn.SyntheticMode(20.0, 0.03, 0.5), syn.SyntheticMode(45.0, 0.1, 0.3),
                    syn.SyntheticMode(90.0, 0.05, 0.2)],
    "0.2 beside 0.02": [syn.SyntheticMode(22.0, 0.2, 0.6), syn.SyntheticMode(60.0, 0.02, 0.4)],
}


def assert_modes(found, machine, frequency_error=0.01, zeta_error=0.25):
    assert len(found) == len(machine), [m.describe() for m in found]
    for true in machine:
        mode = min(found, key=lambda m: abs(m.frequency - true.frequency))
        assert abs(mode.frequency / true.frequency - 1) < frequency_error, (mode.describe(), true)
        assert abs(mode.zeta / true.zeta - 1) < zeta_error, (mode.describe(), true)


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    folder = tmp_path_factory.mktemp("recordings")
    files = {}
    for i, (name, machine) in enumerate(MACHINES.items()):
        t, xyz = syn.record(machine, seed=i)
        raw = folder / f"raw{i}.csv"
        syn.write_klipper_raw(raw, t, xyz)
        rrf = folder / f"m956_{i}.csv"
        syn.write_rrf_m956(rrf, t, xyz, axes="XY")
        files[name] = (raw, rrf)
    return files


@pytest.mark.parametrize("name", MACHINES)
def test_klipper_raw_recordings_give_the_machines_modes(recordings, name):
    found = identify(recordings[name][0], axis="x")
    assert_modes(found.modes.modes, MACHINES[name])
    assert found.recording.jitter > 0.001 and found.recording.gaps == 0  # jittered, as Klipper's are


@pytest.mark.parametrize("name", ["one mode", "two modes", "three modes"])
def test_m956_and_spectrum_files_give_the_raw_files_modes(recordings, name, tmp_path):
    raw = identify(recordings[name][0], axis="x").modes.modes
    rrf = identify(recordings[name][1], axis="x", excitation="sweep").modes.modes
    assert_modes(rrf, [syn.SyntheticMode(m.frequency, m.zeta) for m in raw])
    # the processed file Klipper writes from the same data: its spectra, written and read back
    x, y = (identify(recordings[name][0], axis=a).spectrum for a in "xy")
    spectrum_file = tmp_path / "calibration_data_x.csv"
    syn.write_klipper_spectrum(spectrum_file, x.freq, (x.psd, y.psd, 0 * x.psd))
    processed = identify(spectrum_file, axis="x").modes.modes
    assert_modes(processed, [syn.SyntheticMode(m.frequency, m.zeta) for m in raw])


def test_a_table_with_a_time_column_or_a_rate_and_a_parquet_file(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq

    machine = [syn.SyntheticMode(35.0, 0.04)]
    t, xyz = syn.record(machine, seed=7)
    csv = tmp_path / "encoder.csv"
    np.savetxt(csv, np.column_stack([t, xyz[:, 0]]), delimiter=",", header="seconds,error", comments="")
    assert_modes(identify(csv, axis="error", time_column="seconds", columns=["error"], excitation="sweep").modes.modes,
                 machine)
    table = tmp_path / "log.parquet"
    pq.write_table(pa.table({"a": xyz[:, 0]}), table)
    rate = (len(t) - 1) / (t[-1] - t[0])
    assert_modes(identify(table, axis="a", fs=rate, columns=["a"], excitation="sweep").modes.modes, machine)


def test_a_ring_down_is_refined_by_the_ekf_and_checked_by_the_log_decrement(tmp_path):
    machine = [syn.SyntheticMode(18.0, 0.03)]
    t, y = syn.ring_down(machine, fs=1000.0, duration=4.0)
    path = tmp_path / "tap.csv"
    np.savetxt(path, np.column_stack([t, y]), delimiter=",", header="t,y", comments="")
    found = identify(path, axis="y", time_column="t", columns=["y"], response="mode", ringdown=True)
    (mode,) = found.modes.modes
    assert mode.method == "EKF on the ring-down"
    assert_modes([mode], machine, zeta_error=0.1)
    assert abs(mode.log_decrement_zeta / 0.03 - 1) < 0.1


BAD = [
    (b"", "line 1: expected a recording, got an empty file"),
    (b"#time,accel_x,accel_y,accel_z\n", "line 2: expected rows of numbers after the header, got none"),
    (b"#time,accel_x,accel_y,accel_z\n" + b"".join(b"%f,1,2,3\n" % (i * 1e-3) for i in range(20))
     + b"0.005,1,2,3\n", "line 22: expected the time to increase"),
    (b"#time,accel_x,accel_y,accel_z\n0,1,2,3\n0.001,nan,2,3\n", "line 3: expected finite numbers"),
    (b"#time,accel_x,accel_y,accel_z\n0,1,2\n", "line 2: expected 4 numbers"),
    (b"\x00\x01\x02junk\xff" * 50, "expected a text (CSV) recording or a Parquet file, got binary data"),
    (b"a,b\n1,2\n", "not a Klipper or RepRapFirmware recording"),
    (b"Sample,X\n0,0.1\n1,0.2\n", "expected the last line of an M956 recording"),
]


@pytest.mark.parametrize("content,words", BAD)
def test_a_bad_recording_is_one_line_naming_the_file_and_line(tmp_path, content, words):
    path = tmp_path / "rec.csv"
    path.write_bytes(content)
    code, _, err = guarded(["identify", path])
    assert code == 2 and err.count("\n") == 1 and words in err and str(path) in err, err


def test_unknown_columns_a_rate_too_low_and_no_resonance(tmp_path):
    path = tmp_path / "t.csv"
    rng = np.random.default_rng(1)
    np.savetxt(path, np.column_stack([np.arange(4000) / 400, rng.normal(size=4000)]), delimiter=",",
               header="t,noise", comments="")
    code, _, err = guarded(["identify", path, "--time", "t", "--column", "accel", "--axis", "accel"])
    assert code == 2 and "no column 'accel'; the columns are t, noise" in err
    code, _, err = guarded(["identify", path, "--time", "t", "--column", "noise", "--axis", "noise", "--f-max", "300"])
    assert code == 2 and "f_max = 300 Hz is above the highest frequency of the spectrum, 200 Hz" in err
    code, out, err = guarded(["identify", path, "--time", "t", "--column", "noise", "--axis", "noise"])
    assert code == 0 and "no resonance above the threshold" in out
    code, _, err = guarded(["recommend", path, "--time", "t", "--column", "noise", "--axis", "noise"])
    assert code == 2 and "no resonance found in the recordings" in err


def test_a_recording_larger_than_the_bound_is_refused_before_it_is_read(tmp_path, monkeypatch):
    from shapefmu.identification import recordings

    path = tmp_path / "big.csv"
    path.write_bytes(b"#time,accel_x,accel_y,accel_z\n" + b"0,0,0,0\n" * 1000)
    monkeypatch.setattr(recordings, "MAX_RECORDING_BYTES", 1000)
    code, _, err = guarded(["identify", path])
    assert code == 2 and "more than the 1000 (shapefmu.identification.recordings.MAX_RECORDING_BYTES)" in err


def test_the_command_line_defaults_are_the_metrics_defaults():
    from shapefmu.cli import identify as command

    assert (command.DEFAULT_MAX_SMOOTHING, command.DEFAULT_ACCEL, command.DEFAULT_SCV) == (
        metrics.DEFAULT_MAX_SMOOTHING, metrics.DEFAULT_ACCEL, metrics.DEFAULT_SCV)
