"""Nonlinear plants given as a CasADi symbolic ODE x' = f(x, u, p), y = g(x, u, p).

A ``NonlinearPlant`` names its states, inputs, parameters and outputs, each with the CasADi symbol
(or, for outputs, the expression) it stands for; the generator takes f, g and their Jacobians to C
with CasADi's code generation. The Co-Simulation step is a classic RK4 with the input held over
the step, in equal substeps no longer than the ``substep`` parameter (tunable, default
``NonlinearPlant.substep``).

Example (``models/pendulum.py`` holds the full model)::

    theta, omega, a, L, g = (ca.SX.sym(n) for n in ("theta", "omega", "a", "L", "g"))
    NonlinearPlant(
        name="pendulum",
        states=(Variable("theta", theta, unit="rad"), Variable("omega", omega, unit="rad/s")),
        derivatives=(omega, -(g * ca.sin(theta) + a * ca.cos(theta)) / L),
        inputs=(Variable("acceleration", a, unit="m/s^2"),),
        parameters=(Variable("L", L, 1.0, "m", "positive"), Variable("g", g, 9.80665, "m/s^2", "positive")),
        outputs=(Output("theta", theta, "rad"),),
    )
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca

from shapefmu.fmi.native.model_part import ModelPart, ScalarParameter, Signal


@dataclass(frozen=True)
class Variable:
    """A state, input or parameter: name, scalar CasADi symbol, value (start or default), unit, and
    for parameters the constraint the FMU checks (``model_part.CONSTRAINTS``)."""

    name: str
    symbol: ca.SX
    value: float = 0.0
    unit: str = ""
    constraint: str = "any"
    description: str = ""


@dataclass(frozen=True)
class Output:
    """An output: its name, its CasADi expression in the states, inputs and parameters, its unit."""

    name: str
    expression: ca.SX
    unit: str = ""
    description: str = ""


@dataclass(frozen=True)
class NonlinearPlant:
    """x' = f(x, u, p) (``derivatives``, one expression per state), y = g(x, u, p) (``outputs``)."""

    name: str
    states: Sequence[Variable]
    derivatives: Sequence[ca.SX]
    inputs: Sequence[Variable]
    parameters: Sequence[Variable]
    outputs: Sequence[Output]
    substep: float = 1e-3
    description: str = ""

    def __post_init__(self):
        if len(self.derivatives) != len(self.states):
            raise ValueError(f"{self.name}: derivatives must hold one expression per state "
                             f"({len(self.states)}), got {len(self.derivatives)}")
        if not (self.substep > 0):
            raise ValueError(f"{self.name}: substep must be > 0 s, got {self.substep!r}")
        for group in (self.states, self.inputs, self.parameters):
            for variable in group:
                if not (isinstance(variable.symbol, ca.SX) and variable.symbol.is_symbolic() and variable.symbol.numel() == 1):
                    raise ValueError(f"{self.name}: {variable.name} must be a scalar CasADi SX symbol")
        known = ca.vertcat(*[v.symbol for v in (*self.states, *self.inputs, *self.parameters)])
        expressions = ca.vertcat(*self.derivatives, *[o.expression for o in self.outputs])
        free = [str(s) for s in ca.symvar(expressions) if not ca.depends_on(known, s)]
        if free:
            raise ValueError(f"{self.name}: the expressions use symbols that are neither states, inputs nor "
                             f"parameters: {free}")

    def model_part(self) -> ModelPart:
        parameters = [ScalarParameter(p.name, p.symbol, float(p.value), p.unit, True, p.constraint,
                                      p.description or f"parameter {p.name}") for p in self.parameters]
        parameters.append(ScalarParameter("substep", ca.SX.sym("substep"), float(self.substep), "s", True, "positive",
                                          "longest RK4 substep of a Co-Simulation step"))
        return ModelPart(
            name=self.name,
            description=self.description,
            states=tuple(Signal(v.name, v.unit, float(v.value), description=v.description or f"state {v.name}")
                         for v in self.states),
            inputs=tuple(Signal(v.name, v.unit, float(v.value), description=v.description or f"input {v.name}")
                         for v in self.inputs),
            outputs=tuple(Signal(o.name, o.unit, description=o.description or f"output {o.name}") for o in self.outputs),
            parameters=tuple(parameters),
            x=ca.vertcat(*[v.symbol for v in self.states]),
            u=ca.vertcat(*[v.symbol for v in self.inputs]),
            f=ca.vertcat(*self.derivatives),
            g=ca.vertcat(*[o.expression for o in self.outputs]),
            linear=False,
            substep_parameter="substep",
        )
