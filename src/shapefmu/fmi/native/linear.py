"""Linear plants as model parts: the physical parameters -> (A, B, C, D) mapping, symbolically.

The FMU keeps a plant's physical parameters tunable, so its C code must compute A, B, C, D from
them. For every kind of ``shapefmu.plants`` this module writes the same mapping as the plant
library, in CasADi symbols (the parameters in the units written in the model file, converted with
the loader's unit tables); CasADi then generates the C. A plant whose kind is unknown (a
python-control LTI, a ``rigid_part``), or whose matrices the symbolic mapping does not reproduce,
becomes the generic ``state_space`` kind whose parameters are the entries of A, B, C, D.

Vector parameters become scalar FMU parameters ``name[1]``, ``name[2]``, ... (FMI 2.0 structured
naming); matrix entries ``A[i,j]`` (1-based).
"""

from __future__ import annotations

import math
from dataclasses import replace

import casadi as ca
import numpy as np
import scipy.linalg

from shapefmu.fmi.native.model_part import ModelPart, ScalarParameter, Signal, per_second
from shapefmu.plants import Plant
from shapefmu.plants.library import STANDARD_GRAVITY, sprung_masses_matrices
from shapefmu.plants.loader import PARAMETER_SPECS

# Library plants name the mode frequencies omega (rad/s) where model files write f (Hz or rad/s).
_EXTRA_UNITS = {"omega": {"rad/s": 1.0}}


class _Parameters:
    """Creates the FMU's scalar parameters of one plant and hands out their symbols, converted to
    the units the plant library's constructors take."""

    def __init__(self, plant: Plant, tunable: bool):
        self.plant = plant
        self.tunable = tunable
        self.scalars: list[ScalarParameter] = []
        self.descriptions: dict[str, str] = {}

    def has(self, name: str) -> bool:
        return name in self.plant.parameters

    def _factor(self, name: str, unit: str) -> float:
        spec = PARAMETER_SPECS.get(self.plant.kind, {}).get(name)
        units = _EXTRA_UNITS.get(name) or (spec.units if spec is not None else None)
        if units is None:
            return 1.0
        if unit not in units:
            raise _Mismatch(f"parameter {name} has unit {unit!r}, expected one of {sorted(units)}")
        return units[unit]

    def _make(self, name: str, value: float, unit: str, constraint: str, factor: float) -> ca.SX:
        symbol = ca.SX.sym(name)
        description = self.descriptions.get(name.split("[")[0]) or f"parameter {name} of the {self.plant.kind} model"
        self.scalars.append(ScalarParameter(name, symbol, float(value), unit, self.tunable, constraint, description))
        return factor * symbol

    def scalar(self, name: str, constraint: str = "any", default: float | None = None) -> ca.SX:
        if not self.has(name):
            if default is None:
                raise _Mismatch(f"parameter {name} is missing")
            return ca.SX(default)
        parameter = self.plant.parameters[name]
        if isinstance(parameter.value, tuple):
            raise _Mismatch(f"parameter {name} must be a scalar")
        return self._make(name, parameter.value, parameter.unit, constraint, self._factor(name, parameter.unit))

    def vector(self, name: str, constraint: str = "any", default: float | None = None, size: int = 0,
               first: str | None = None) -> list[ca.SX]:
        """The symbols name[1], name[2], ...; ``first`` overrides the constraint of name[1]."""
        if not self.has(name):
            if default is None:
                raise _Mismatch(f"parameter {name} is missing")
            return [ca.SX(default)] * size
        parameter = self.plant.parameters[name]
        values = parameter.value if isinstance(parameter.value, tuple) else (parameter.value,)
        factor = self._factor(name, parameter.unit)
        return [self._make(f"{name}[{i}]", v, parameter.unit, first if i == 1 and first else constraint, factor)
                for i, v in enumerate(values, 1)]


class _Mismatch(Exception):
    """The plant does not fit the symbolic mapping of its kind (falls back to state_space)."""


def _rigid_flexible(b2, omegas, zetas, b4s, rigid_damping):
    """Paper 002, eq. (1): rigid body x_r'' = -d x_r' + b2 u and modes
    x_fi'' = -omega_i^2 x_fi - 2 zeta_i omega_i x_fi' + b4i u; outputs x_r and x_fi."""
    n = 2 + 2 * len(omegas)
    A = ca.SX.zeros(n, n)
    B = ca.SX.zeros(n, 1)
    A[0, 1] = 1.0
    A[1, 1] = -rigid_damping
    B[1, 0] = b2
    for i, (w, z, b4) in enumerate(zip(omegas, zetas, b4s)):
        k = 2 + 2 * i
        A[k, k + 1] = 1.0
        A[k + 1, k] = -w * w
        A[k + 1, k + 1] = -2.0 * z * w
        B[k + 1, 0] = b4
    C = ca.SX(np.eye(n)[0::2])
    return A, B, C, ca.SX.zeros(C.shape[0], 1)


