"""Result files are complete or clearly partial, one writer at a time, never a trap (issue 23).

``simulate --out`` and ``sweep --out`` against signals at the wrong moment, a second run on the same
file, files that are not theirs (a one-line text, a link, a FIFO, a foreign Parquet file), names the
file system cannot hold, and resumed files with a field of megabytes.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from hostile_support import guarded
from support.run_watch import OutputWatch

from shapefmu.cosim.output_files import output_lock
from shapefmu.fmi.ssp import System

ROWS = 2_000_001  # a save of seconds: a signal sent once the summary is printed lands during it


@pytest.fixture(scope="module")
def plant_ssp(plant_fmus, tmp_path_factory):
    """The disk drive alone with 1 V on its input: x_r = b2 t^2 / 2 (b2 = 2.7e3), the compiled loop."""
    return (System("plant_alone").add("plant", plant_fmus["disk_drive"], {"voltage": 1.0})
            .write_ssp(tmp_path_factory.mktemp("outputs") / "plant.ssp"))


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    return tmp_path


def start_simulate(ssp, out, stop="2", *extra):
    return subprocess.Popen([sys.executable, "-m", "shapefmu", "simulate", str(ssp), "--stop", stop, "--step", "1e-6",
                             "--record", "plant.position", "--out", str(out), *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def wait_for(process, words, seconds=600):
    """Read ``process``'s stdout until a line holds ``words``; the lines read."""
    lines, deadline = [], time.monotonic() + seconds
    while time.monotonic() < deadline:
        line = process.stdout.readline()
        if not line:
            break
        lines.append(line)
        if words in line:
            return lines
    raise AssertionError(f"{words!r} never came: {lines}")


