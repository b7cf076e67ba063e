"""Input files and signals no command turns into a traceback or a hang (issue 23).

Devices and FIFOs given as files, nesting deeper than the parsers follow, Python plant models that
raise or exit, and Ctrl-C or SIGTERM while a command works outside a run loop.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest
from hostile_support import guarded


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize("argv, words", [
    (["plant", "show", "/dev/zero"], "/dev/zero: plant model must be a regular file, not a FIFO, device or folder"),
    (["build", "reference", "/dev/zero", "-o", "R.fmu"], "signal table must be a regular file"),
    (["plant", "show", "fifo.toml"], "fifo.toml: plant model must be a regular file"),
])
def test_a_device_or_fifo_given_as_a_file_is_refused_at_once(workdir, argv, words):
    os.mkfifo(workdir / "fifo.toml")  # no writer: reading it would block forever
    code, _, err = guarded(argv, seconds=20)
    assert code == 2 and words in err and len(err.splitlines()) == 1


def test_a_file_larger_than_the_bound_is_refused_before_it_is_read(workdir, monkeypatch):
    from shapefmu.runtime import limits

    monkeypatch.setattr(limits, "MAX_INPUT_FILE_BYTES", 1000)
    (workdir / "big.toml").write_text("# " + "x" * 2000 + "\n")
    code, _, err = guarded(["plant", "show", "big.toml"])
    assert code == 2 and "big.toml: plant model of 2,003 bytes, more than the limit of 1,000" in err


@pytest.mark.parametrize("name, text, argv", [
    ("deep.toml", 'name = "x"\nkind = "rigid_flexible"\nx = ' + "[" * 100_000 + "]" * 100_000 + "\n", ["plant", "show", "deep.toml"]),
    ("deep.json", "[" * 100_000 + "]" * 100_000, ["build", "reference", "deep.json", "-o", "R.fmu"]),
])
def test_nesting_deeper_than_the_parsers_follow_is_one_line(workdir, name, text, argv):
    (workdir / name).write_text(text)
    code, _, err = guarded(argv)
    assert code == 2 and f"{name} is nested deeper than can be read" in err and len(err.splitlines()) == 1


@pytest.mark.parametrize("body, words", [
    ("raise RuntimeError('my model is broken')\n", "the model file raised RuntimeError: my model is broken"),
    ("import sys\nsys.exit(3)\n", "the model file called sys.exit(3) while shapefmu read it"),
    ("def plant():\n    return 1 / 0\n", "the model file raised ZeroDivisionError: division by zero"),
])
def test_a_python_plant_model_that_raises_or_exits_is_named(workdir, body, words):
    (workdir / "model.py").write_text(body)
    code, _, err = guarded(["plant", "build", "model.py", "-o", "M.fmu"])
    assert code == 2 and f"model.py: {words}" in err and len(err.splitlines()) == 1


@pytest.mark.parametrize("number", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_a_signal_outside_a_run_loop_ends_cleanly_and_removes_temporary_folders(tmp_path, number):
    # `shapefmu build` spends seconds compiling FMUs in temporary folders
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    process = subprocess.Popen([sys.executable, "-m", "shapefmu", "build", "-o", str(tmp_path / "fmus")],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env={**os.environ, "TMPDIR": str(scratch)}, cwd=tmp_path)
    deadline = time.monotonic() + 600  # a hang, not a slow machine
    while not any(scratch.iterdir()) and time.monotonic() < deadline:  # at work: a temporary folder exists
        time.sleep(0.05)
    assert any(scratch.iterdir())
    process.send_signal(number)
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 128 + number, stderr
    assert stderr.strip().splitlines()[-1] == f"shapefmu build: interrupted ({signal.Signals(number).name})"
    assert "Traceback" not in stderr
    left = [p.name for p in scratch.iterdir() if not p.name.startswith("shapefmu-objects-")]  # the cache may stay
    assert left == []