def _kind_rigid_flexible(p: _Parameters):
    b2 = p.scalar("b2", "nonzero")
    frequency = "f" if p.has("f") else "omega"
    omegas = p.vector(frequency, "positive")
    zetas = p.vector("zeta", "damping_ratio")
    b4s = p.vector("b4")
    damping = p.scalar("rigid_damping", "nonnegative", default=0.0)
    return _rigid_flexible(b2, omegas, zetas, b4s, damping)


def _kind_voice_coil_flexible(p: _Parameters):
    """Paper 002, Sec. I and Fig. 5: back EMF damps the rigid body by Kt^2/(R J)."""
    b2 = p.scalar("b2", "nonzero")
    Kt, R, J = p.scalar("Kt"), p.scalar("R", "positive"), p.scalar("J", "positive")
    omegas = p.vector("f", "positive")
    return _rigid_flexible(b2, omegas, p.vector("zeta", "damping_ratio"), p.vector("b4"), Kt**2 / (R * J))


def _kind_pendula(p: _Parameters):
    """Pendula on a cart (plants.library.pendula): L theta'' + 2 zeta omega L theta' + g theta = -a."""
    lengths = p.vector("lengths", "positive")
    g = p.scalar("g", "positive", default=STANDARD_GRAVITY)
    zeta = p.scalar("zeta", "damping_ratio", default=0.0)
    omegas = [ca.sqrt(g / L) for L in lengths]
    return _rigid_flexible(1.0, omegas, [zeta] * len(lengths), [-1.0 / L for L in lengths], 0.0)


def _kind_mass_spring_chain(p: _Parameters):
    """m_i x_i'' = k_{i-1} (x_{i-1} - x_i) + k_i (x_{i+1} - x_i) + the same with c (library)."""
    masses = p.vector("masses", "positive")
    n = len(masses)
    springs = p.vector("springs", "positive")
    dampers = p.vector("dampers", "nonnegative", default=0.0, size=n - 1)
    if len(springs) != n - 1 or len(dampers) != n - 1:
        raise _Mismatch("a chain of N masses needs N - 1 springs and dampers")
    K = ca.SX.zeros(n, n)
    Cd = ca.SX.zeros(n, n)
    for i in range(n - 1):
        for M, value in ((K, springs[i]), (Cd, dampers[i])):
            M[i, i] += value
            M[i + 1, i + 1] += value
            M[i, i + 1] -= value
            M[i + 1, i] -= value
    A = ca.SX.zeros(2 * n, 2 * n)
    for i in range(n):
        A[2 * i, 2 * i + 1] = 1.0
        for j in range(n):
            A[2 * i + 1, 2 * j] = -K[i, j] / masses[i]
            A[2 * i + 1, 2 * j + 1] = -Cd[i, j] / masses[i]
    B = ca.SX.zeros(2 * n, 1)
    B[1, 0] = 1.0 / masses[0]
    C = ca.SX(np.eye(2 * n)[0::2])
    return A, B, C, ca.SX.zeros(n, 1)


def _kind_sprung_masses(p: _Parameters):
    """Masses sprung from a driven carriage: the library's own matrices (plants.library.sprung_masses)
    of the symbols."""
    masses = p.vector("masses", "positive")
    n = len(masses)
    stiffnesses = p.vector("stiffnesses", "positive")
    dampers = p.vector("dampers", "nonnegative", default=0.0, size=n)
    if len(stiffnesses) != n or len(dampers) != n:
        raise _Mismatch("N sprung masses need N stiffnesses and dampers")
    return sprung_masses_matrices(masses, stiffnesses, dampers, ca.SX.zeros)


