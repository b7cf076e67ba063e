"""Hostile recordings and reading options (issue 34: items 3, 4 and 7 for recordings, 8's
``--column`` given 2000 times, 9's one-row spectrum file, the Low items about recordings): a
spectrum without a resonance says so, and every bad input is one line naming the file or option,
the line, the value and the valid range, exit 2, never a NaN with exit 0."""

import json

import numpy as np
import pytest
from hostile_support import guarded

from shapefmu.identification import recordings

RAW_HEADER = "#time,accel_x,accel_y,accel_z\n"


def one_line_error(argv, *words):
    code, out, err = guarded(argv)
    assert code == 2 and err.count("\n") == 1 and not out, (code, out, err)
    for word in words:
        assert word in err, err
    return err


@pytest.fixture
def noise(tmp_path):
    """30 s of Gaussian noise at 3.2 kHz in one column ``a``."""
    path = tmp_path / "noise.csv"
    rng = np.random.default_rng(34)
    path.write_text("a\n" + "".join(f"{v:.6f}\n" for v in rng.normal(size=96000)))
    return path


@pytest.fixture
def raw(tmp_path):
    """A short Klipper raw recording of sensor noise (nothing excited)."""
    rng = np.random.default_rng(3)
    t = 1234.5 + np.arange(20000) / 3200
    path = tmp_path / "raw_data_x.csv"
    rows = np.column_stack([t, rng.normal(0, 40, (20000, 2)), 9806.65 + rng.normal(0, 40, 20000)])
    path.write_text(RAW_HEADER + "".join("%.6f,%.3f,%.3f,%.3f\n" % tuple(r) for r in rows))
    return path


def test_white_noise_reports_no_mode_and_says_so(noise):
    code, out, err = guarded(["identify", noise, "--column", "a", "--fs", "3200"])
    assert code == 0 and "no resonance" in out and "mode(s)" not in out, out
    code, out, _ = guarded(["identify", noise, "--column", "a", "--fs", "3200", "--json"])
    (found,) = json.loads(out)
    assert found["modes"] == [] and "no resonance" in found["notes"][0]


def test_noise_in_a_klipper_raw_file_reports_no_mode(raw):
    code, out, _ = guarded(["identify", raw])
    assert code == 0 and "no resonance" in out and "mode(s)" not in out, out


def test_one_sample_of_1e308_is_named_with_its_line(tmp_path, noise):
    lines = noise.read_text().splitlines()
    lines[50001] = "1e308"
    path = tmp_path / "big.csv"
    path.write_text("\n".join(lines) + "\n")
    one_line_error(["identify", path, "--column", "a", "--fs", "3200"], "line 50002", "1e308", "at most 1e+100")


@pytest.mark.parametrize("axis,shown", [("1e-320,0,0", "1e-320"), ("1e308,1e308,1e308", "1e+308")])
def test_a_direction_that_under_or_overflows_is_refused(raw, axis, shown):
    one_line_error(["identify", raw, "--axis", axis], "direction", "[1e-09, 1e+09]", shown)


def test_a_parquet_file_is_bounded_by_its_rows_not_its_bytes(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq

    path = tmp_path / "zeros.parquet"
    pq.write_table(pa.table({"a": np.zeros(20_000_000, dtype=np.int8)}), path, compression="zstd")
    assert path.stat().st_size < 1_000_000
    one_line_error(["identify", path, "--column", "a", "--fs", "3200"], "20000000 rows",
                   f"{recordings.MAX_RECORDING_VALUES} numbers")


def test_a_column_asked_for_2000_times_is_refused_before_any_work(noise):
    one_line_error(["identify", noise, "--fs", "3200", *["--column", "a"] * 2000], "--column", "at most 16", "2000")
    one_line_error(["identify", noise, "--fs", "3200", "--column", "a", "--column", "a"], "'a' is given 2 times")


def test_a_klipper_spectrum_file_with_one_row(tmp_path):
    path = tmp_path / "resonances_x.csv"
    path.write_text("freq,psd_x,psd_y,psd_z,psd_xyz\n10.0,1e2,1e1,1e1,1.2e2\n")
    one_line_error(["identify", path], "at least 8 rows", "got 1")


M956_ROWS = "Sample,X\n" + "".join(f"{i},{0.001 * (i % 13)}\n" for i in range(64))


@pytest.mark.parametrize("last,words", [
    ("Rate ., overflows 0", ("line 66", "'Rate'", "'.'", "(0, 1e+06]")),
    ("Rate 1000, overflows " + "9" * 5000, ("line 66", "overflow count", "[0, 1000000000000]", "5000 characters")),
])
def test_a_bad_m956_last_line_is_named(tmp_path, last, words):
    path = tmp_path / "m956.csv"
    path.write_text(M956_ROWS + last + "\n")
    err = one_line_error(["identify", path], *words)
    assert len(err) < 400


def test_a_number_with_an_underscore_is_named_with_its_line(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text("t,a\n" + "".join(f"{i / 1000},{i % 5}\n" for i in range(40)) + "0.04,1_234\n")
    one_line_error(["identify", path, "--time", "t", "--column", "a"], "line 42", "1_234")


def test_a_denormal_time_step_is_named(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text("t,a\n" + "".join(f"{i * 5e-324!r},{i % 5}\n" for i in range(40)))
    one_line_error(["identify", path, "--time", "t", "--column", "a"], "4.94066e-324 s", "at least 1e-06 s")


def test_a_utf8_byte_order_mark_is_skipped_in_klipper_and_m956_files(tmp_path, raw):
    bom = b"\xef\xbb\xbf"
    marked = tmp_path / "marked_raw.csv"
    marked.write_bytes(bom + raw.read_bytes())
    code, out, err = guarded(["identify", marked])
    assert code == 0 and "klipper-raw" in out, err
    m956 = tmp_path / "marked_m956.csv"
    rows = "Sample,X\n" + "".join(f"{i},{0.01 * np.sin(i)}\n" for i in range(4000))
    m956.write_bytes(bom + (rows + "Rate 1000, overflows 0\n").encode())
    code, out, err = guarded(["identify", m956])
    assert code == 0 and "rrf-m956" in out, err


def test_fs_above_any_accelerometer_is_refused(noise):
    one_line_error(["identify", noise, "--column", "a", "--fs", "1e300"], "--fs", "(0, 1e+06]", "1e+300")
