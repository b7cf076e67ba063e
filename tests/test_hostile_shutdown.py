"""SIGTERM during recommend --build --fmi-version 3.0 ends it cleanly, whatever it was doing (issue 34, item 5).

The issue saw one SIGABRT in 23 runs ("Python runtime state: finalizing", 22.6 s in); it was not
reproduced here (90 runs signalled at random times, and these), so this is a guard, not a fix. What
the guard did find: 1 run in 10 of the "building" case ended -2 (SIGINT) instead of 143, a CPython
3.11 quirk the last test pins (cli/signals.py's Interrupted). The
signal is sent at the run's own output, never after a fixed time (its progress lines show on a
terminal only, so its stdout): once the modes are printed (the scan), once the pick is (the
build), and once the FMU is written (the .ssv and the exit). Each run ends 143 (or 0 or -15 if it had
ended already) without a fatal error or a traceback, and leaves nothing half-written: the FMU is absent or
a whole archive, and no temporary file is left.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from support.run_watch import OutputWatch

SPECTRUM = Path(__file__).resolve().parent / "data" / "recordings" / "v24_resonances_x_20230306_224517.csv"


@pytest.mark.parametrize("words", ["mode(s), sweep excitation", "pick (fmu):", "wrote o.fmu"],
                         ids=["scanning", "building", "exiting"])
def test_sigterm_at_the_run_s_progress_ends_it_cleanly(tmp_path, words):
    process = subprocess.Popen([sys.executable, "-X", "faulthandler", "-m", "shapefmu", "recommend", str(SPECTRUM),
                                "--build", "o.fmu", "--fmi-version", "3.0"], cwd=tmp_path,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    watch = OutputWatch(process, "stdout")
    watch.wait_for(words)
    process.send_signal(signal.SIGTERM)
    stdout, stderr = watch.finish()
    # 143; 0 if it had ended; -15 if the signal came once the command had returned, as the interpreter
    # exited under SIGTERM's default action (a shell shows 143 for that too)
    assert process.returncode in (143, 0, -signal.SIGTERM), stderr[-3000:]
    assert "Fatal Python error" not in stderr and "Traceback" not in stderr, stderr[-3000:]
    if process.returncode == 143:
        assert stderr.strip().splitlines()[-1] == "shapefmu recommend: interrupted (SIGTERM)", stderr[-3000:]
    written = sorted(p.name for p in tmp_path.iterdir())
    assert written in ([], ["o.fmu"], ["o.fmu", "o.ssv"]), written  # no temporary left beside them
    if written:
        assert zipfile.ZipFile(tmp_path / "o.fmu").testzip() is None


def test_a_sigterm_inside_code_that_exec_runs_from_a_string_ends_143(tmp_path):
    """CPython 3.11 run with -m (as ``python -m shapefmu``) ends by SIGINT once a KeyboardInterrupt of exactly
    that type escaped code run by exec() from a string (dataclasses make their methods so at import), whatever
    exit code follows: the "building" case above ended -2 in about 1 run of 10 (SIGTERM during an import).
    Here the signal lands inside such code every time."""
    (tmp_path / "exec_interrupted.py").write_text(
        "import os, signal, sys\n"
        "from shapefmu.cli.signals import exit_code, interrupts\n"
        "with interrupts() as received:\n"
        "    try:\n"
        "        exec('os.kill(os.getpid(), signal.SIGTERM)\\nwhile not received: pass')\n"
        "    except KeyboardInterrupt:\n"
        "        sys.exit(exit_code(received))\n")
    done = subprocess.run([sys.executable, "-m", "exec_interrupted"], cwd=tmp_path, capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 128 + signal.SIGTERM, done.stderr
