"""Errors of the master algorithm, and the normal end an FMU may ask for."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Termination:
    """An FMU asked to end the simulation: ``component`` at ``time`` s, through ``call``
    (e.g. "fmi2DoStep returned fmi2Discard and fmi2Terminated is true"). A normal end of the run."""

    component: str
    time: float
    call: str

    def __str__(self) -> str:
        return f"component {self.component!r} ended the simulation at t = {self.time:.9g} s ({self.call})"


class CosimError(RuntimeError):
    """An FMU returned fmi2Error/fmi2Discard/fmi2Fatal (or a loop did not converge) during a run.

    The message names the component, the FMI call and the simulation time; ``partial`` holds the
    results recorded up to that point (a numpy structured array, or None before the first record).
    """

    def __init__(self, message: str, *, component: str | None = None, call: str | None = None,
                 time: float | None = None, partial=None):
        super().__init__(message)
        self.component = component
        self.call = call
        self.time = time
        self.partial = partial


class CosimInterrupted(KeyboardInterrupt):
    """Ctrl-C during :meth:`Master.run`; ``partial`` holds the results recorded so far."""

    def __init__(self, time: float, partial):
        super().__init__(f"co-simulation interrupted at t = {time:.9g} s")
        self.time = time
        self.partial = partial


class AlgebraicLoopError(ValueError):
    """The system has an algebraic loop the master cannot solve (an FMU in it cannot roll back)."""

    def __init__(self, message: str, variables: list[str]):
        super().__init__(message)
        self.variables = variables
