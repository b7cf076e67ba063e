"""Running the C compiler so that an interruption leaves nothing behind.

``gcc`` is a driver: it runs ``cc1``, ``as`` and ``collect2`` in turn, which write temporary files
(``/tmp/cc*.o``) the driver removes when it ends. A Ctrl-C or SIGTERM to shapefmu kills the driver
(``subprocess.run`` does), not the programs it started, and their temporary files stay. So the
compiler runs in a process group of its own, killed whole on an interruption, and with its own
``TMPDIR``, a folder removed afterwards whatever happened.
"""

from __future__ import annotations

import os
import signal
import subprocess
import tempfile


def run_compiler(command: list[str], text: bool = True) -> subprocess.CompletedProcess:
    """Run ``command`` (a compiler invocation) to its end and return its CompletedProcess (output
    captured); on any exception, the compiler and everything it started are killed first."""
    with tempfile.TemporaryDirectory(prefix="shapefmu-cc-") as scratch:
        process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=text,
                                   start_new_session=True, env={**os.environ, "TMPDIR": scratch})
        try:
            stdout, stderr = process.communicate()
        except BaseException:
            try:
                os.killpg(process.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            process.wait()
            raise
        return subprocess.CompletedProcess(command, process.returncode, stdout, stderr)
