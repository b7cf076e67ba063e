"""Progress of long work, on stderr: on by default on a terminal, off when stderr is piped or with
``--quiet`` (every command has it), so a log file or a pipe gets only the results.

The layers below take ``progress``, a function of one line of text (``None``: say nothing), and call
it as each step of their work begins (a candidate of ``compare``, an FMU of ``build``, a phase of
the time-optimal solver); a command passes them :func:`reporter`'s. ``showing(args)`` is the same
decision for the progress bars of the master and of a sweep.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable


def showing(args) -> bool:
    """Whether this command shows progress: stderr is a terminal and ``--quiet`` was not given."""
    return not getattr(args, "quiet", False) and sys.stderr.isatty()


def reporter(args, command: str) -> Callable[[str], None] | None:
    """A ``progress`` function printing ``shapefmu COMMAND: [  12.3 s] TEXT`` on stderr, or None when
    progress is not shown (see :func:`showing`)."""
    if not showing(args):
        return None
    start = time.monotonic()

    def say(text: str) -> None:
        print(f"shapefmu {command}: [{time.monotonic() - start:6.1f} s] {text}", file=sys.stderr, flush=True)

    return say