def _kind_transfer_function(p: _Parameters):
    """num(s)/den(s) in controllable canonical form, scaled by the frequency sigma = max_k |a_k|^(1/k).

    With a_k = den[k]/den[0] and b_k = num[k]/den[0] (num padded to the degree of den), the
    companion form has A = [[-a_1 ... -a_n], [I 0]], B = e_1, C_k = b_k - a_k b_0, D = b_0. Its
    entries span 1 to a_n (1e8 for eq. (33) of paper 001); the similarity T = diag(sigma^-(i-1))
    makes them all of order sigma (a_k ~ sigma^k), which keeps the ODE and its matrix exponential
    well scaled. The scaling is a smooth function of the coefficients, so it is generated with them.
    """
    num, den = p.vector("num"), p.vector("den", first="nonzero")
    if len(num) > len(den):
        raise _Mismatch("the transfer function must be proper")
    n = len(den) - 1
    if n == 0:
        raise _Mismatch("a transfer function without poles has no state")
    a = [den[k] / den[0] for k in range(1, n + 1)]
    b = [ca.SX(0.0)] * (n + 1 - len(num)) + [c / den[0] for c in num]
    sigma = ca.SX(0.0)
    for k, ak in enumerate(a, 1):
        sigma = ca.fmax(sigma, ca.fabs(ak) ** (1.0 / k))
    sigma = ca.if_else(sigma > 0, sigma, 1.0)
    A = ca.SX.zeros(n, n)
    C = ca.SX.zeros(1, n)
    for j in range(n):
        A[0, j] = -a[j] / sigma**j
        C[0, j] = (b[j + 1] - a[j] * b[0]) / sigma**j
        if j + 1 < n:
            A[j + 1, j] = sigma
    B = ca.SX.zeros(n, 1)
    B[0, 0] = 1.0
    return A, B, C, ca.reshape(b[0], 1, 1)


# Per kind: the symbolic mapping, whether its parameters may change during a run, and whether the
# plant's own state coordinates are kept (a transfer function's realisation has its own).
_MAPPINGS = {
    "rigid_flexible": (_kind_rigid_flexible, True, True),
    "voice_coil_flexible": (_kind_voice_coil_flexible, True, True),
    "pendula": (_kind_pendula, True, True),
    "mass_spring_chain": (_kind_mass_spring_chain, True, True),
    "sprung_masses": (_kind_sprung_masses, True, True),
    # The states of a realisation have no physical meaning to carry across a change of
    # coefficients: num and den are fixed.
    "transfer_function": (_kind_transfer_function, False, False),
}


def _state_space(plant: Plant):
    """The generic kind: every entry of A, B, C, D is a tunable parameter A[i,j], ... (1-based)."""
    scalars = []
    matrices = []
    for key in "ABCD":
        value = getattr(plant, key)
        M = ca.SX.zeros(*value.shape)
        for i in range(value.shape[0]):
            for j in range(value.shape[1]):
                name = f"{key}[{i + 1},{j + 1}]"
                symbol = ca.SX.sym(name)
                scalars.append(ScalarParameter(name, symbol, float(value[i, j]), "", True, "any",
                                               f"entry ({i + 1}, {j + 1}) of the state-space matrix {key}"))
                M[i, j] = symbol
        matrices.append(M)
    return scalars, matrices


def _numeric(scalars, matrices) -> list[np.ndarray]:
    symbols = ca.vertcat(*[s.symbol for s in scalars]) if scalars else ca.SX(0, 1)
    function = ca.Function("matrices", [symbols], [ca.densify(M) for M in matrices])
    return [np.array(M, dtype=float) for M in function([s.value for s in scalars])]


def _same_matrices(ours, theirs) -> bool:
    return all(a.shape == b.shape and np.allclose(a, b, rtol=1e-12, atol=1e-12 * max(1.0, np.abs(b).max(initial=0)))
               for a, b in zip(ours, theirs))


def _same_transfer_function(ours, plant: Plant) -> bool:
    """Same frequency response at frequencies spread over the plant's poles (realisations differ)."""
    A, B, C, D = ours
    if A.shape != plant.A.shape:
        return False
    scale = max(np.abs(np.linalg.eigvals(plant.A)).max(), 1.0)
    for w in scale * np.logspace(-2, 1, 7):
        s = 1j * w
        G1 = C @ np.linalg.solve(s * np.eye(len(A)) - A, B) + D
        G2 = plant.C @ np.linalg.solve(s * np.eye(len(A)) - plant.A, plant.B) + plant.D
        if not np.allclose(G1, G2, rtol=1e-9, atol=1e-12 * np.abs(G2).max()):
            return False
    return True


