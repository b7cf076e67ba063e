"""Ctrl-C and SIGTERM in every command: a clean exit with the shell's codes, never a traceback.

``main`` runs each command inside :func:`interrupts`: SIGTERM (``kill``, ``timeout``, a batch system
ending a job) then raises :class:`Interrupted`, a KeyboardInterrupt, as Ctrl-C does, so ``finally``
blocks and exit handlers run (temporary folders are removed) and the command ends with 130 (SIGINT)
or 143 (SIGTERM).
``deferred`` holds both signals off while a result file is written, so it is written whole.
"""

from __future__ import annotations

import contextlib
import signal

SIGNALS = (signal.SIGINT, signal.SIGTERM)


class Interrupted(KeyboardInterrupt):
    """What the handler raises: a subclass, never KeyboardInterrupt itself. CPython 3.11 marks a
    KeyboardInterrupt of exactly that type escaping code that ``exec`` runs from a string (dataclasses
    and namedtuple make their methods so, at import) as unhandled, and then ends the process by SIGINT
    whatever ``main`` returned: a SIGTERM during an import ended -2, not 143."""


@contextlib.contextmanager
def interrupts():
    """Ctrl-C and SIGTERM raise :class:`Interrupted`; yields the list of signals received."""
    received = []

    def interrupt(signum, frame):
        received.append(signum)
        raise Interrupted

    with _handlers(interrupt):
        yield received


@contextlib.contextmanager
def deferred():
    """Ctrl-C and SIGTERM are noted, not acted on, until the block ends; yields the signals received."""
    received = []
    with _handlers(lambda signum, frame: received.append(signum)):
        yield received


@contextlib.contextmanager
def _handlers(handler):
    try:
        previous = {number: signal.signal(number, handler) for number in SIGNALS}
    except ValueError:  # not the main thread (main called from a worker): leave the handlers alone
        yield
        return
    try:
        yield
    finally:
        for number, old in previous.items():
            signal.signal(number, old)


def exit_code(received) -> int:
    """128 + the last signal received, as a shell reports it (130 for Ctrl-C when none was recorded)."""
    return 128 + (received[-1] if received else signal.SIGINT)
