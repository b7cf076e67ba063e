"""fmpy's logger proxy in a test process: one callback for the process, each message routed to its listener.

fmpy formats an FMU's C varargs message in a native proxy and then calls ONE process-wide Python
callback: the last one registered with ``fmpy.logging.addLoggerProxy`` (importing fmpy registers its
printer; ``instantiate_fmu(logger=...)``, ``simulate_fmu(logger=...)`` and shapefmu's master register
theirs). Under pytest-xdist a worker runs many test modules in one process, so the slot holds whatever
the last module put there: a module that takes it for a list of its own swallows the messages later
tests read from fmpy's printed output (they then fail or pass by the order of the modules), and a
callback that dies with its test leaves the slot calling freed memory.

    callbacks = listening(sink)     fmi2CallbackFunctions for ``instantiate(callbacks=...)`` or a ctypes
                                    fmi2Instantiate: each message of that instance is passed to
                                    ``sink(status, category, message)`` (str); keep it alive with the instance

The callback registered lives as long as the process; a message of an instance nobody listens to
(fmpy's default callbacks) is printed as fmpy's printer prints it, so ``capfd`` still sees it.
"""

from __future__ import annotations

import ctypes

from fmpy.fmi1 import printLogMessage
from fmpy.fmi2 import defaultCallbacks, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
from fmpy.logging import addLoggerProxy

_SINKS: dict[int, object] = {}  # componentEnvironment -> sink; never dropped, so an id is never reused


def _route(environment, instance_name, status, category, message):
    sink = _SINKS.get(environment or 0)
    if sink is None:
        printLogMessage(environment, instance_name, status, category, message)
    else:
        sink(status, (category or b"").decode(errors="replace"), (message or b"").decode(errors="replace"))


_ROUTER = fmi2CallbackLoggerTYPE(_route)


def listening(sink) -> fmi2CallbackFunctions:
    """Callbacks whose instance's messages go to ``sink(status, category, message)``; the proxy is (re)pointed
    at the process's one router, as another host in this process may have taken it since."""
    _SINKS[id(sink)] = sink
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = _ROUTER
    callbacks.allocateMemory = defaultCallbacks.allocateMemory
    callbacks.freeMemory = defaultCallbacks.freeMemory
    callbacks.componentEnvironment = id(sink)
    addLoggerProxy(ctypes.byref(callbacks))
    return callbacks
