"""The ``Plant``: a linear model with named inputs, outputs, states and physical parameters.

A plant is x' = A x + B u, y = C x + D u. It converts to and from python-control ``StateSpace`` /
``TransferFunction``; every function that expects a plant also takes a python-control LTI or a
model file (``shapefmu.plants.as_plant``, which lives in ``loader`` because it reads files).
``modes()`` lists the natural frequencies, damping ratios and participations that a shaper is
designed from.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import MappingProxyType

import control
import numpy as np
from scipy.linalg import schur, solve_sylvester


@dataclass(frozen=True)
class Parameter:
    """A physical parameter: its value (a float or a tuple of floats) and its unit.

    Examples
    --------
    >>> Parameter((2000.0, 3000.0), "Hz").unit
    'Hz'
    """

    value: float | tuple[float, ...]
    unit: str


@dataclass(frozen=True)
class Mode:
    """One mode of a plant.

    ``omega`` is the undamped natural frequency in rad/s, ``zeta`` the damping ratio (1 for a real
    pole, nan for a pole at the origin, as python-control's ``damp`` reports them), ``pole`` the
    pole with non-negative imaginary part, and ``participation`` the static gain of the mode's term
    r/(s - p) in the partial-fraction expansion of the plant, summed in magnitude over all outputs:
    sum_j |r_j| / |p| for a real pole, 2 sum_j |r_j| / |p| for a pole pair: |b4| / (omega omega_d)
    for a mode b4/(s^2 + 2 zeta omega s + omega^2) of eq. (1) of paper 002, its static gain
    b4/omega^2 times 1/sqrt(1 - zeta^2), and never 0 for a mode that is seen. A mode the input does not
    excite, or no output sees, has participation 0. Poles at the origin (rigid body) have no
    finite static gain: their omega is 0 and their participation ``inf``.

    Examples
    --------
    >>> from shapefmu.plants.library import transfer_function
    >>> mode = transfer_function([100.0], [1.0, 2.0, 100.0]).modes()[0]  # 100 / (s^2 + 2 s + 100)
    >>> round(mode.hz, 6), mode.oscillatory, round(mode.participation, 9)  # 1 / sqrt(1 - zeta^2)
    (1.591549, True, 1.005037815)
    """

    omega: float
    zeta: float
    pole: complex
    participation: float

    @property
    def hz(self) -> float:
        return self.omega / (2.0 * math.pi)

    @property
    def oscillatory(self) -> bool:
        return self.pole.imag > 0.0


def _names(names, count, prefix, what):
    if names is None:
        return tuple(f"{prefix}{i}" for i in range(count))
    names = tuple(str(n) for n in names)
    if len(names) != count:
        raise ValueError(f"{what} must hold {count} names, got {len(names)}: {names}")
    if len(set(names)) != count:
        raise ValueError(f"{what} must be distinct, got {names}")
    return names


@dataclass(frozen=True, eq=False)
class Plant:
    """x' = A x + B u, y = C x + D u with named signals and physical parameters.

    ``A`` (n x n), ``B`` (n x m), ``C`` (p x n), ``D`` (p x m) are copied into read-only float arrays.
    ``parameters`` maps a parameter name to its ``Parameter`` (value with unit); ``limits`` maps an
    input name to its symmetric actuator limit |u| <= limit (e.g. the 11 V of paper 002, Table I).

    Examples
    --------
    >>> import control
    >>> plant = Plant.from_lti(control.tf([1.0], [1.0, 0.0, 100.0]), name="spring")
    >>> plant.n_states, [(round(w, 9), round(z, 9)) for w, z in plant.flexible_modes()]
    (2, [(10.0, 0.0)])
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    inputs: tuple[str, ...] = None
    outputs: tuple[str, ...] = None
    states: tuple[str, ...] = None
    parameters: dict = field(default_factory=dict)
    limits: dict = field(default_factory=dict)
    name: str = "plant"
    kind: str = "lti"

    def __post_init__(self):
        arrays = {}
        for key in "ABCD":
            value = np.array(getattr(self, key), dtype=float, ndmin=2)
            if not np.all(np.isfinite(value)):
                raise ValueError(f"{self.name}: matrix {key} must be finite")
            value.setflags(write=False)
            arrays[key] = value
        n = arrays["A"].shape[0]
        if arrays["A"].shape != (n, n) or n == 0:
            raise ValueError(f"{self.name}: A must be square and non-empty, got shape {arrays['A'].shape}")
        m = arrays["B"].shape[1]
        p = arrays["C"].shape[0]
        for key, shape in (("B", (n, m)), ("C", (p, n)), ("D", (p, m))):
            if arrays[key].shape != shape:
                raise ValueError(f"{self.name}: {key} must have shape {shape}, got {arrays[key].shape}")
        for key, value in arrays.items():
            object.__setattr__(self, key, value)
        object.__setattr__(self, "inputs", _names(self.inputs, m, "u", "inputs"))
        object.__setattr__(self, "outputs", _names(self.outputs, p, "y", "outputs"))
        object.__setattr__(self, "states", _names(self.states, n, "x", "states"))
        for key, limit in self.limits.items():
            if key not in self.inputs:
                raise ValueError(f"{self.name}: limit given for unknown input {key!r}; inputs are {self.inputs}")
            if not (math.isfinite(limit) and limit > 0):
                raise ValueError(f"{self.name}: limit of input {key!r} must be finite and > 0, got {limit!r}")
        object.__setattr__(self, "parameters", MappingProxyType(dict(self.parameters)))
        object.__setattr__(self, "limits", MappingProxyType({k: float(v) for k, v in self.limits.items()}))

    @property
    def n_states(self) -> int:
        return self.A.shape[0]

    def to_statespace(self) -> control.StateSpace:
        return control.ss(
            self.A, self.B, self.C, self.D,
            inputs=list(self.inputs), outputs=list(self.outputs), states=list(self.states), name=self.name,
        )

    def to_transfer_function(self) -> control.TransferFunction:
        return control.ss2tf(self.to_statespace())

    @classmethod
    def from_lti(cls, system, name: str | None = None, **metadata) -> Plant:
        """A plant from a python-control ``StateSpace`` or ``TransferFunction`` (converted with ``ss``).

        Signal names are taken from the system; ``metadata`` (parameters, limits, kind) is passed on.
        """
        if isinstance(system, control.TransferFunction):
            system = control.ss(system)
        if not isinstance(system, control.StateSpace):
            raise ValueError(f"expected a python-control StateSpace or TransferFunction, got {type(system).__name__}")
        if system.isdtime(strict=True):
            raise ValueError(f"a plant must be continuous-time, got a discrete-time system (dt = {system.dt})")
        return cls(
            system.A, system.B, system.C, system.D,
            inputs=system.input_labels, outputs=system.output_labels, states=system.state_labels,
            name=name or system.name, **metadata,
        )

    def modes(self) -> list[Mode]:
        """Modes sorted by natural frequency, one entry per real pole or complex pole pair.

        Frequencies and damping ratios come from python-control's ``damp``; participation from the
        residues of the stable-part decomposition (see ``Mode``).
        """
        with np.errstate(invalid="ignore"):  # damp divides by |p| = 0 for a rigid body
            wn, zeta, poles = control.damp(self.to_statespace(), doprint=False)
        participation, scale = _participations(self)
        modes = []
        for w, z, p in zip(wn, zeta, poles):
            if p.imag < 0:
                continue
            if _is_rigid(p, scale):
                modes.append(Mode(0.0, math.nan, 0j, math.inf))
            else:
                modes.append(Mode(float(w), float(z), complex(p), participation(complex(p))))
        return sorted(modes, key=lambda m: (m.omega, m.pole.imag))

    def flexible_modes(self, threshold: float = 0.0) -> list[tuple[float, float]]:
        """``(omega, zeta)`` of the oscillatory modes whose participation exceeds ``threshold``.

        This is what ``shapefmu.shapers.convolve_modes`` and ``simultaneous`` take.
        """
        return [(m.omega, m.zeta) for m in self.modes() if m.oscillatory and m.participation > threshold]


def _is_rigid(eigenvalue, scale) -> bool:
    """A pole at the origin (rigid-body motion), relative to the plant's fastest pole.

    The double pole of a rigid body is a Jordan block, whose computed eigenvalues split by about
    sqrt(machine epsilon) times the size of A; hence the loose tolerance.
    """
    return abs(eigenvalue) <= 1e-6 * scale


def decouple(plant: Plant, keep) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Block-diagonalise A = T diag(A11, A22) T^-1 with the eigenvalues selected by ``keep`` in A11.

    Returns (A11, B1, C1, (A22, B2, C2)): the kept subsystem and the rest, in the new coordinates.
    The ordered real Schur form puts the kept eigenvalues first; the Sylvester equation
    A11 X - X A22 = -A12 then removes the coupling block (it is solvable because the two blocks
    have no eigenvalue in common). Unlike an eigenvector basis this handles Jordan blocks, such
    as the double integrator of a rigid body.

    Examples
    --------
    >>> import numpy as np
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(2.0, [(10.0, 0.1, -2.0)])
    >>> A11, B1, C1, rest = decouple(plant, lambda re, im: abs(im) > 0)  # the mode alone
    >>> [complex(round(p.real, 6), round(p.imag, 6)) for p in np.linalg.eigvals(A11)]
    [(-1+9.949874j), (-1-9.949874j)]
    """
    A = plant.A
    n = A.shape[0]
    T, Z, k = schur(A, output="real", sort=keep)
    X = solve_sylvester(T[:k, :k], -T[k:, k:], -T[:k, k:]) if 0 < k < n else np.zeros((k, n - k))
    # x = Z [[I, X], [0, I]] z: the transformation that makes the Schur form block diagonal.
    S = np.eye(n)
    S[:k, k:] = X
    S_inv = np.eye(n)
    S_inv[:k, k:] = -X
    B = S_inv @ Z.T @ plant.B
    C = plant.C @ Z @ S
    return T[:k, :k], B[:k], C[:, :k], (T[k:, k:], B[k:], C[:, k:])


def _participations(plant: Plant):
    eigenvalues = np.linalg.eigvals(plant.A)
    scale = max(np.max(np.abs(eigenvalues)), 1.0)
    _, _, _, (A2, B2, C2) = decouple(plant, lambda re, im: _is_rigid(complex(re, im), scale))
    if A2.size:
        poles, V = np.linalg.eig(A2)
        W = np.linalg.inv(V)
    else:
        poles, V, W = np.zeros(0), np.zeros((0, 0)), np.zeros((0, 0))

    def participation(pole: complex) -> float:
        total = 0.0
        for i in np.flatnonzero(np.abs(poles - pole) <= 1e-9 * scale):
            # Residue matrix of this pole, C v_i w_i^T B (outputs x inputs), as a static gain.
            residue = np.outer(C2 @ V[:, i], W[i] @ B2)
            total += np.abs(residue).sum() / abs(pole)
        return float(total * (2.0 if pole.imag > 0 else 1.0))

    return participation, scale


def rigid_part(plant: Plant) -> Plant:
    """The plant without its oscillatory modes: the poles with zero imaginary part (rigid body,
    back-EMF damping, real poles), decoupled from the rest by ``decouple``.

    For the plants of paper 002 this is the rigid body b2/s^2 (or b2/(s (s + Kt^2/(R J)))) whose
    bang-bang, eq. (2), the shapers are convolved with.

    Examples
    --------
    >>> from shapefmu.plants.library import disk_drive
    >>> rigid = rigid_part(disk_drive())  # b2 / s^2
    >>> rigid.n_states, rigid.kind
    (2, 'rigid_part')
    """
    eigenvalues = np.linalg.eigvals(plant.A)
    scale = max(np.max(np.abs(eigenvalues)), 1.0)
    A1, B1, C1, _ = decouple(plant, lambda re, im: abs(im) <= 1e-12 * scale)
    if A1.size == 0:
        raise ValueError(f"plant {plant.name!r} has no real poles: it has no rigid part")
    return Plant(A1, B1, C1, plant.D, inputs=plant.inputs, outputs=plant.outputs,
                 name=f"{plant.name} (rigid part)", limits=dict(plant.limits), kind="rigid_part")
