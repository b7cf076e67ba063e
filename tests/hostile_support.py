"""Running the command line on hostile input, in this process, within a time limit (tests/test_hostile_*.py)."""

import contextlib
import io
import signal

from shapefmu.cli import main


class Hung(Exception):
    """A command or test that did not finish within its time limit."""


@contextlib.contextmanager
def time_limit(seconds, what="the test"):
    """Raise Hung in this (the main) thread after ``seconds``: a hang fails instead of stalling the suite."""
    def hung(*_):
        raise Hung(f"{what} did not finish within {seconds} s")

    previous = signal.signal(signal.SIGALRM, hung)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def guarded(argv, seconds=60):
    """(exit code, stdout, stderr) of ``shapefmu argv`` run by ``shapefmu.cli.main`` in this process."""
    out, err = io.StringIO(), io.StringIO()
    with time_limit(seconds, f"shapefmu {' '.join(map(str, argv))}"):
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                code = main([str(a) for a in argv])
        except SystemExit as stop:
            code = stop.code
    assert "Traceback" not in err.getvalue(), err.getvalue()
    return code, out.getvalue(), err.getvalue()