def state_nominals(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """A scale for each state: the peak it reaches under a unit step of every input during one
    period 2 pi/|lambda| of the slowest non-zero eigenvalue, rounded to a power of ten (1 where the
    state does not move). Hosts use it as absolute tolerance scale (abstol = rtol * nominal)."""
    n, m = B.shape
    magnitudes = np.abs(np.linalg.eigvals(A))
    # Below 1e-6 of the fastest pole: the split double pole of a rigid body (as plants.model._is_rigid).
    nonzero = magnitudes[magnitudes > 1e-6 * max(magnitudes.max(), 1.0)]
    horizon = 2.0 * math.pi / nonzero.min() if nonzero.size else 1.0
    samples = 200
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A, B
    E = scipy.linalg.expm(M * horizon / samples)
    Phi, Gamma = E[:n, :n], E[:n, n:]
    x = np.zeros(n)
    peak = np.zeros(n)
    for _ in range(samples):
        x = Phi @ x + Gamma @ np.ones(m)
        peak = np.maximum(peak, np.abs(x))
    return np.array([10.0 ** round(math.log10(v)) if v > 0 and math.isfinite(v) else 1.0 for v in peak])


def model_part(plant: Plant, *, name: str | None = None, signals: dict | None = None,
               descriptions: dict | None = None, description: str = "") -> ModelPart:
    """The model part of a linear plant: its kind's parameter mapping (or state_space), checked
    against the plant's own matrices at the plant's parameter values.

    ``signals`` maps input and output names to their model-file fields (``unit``, ``description``),
    ``descriptions`` parameter names to descriptions (both as read from a model file). An input
    with a limit |u| <= U gets min -U and max U; the states are described by what they are in the
    plant's kind (``_state_signals``).
    """
    signals = signals or {}
    matrices = None
    keep_states = True
    mapping = _MAPPINGS.get(plant.kind)
    if mapping is not None:
        build, tunable, keep_states = mapping
        parameters = _Parameters(plant, tunable)
        parameters.descriptions = dict(descriptions or {})
        try:
            candidate = build(parameters)
            numeric = _numeric(parameters.scalars, candidate)
            same = _same_matrices(numeric, (plant.A, plant.B, plant.C, plant.D)) if keep_states else \
                _same_transfer_function(numeric, plant)
            if same:
                scalars, matrices = parameters.scalars, candidate
        except _Mismatch:
            pass
    if matrices is None:
        keep_states = True
        scalars, matrices = _state_space(plant)
    A, B, C, D = matrices
    numeric_A, numeric_B = _numeric(scalars, [A, B])
    nominals = state_nominals(numeric_A, numeric_B)
    x = ca.SX.sym("x", A.shape[0])
    u = ca.SX.sym("u", B.shape[1])
    outputs = tuple(_signal(s, signals, f"output {s} of the plant") for s in plant.outputs)
    limits = {s: plant.limits.get(s) for s in plant.inputs}
    return ModelPart(
        name=name or plant.name,
        description=description,
        states=_state_signals(plant.kind if keep_states else "realisation", plant.states, nominals, outputs),
        inputs=tuple(replace(_signal(s, signals, f"input {s} of the plant"), minimum=-limits[s], maximum=limits[s])
                     if limits[s] is not None else _signal(s, signals, f"input {s} of the plant") for s in plant.inputs),
        outputs=outputs,
        parameters=tuple(scalars),
        x=x, u=u, f=A @ x + B @ u, g=C @ x + D @ u,
        linear=True,
    )


def _signal(name: str, signals: dict, fallback: str) -> Signal:
    """An input or output with its model-file unit and description (``fallback`` where it has none)."""
    fields = signals.get(name, {})
    return Signal(name, fields.get("unit", ""), description=fields.get("description") or fallback)


# What the states of a kind are, in pairs (a position, its rate), the k-th position being the k-th
# output's quantity: the names of each pair, by index k (0-based), in the order library.py builds them.
_PAIRS = {
    "rigid_flexible": lambda k: ("rigid-body position", "rigid-body velocity") if k == 0 else
    (f"deflection of flexible mode {k}", f"deflection rate of flexible mode {k}"),
    "pendula": lambda k: ("cart position", "cart velocity") if k == 0 else
    (f"swing angle of pendulum {k}", f"swing rate of pendulum {k}"),
    "mass_spring_chain": lambda k: (f"position of mass {k + 1}", f"velocity of mass {k + 1}"),
    "sprung_masses": lambda k: ("carriage position", "carriage velocity") if k == 0 else
    (f"deflection of sprung mass {k} from the carriage", f"deflection rate of sprung mass {k}"),
}
_PAIRS["voice_coil_flexible"] = _PAIRS["rigid_flexible"]


def _state_signals(kind: str, names, nominals, outputs) -> tuple[Signal, ...]:
    """The states with what they are: a kind's positions and rates (their units those of its outputs
    and per second), a transfer function's realisation or a state-space model's states (no unit)."""
    if kind in _PAIRS:
        signals = []
        for i, (name, nominal) in enumerate(zip(names, nominals)):
            unit = outputs[i // 2].unit
            text = _PAIRS[kind](i // 2)[i % 2]
            signals.append(Signal(name, unit if i % 2 == 0 else per_second(unit), nominal=float(nominal),
                                  description=text))
        return tuple(signals)
    if kind == "realisation":
        return tuple(Signal(f"x_{i}", nominal=float(v), description=f"state {i} of the transfer function's "
                            "controllable canonical realisation, scaled (no physical unit)")
                     for i, v in enumerate(nominals, 1))
    return tuple(Signal(s, nominal=float(v), description=f"state {s} of the plant's state-space model")
                 for s, v in zip(names, nominals))
