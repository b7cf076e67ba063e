"""fmpy's logger proxy: one callback for the process, each FMI 2.0 instance's messages routed to its sink.

fmpy formats an FMU's C varargs message in a native proxy and then calls ONE process-wide Python
callback: the last one registered with ``fmpy.logging.addLoggerProxy`` (importing fmpy registers its
printer; so do ``instantiate_fmu(logger=...)`` and ``simulate_fmu(logger=...)``). A callback registered
per instance dies with it, and the next FMU in the process that logs through the proxy calls freed
memory; a host that takes the slot for its own list swallows every other instance's messages. So every
host here (the master, the test hosts) registers this module's one router, which lives as long as the
process and finds the instance's sink by componentEnvironment; a message of an instance nobody listens
to (fmpy's default callbacks) is printed as fmpy's printer prints it.

    callbacks = listening(sink, environment)   fmi2CallbackFunctions for fmi2Instantiate: each message of
                                               that instance goes to ``sink(status, category, message)``
                                               (str); keep both alive while the instance lives
    SINKS.pop(environment, None)               once the instance is freed

(FMI 3.0 passes its logger to each instance itself, with no proxy: ``units3`` needs none of this.)
"""

from __future__ import annotations

from ctypes import byref

from fmpy.fmi1 import printLogMessage
from fmpy.fmi2 import defaultCallbacks, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

SINKS: dict[int, object] = {}  # componentEnvironment -> sink(status, category, message)


def _route(environment, instance_name, status, category, message):
    sink = SINKS.get(environment or 0)
    if sink is None:
        printLogMessage(environment, instance_name, status, category, message)
    else:
        sink(status, (category or b"").decode(errors="replace"), (message or b"").decode(errors="replace"))


_ROUTER = fmi2CallbackLoggerTYPE(_route)


def listening(sink, environment: int | None = None) -> fmi2CallbackFunctions:
    """Callbacks whose instance's messages go to ``sink``, keyed by ``environment`` (default ``id(sink)``);
    the proxy is (re)pointed at the router, as another library in the process may have taken it since."""
    environment = id(sink) if environment is None else environment
    SINKS[environment] = sink
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = _ROUTER
    callbacks.allocateMemory = defaultCallbacks.allocateMemory
    callbacks.freeMemory = defaultCallbacks.freeMemory
    callbacks.componentEnvironment = environment
    try:  # formats the C varargs message before it reaches Python
        from fmpy.logging import addLoggerProxy

        addLoggerProxy(byref(callbacks))
    except Exception:  # noqa: BLE001 - without the proxy messages arrive unformatted, still useful
        pass
    return callbacks
