"""The model part of a plant FMU, before it becomes C: named symbols and CasADi expressions.

A ``ModelPart`` holds x' = f(x, u, p), y = g(x, u, p) as CasADi SX expressions of the state x, the
input u and the scalar parameters p, with the names, units, start values and constraints the FMU
declares. Linear plants (``shapefmu.fmi.native.linear``) and nonlinear ones
(``shapefmu.fmi.native.nonlinear``) both end here, so that one code generator and one C wrapper
serve both.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import casadi as ca
import numpy as np

from shapefmu.fmi.kinds.interface import Interface, Variable
from shapefmu.runtime.checks import check_text

# What the C wrapper checks when a parameter is set (plant_model.h, PlantConstraint).
CONSTRAINTS = ("any", "positive", "nonnegative", "nonzero", "damping_ratio")
# The inclusive lower bound (FMI min) a constraint gives; a strict one (> 0) has none.
_LOWER_BOUNDS = {"nonnegative": 0.0, "damping_ratio": 0.0}
# The damping ratio the icon's magnitude responses are drawn with at least (ModelPart.picture).
PICTURE_DAMPING = 1e-3

# A structured FMI 2.0 name without quoted parts (fmi2 standard, section 2.2.9): identifiers
# separated by dots, each with optional array indices.
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(\[[0-9]+(,[0-9]+)*\])?(\.[A-Za-z_][A-Za-z0-9_]*(\[[0-9]+(,[0-9]+)*\])?)*")


def check_name(name: str, what: str) -> str:
    """``name`` if it is a structured FMI 2.0 variable name (letters, digits, _, dots, [i,j])."""
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        raise ValueError(f"{what} must be a structured FMI name such as x_1, f[2] or mass.v, got {name!r}")
    return name


@dataclass(frozen=True)
class ScalarParameter:
    """One scalar parameter of the FMU: ``symbol`` is the CasADi symbol f and g are written in."""

    name: str
    symbol: ca.SX
    value: float
    unit: str = ""
    tunable: bool = True
    constraint: str = "any"
    description: str = ""

    def __post_init__(self):
        check_name(self.name, "parameter name")
        check_text(self.unit, f"unit of parameter {self.name}")
        check_text(self.description, f"description of parameter {self.name}")
        if self.constraint not in CONSTRAINTS:
            raise ValueError(f"constraint of {self.name} must be one of {CONSTRAINTS}, got {self.constraint!r}")


@dataclass(frozen=True)
class Signal:
    """A state, input or output: its name, unit, start value (states, inputs), nominal (states),
    description and limits (inputs)."""

    name: str
    unit: str = ""
    start: float = 0.0
    nominal: float = 1.0
    description: str = ""
    minimum: float | None = None   # an input's limits
    maximum: float | None = None


@dataclass(frozen=True)
class ModelPart:
    """Everything the generator needs for one plant FMU.

    ``x`` and ``u`` are SX column vectors, ``f`` (like x) and ``g`` (ny x 1) SX expressions of
    ``x``, ``u`` and the parameters' symbols. ``linear`` selects the exact zero-order-hold
    Co-Simulation step; otherwise the step is a fixed-substep RK4 whose substep is the parameter
    named by ``substep_parameter``.
    """

    name: str
    description: str
    states: tuple[Signal, ...]
    inputs: tuple[Signal, ...]
    outputs: tuple[Signal, ...]
    parameters: tuple[ScalarParameter, ...]
    x: ca.SX
    u: ca.SX
    f: ca.SX
    g: ca.SX
    linear: bool
    substep_parameter: str | None = None
    source: str = ""   # where the model comes from (a model file's ``source``: "paper 002, eq. (1), Table I")

    def __post_init__(self):
        # The name and every description and unit reach modelDescription.xml (escaped there, but
        # XML cannot carry control characters at all); the C sees only check_name'd names and the
        # model identifier made of the name (``identifier``), never these strings.
        check_text(self.name, "plant name")
        check_text(self.description, f"description of plant {self.name!r}")
        check_text(self.source, f"source of plant {self.name!r}")
        for what, signals in (("state", self.states), ("input", self.inputs), ("output", self.outputs)):
            for signal in signals:
                check_name(signal.name, f"{what} name")
                check_text(signal.unit, f"unit of {what} {signal.name}")
                check_text(signal.description, f"description of {what} {signal.name}")
        names = [f"state.{s.name}" for s in self.states] + [s.name for s in self.inputs + self.outputs]
        names += [p.name for p in self.parameters]
        duplicates = sorted({n for n in names if names.count(n) > 1})
        if duplicates:
            raise ValueError(f"plant {self.name!r}: variable names must be unique, repeated: {duplicates}")
        if not self.inputs:
            raise ValueError(f"plant {self.name!r} must have at least one input")
        shapes = {"x": (self.x.shape, (len(self.states), 1)), "u": (self.u.shape, (len(self.inputs), 1)),
                  "f": (self.f.shape, (len(self.states), 1)), "g": (self.g.shape, (len(self.outputs), 1))}
        for key, (shape, expected) in shapes.items():
            if tuple(shape) != expected:
                raise ValueError(f"plant {self.name!r}: {key} must have shape {expected}, got {tuple(shape)}")
        if not self.linear and self.substep_parameter not in [p.name for p in self.parameters]:
            raise ValueError(f"plant {self.name!r}: a nonlinear plant needs its RK4 substep among the parameters, "
                             f"got substep_parameter={self.substep_parameter!r}")

    @property
    def identifier(self) -> str:
        """The C identifier the shared library is named by: the name with non-word characters replaced."""
        identifier = "".join(c if c.isalnum() or c == "_" else "_" for c in self.name)
        return identifier if identifier[:1].isalpha() else f"plant_{identifier}"

    def interface(self) -> Interface:
        """The plant FMU's interface, its variables in the order of the values of ``c/plant_model.h``:
        time, the states ``state.<name>``, their derivatives, the inputs, the outputs, the parameters.
        One input is the command the plant takes (FMI 3.0 terminals); several are no one command."""
        variables = [Variable("time", "Real", "independent", "continuous")]
        variables += [Variable(f"state.{s.name}", "Real", "local", "continuous", s.start, s.unit, s.description,
                               initial="exact", nominal=s.nominal) for s in self.states]
        variables += [Variable(f"der(state.{s.name})", "Real", "local", "continuous", None, per_second(s.unit),
                               f"time derivative of state.{s.name}", initial="calculated",
                               derivative_of=f"state.{s.name}") for s in self.states]
        variables += [Variable(s.name, "Real", "input", "continuous", s.start, s.unit, s.description, s.minimum,
                               s.maximum) for s in self.inputs]
        variables += [Variable(s.name, "Real", "output", "continuous", None, s.unit, s.description, initial="calculated")
                      for s in self.outputs]
        variables += [Variable(q.name, "Real", "parameter", "tunable" if q.tunable else "fixed", q.value, q.unit,
                               q.description, _LOWER_BOUNDS.get(q.constraint), initial="exact") for q in self.parameters]
        command = self.inputs[0].name if len(self.inputs) == 1 else None
        return Interface(self.name, self.description, tuple(variables), command_in=command)

    def linearisation(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(A, B, C, D) of the plant at rest (x = 0, u = 0, the parameters' values)."""
        point = (np.zeros(self.x.shape[0]), np.zeros(self.u.shape[0]), [q.value for q in self.parameters])
        _, jacobians = self.functions()
        return tuple(np.array(M, dtype=float) for M in jacobians(*point))

    def _frequencies(self) -> list[float]:
        """The natural frequencies (rad/s) of the oscillatory modes of the linearisation, ascending."""
        A = self.linearisation()[0]
        eigenvalues = np.linalg.eigvals(A) if A.size else np.zeros(0)
        scale = max(np.abs(eigenvalues).max(initial=0.0), 1.0)
        return sorted(abs(v) for v in eigenvalues if v.imag > 1e-9 * scale)

    def experiment(self) -> tuple[float, float, float]:
        """The DefaultExperiment (start, stop, step), s: ten periods of the slowest oscillatory mode of
        the linearisation at rest, in steps of a twentieth of the fastest one's period rounded down to
        a power of ten; (0, 1, 1e-3) without one."""
        omegas = self._frequencies()
        if not omegas:
            return 0.0, 1.0, 1e-3
        step = 10.0 ** math.floor(math.log10(2.0 * math.pi / omegas[-1] / 20.0))
        stop = float(f"{step * math.ceil(10.0 * 2.0 * math.pi / omegas[0] / step):.12g}")
        return 0.0, stop, step

    def picture(self):
        """The icon's picture (``shapefmu.fmi.icon``): the plant's modes, as the resonance peaks of the
        sum of its outputs' magnitude responses (each scaled to its peak), log-log, around the modes.
        The responses are taken at s = (PICTURE_DAMPING + j) w, just right of the imaginary axis, so an
        undamped mode's pole on the grid draws a tall peak instead of a singular matrix."""
        A, B, C, D = self.linearisation()
        omegas = self._frequencies() or [1.0]
        grid = np.logspace(math.log10(omegas[0] / 4.0), math.log10(omegas[-1] * 4.0), 97)
        n = A.shape[0]
        G = np.array([np.abs(C @ np.linalg.solve((PICTURE_DAMPING + 1j) * w * np.eye(n) - A, B[:, :1]) + D[:, :1])[:, 0]
                      for w in grid])
        logs = np.log10(np.maximum((G / np.maximum(G.max(axis=0), 1e-300)).sum(axis=1), 1e-12))
        return [("line", [(math.log10(w), g - logs.min()) for w, g in zip(grid, logs)])]

    def dependencies_by_name(self) -> dict[str, list[str]]:
        """Each output's and derivative's dependencies on the states and inputs, by variable name."""
        known = [f"state.{s.name}" for s in self.states] + [s.name for s in self.inputs]
        derivative_dependencies, output_dependencies = self.dependencies()
        result = {f"der(state.{s.name})": [known[d] for d in deps] for s, deps in zip(self.states, derivative_dependencies)}
        result.update({s.name: [known[d] for d in deps] for s, deps in zip(self.outputs, output_dependencies)})
        return result

    @property
    def p(self) -> ca.SX:
        return ca.vertcat(*[parameter.symbol for parameter in self.parameters])

    def functions(self) -> tuple[ca.Function, ca.Function]:
        """The CasADi functions the C model part is generated from: (f, g) and their Jacobians,
        A = df/dx, B = df/du, C = dg/dx, D = dg/du (dense, column-major when generated)."""
        arguments = [self.x, self.u, self.p]
        derivatives_outputs = ca.Function("plant_casadi_derivatives_outputs", arguments, [self.f, self.g],
                                          ["x", "u", "p"], ["dx", "y"])
        jacobians = ca.Function(
            "plant_casadi_jacobians", arguments,
            [ca.densify(ca.jacobian(e, v)) for e, v in ((self.f, self.x), (self.f, self.u), (self.g, self.x), (self.g, self.u))],
            ["x", "u", "p"], ["A", "B", "C", "D"])
        return derivatives_outputs, jacobians

    def dependencies(self) -> tuple[list[list[int]], list[list[int]]]:
        """Structural dependencies of each derivative and each output on the states and inputs,
        as 0-based positions in (x, u): the ModelStructure of the modelDescription."""
        known = ca.vertcat(self.x, self.u)
        result = []
        for expression in (self.f, self.g):
            sparsity = ca.jacobian(expression, known).sparsity()
            rows = [[] for _ in range(expression.shape[0])]
            for row, column in zip(*sparsity.get_triplet()):
                rows[row].append(column)
            result.append([sorted(r) for r in rows])
        return result[0], result[1]


def per_second(unit: str) -> str:
    """The unit of a quantity's time derivative ("" for a quantity without a unit): rad -> rad/s,
    rad/s -> rad/s2 (FMI's own way of writing a power)."""
    if not unit:
        return ""
    if unit == "1":
        return "1/s"
    power = re.fullmatch(r"(.*)/s(\d*)", unit)
    return f"{power.group(1)}/s{int(power.group(2) or 1) + 1}" if power else f"{unit}/s"