@pytest.mark.parametrize("number", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_a_signal_while_the_results_are_written_leaves_them_whole(plant_ssp, tmp_path, number):
    out = tmp_path / "r.csv"
    process = start_simulate(plant_ssp, out)
    wait_for(process, f"{ROWS} records to t = 2 s")  # printed just before the file is written
    process.send_signal(number)
    stdout, stderr = process.communicate(timeout=120)
    assert process.returncode == 128 + number, stderr
    assert "Traceback" not in stderr and "written whole" in stderr and f"results written to {out}" in stdout
    saved = np.loadtxt(out, delimiter=",", skiprows=1)
    assert saved.shape == (ROWS, 2) and saved[-1, 0] == 2.0
    np.testing.assert_allclose(saved[:, 1], 2.7e3 * saved[:, 0] ** 2 / 2, rtol=1e-7, atol=1e-15)
    assert [p.name for p in tmp_path.iterdir()] == ["r.csv"]  # no temporary or lock file left


def test_a_run_stopped_early_marks_its_file_partial_in_the_file_and_on_stderr(plant_ssp, tmp_path):
    out = tmp_path / "r.parquet"
    process = start_simulate(plant_ssp, out, "1000", "--output-interval", "1e-3", "--progress")
    watch = OutputWatch(process)
    watch.wait_for("steps/s")  # its first progress update: a first chunk of 10^4 steps is done
    process.send_signal(signal.SIGTERM)
    stdout, stderr = watch.finish()
    assert process.returncode == 143 and "Traceback" not in stderr
    assert f"{out} holds partial results, to t = " in stderr and "(partial: the run stopped early)" in stdout
    import pyarrow.parquet as pq

    table = pq.read_table(out)
    assert b"co-simulation interrupted at t = " in table.schema.metadata[b"shapefmu.partial"]
    assert 2 <= table.num_rows < 1_000_001


def test_a_partial_csv_says_so_on_its_last_line(plant_ssp, workdir):
    from shapefmu.cosim import save_results, simulate

    results = simulate(plant_ssp, 1e-4, 1e-6, record=["plant.position"])
    path = save_results(results, workdir / "r.csv", partial="co-simulation interrupted at t = 1e-4 s (SIGINT)")
    lines = path.read_text().splitlines()
    assert lines[0] == "time,plant.position" and len(lines) == 1 + len(results) + 1
    assert lines[-1] == "# partial results: co-simulation interrupted at t = 1e-4 s (SIGINT)"


def test_a_second_run_on_the_same_output_is_refused_while_the_first_writes(plant_ssp, tmp_path):
    out = tmp_path / "r.csv"
    first = start_simulate(plant_ssp, out, "1000", "--output-interval", "1e-3", "--progress")
    watch = OutputWatch(first)
    watch.wait_for("steps/s")  # at work, so holding the file's lock
    second = subprocess.run([sys.executable, "-m", "shapefmu", "simulate", str(plant_ssp), "--stop", "1e-3",
                             "--step", "1e-6", "--out", str(out)], capture_output=True, text=True, timeout=120)
    assert second.returncode == 2 and len(second.stderr.splitlines()) == 1
    assert f"{out} is being written by another run (process {first.pid})" in second.stderr
    first.send_signal(signal.SIGINT)
    watch.finish()
    assert first.returncode == 130  # it was still running: the refusal did not wait for it


def test_the_lock_is_one_writer_at_a_time_and_released(tmp_path):
    out = tmp_path / "rows.csv"
    with output_lock(out):
        done = subprocess.run([sys.executable, "-c", "from shapefmu.cosim.output_files import output_lock\n"
                               f"with output_lock({str(out)!r}): pass"], capture_output=True, text=True)
        assert done.returncode == 1 and "is being written by another run" in done.stderr
    with output_lock(out):  # free again, and no lock file left behind
        pass
    assert list(tmp_path.iterdir()) == []


def test_a_fifo_as_output_is_refused_before_the_run(plant_ssp, workdir):
    os.mkfifo(workdir / "r.csv")
    code, out, err = guarded(["simulate", str(plant_ssp), "--stop", "1e-3", "--step", "1e-6", "--out", "r.csv"], seconds=20)
    assert code == 2 and "argument --out: file 'r.csv' is a FIFO, not a regular file" in err and out == ""


def test_a_name_too_long_for_the_file_system_is_one_line(plant_ssp, workdir):
    name = "a" * 300 + ".csv"
    code, out, err = guarded(["simulate", str(plant_ssp), "--stop", "1e-3", "--step", "1e-6", "--out", name])
    assert code == 2 and len(err.splitlines()) == 1 and "is 304 bytes, more than the 255 a file name may have" in err


SWEEP = ["--metric", "peak", "--command", "plant.position", "--step", "1e-3", "--stop-time", "0.01",
         "--vary", "plant.voltage=1,2", "--workers", "1"]


@pytest.mark.parametrize("text", ["results of my thesis", "a,b\n1,2\nkeep this line", ""],
                         ids=["one line", "other columns", "empty"])
def test_sweep_never_touches_a_file_that_is_not_its_own(plant_ssp, workdir, text):
    (workdir / "rows.csv").write_text(text)
    code, _, err = guarded(["sweep", str(plant_ssp), "--out", "rows.csv", *SWEEP], seconds=120)
    if text:
        assert code == 2 and "cannot resume from 'rows.csv'" in err and len(err.splitlines()) == 1
        assert (workdir / "rows.csv").read_text() == text
    else:  # an empty file is a sweep cut before its header: it starts anew
        assert code == 0 and (workdir / "rows.csv").read_text().startswith("run,plant.voltage,peak,")


def test_sweep_refuses_an_output_that_is_a_link(plant_ssp, workdir):
    (workdir / "mine.csv").write_text("precious\n")
    (workdir / "rows.csv").symlink_to(workdir / "mine.csv")
    code, _, err = guarded(["sweep", str(plant_ssp), "--out", "rows.csv", *SWEEP], seconds=60)
    assert code == 2 and "argument --out: file 'rows.csv' is a symbolic link" in err
    assert (workdir / "mine.csv").read_text() == "precious\n"


def test_no_resume_keeps_the_old_rows_when_an_error_is_found_later(plant_ssp, workdir):
    first = guarded(["sweep", str(plant_ssp), "--out", "rows.csv", *SWEEP], seconds=120)
    assert first[0] == 0
    before = (workdir / "rows.csv").read_text()
    arguments = [a for a in SWEEP if a not in ("--workers", "1")]
    code, _, err = guarded(["sweep", str(plant_ssp), "--out", "rows.csv", "--no-resume", "--scheduler",
                            "tcp://127.0.0.1:9", *arguments], seconds=120)
    assert code == 2 and "scheduler 'tcp://127.0.0.1:9': no Dask scheduler answered" in err
    assert (workdir / "rows.csv").read_text() == before


def test_a_foreign_parquet_file_is_refused_before_any_run(plant_ssp, workdir):
    from shapefmu.cosim import save_results, simulate

    save_results(simulate(plant_ssp, 1e-3, 1e-6, record=["plant.position"]), workdir / "rows.parquet")
    before = (workdir / "rows.parquet").read_bytes()
    code, out, err = guarded(["sweep", str(plant_ssp), "--out", "rows.parquet", *SWEEP], seconds=60)
    assert code == 2 and "cannot resume from 'rows.parquet': its columns ['time', 'plant.position']" in err
    assert "rows written" not in out and (workdir / "rows.parquet").read_bytes() == before


def test_a_resumed_row_with_a_field_of_megabytes_is_one_line(plant_ssp, workdir):
    first = guarded(["sweep", str(plant_ssp), "--out", "rows.csv", *SWEEP], seconds=120)
    assert first[0] == 0
    lines = (workdir / "rows.csv").read_text().splitlines()
    (workdir / "rows.csv").write_text("\n".join([lines[0], lines[1].replace(",ok,", ",ok," + "x" * 5_000_000, 1)]) + "\n")
    code, _, err = guarded(["sweep", str(plant_ssp), "--out", "rows.csv", *SWEEP], seconds=60)
    assert code == 2 and len(err.splitlines()) == 1 and "rows.csv, line 2: not a sweep row" in err


def test_a_server_that_is_no_dask_scheduler_is_one_line(plant_ssp, workdir):
    import socket
    import threading

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()

    def answer_as_a_web_server():
        while True:
            try:
                connection, _ = server.accept()
            except OSError:  # closed at the end of the test
                return
            connection.sendall(b"HTTP/1.0 400 Bad Request\r\n\r\nnot a scheduler")
            connection.close()

    threading.Thread(target=answer_as_a_web_server, daemon=True).start()
    address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
    arguments = [a for a in SWEEP if a not in ("--workers", "1")]
    try:
        code, _, err = guarded(["sweep", str(plant_ssp), "--out", "rows.csv", "--scheduler", address, *arguments],
                               seconds=120)
    finally:
        server.close()
    assert code == 2 and err.count("\n") == 1 and f"scheduler {address!r}: no Dask scheduler answered" in err
    assert not (workdir / "rows.csv").exists()
