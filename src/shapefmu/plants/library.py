"""Named plants: the flexible servomechanisms, motor and pendula of the papers, and a generic chain.

Every constructor returns a ``Plant`` whose ``parameters`` record the physical values with units,
so that a plant built here and one loaded from ``models/*.toml`` are the same object.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import control
import numpy as np
from scipy.linalg import matrix_balance

from shapefmu.plants.model import Parameter, Plant
from shapefmu.runtime.checks import check_finite, check_positive, check_zeta

STANDARD_GRAVITY = 9.80665  # m/s^2
INCH = 0.0254  # m


def rigid_flexible(
    b2: float,
    modes: Sequence[tuple[float, float, float]] = (),
    rigid_damping: float = 0.0,
    u_max: float | None = None,
    name: str = "rigid_flexible",
    input_name: str = "u",
) -> Plant:
    """A rigid body plus M flexible modes in modal coordinates (paper 002, eq. 1).

    ``modes`` holds ``(omega_n, zeta, b4)`` per flexible mode (rad/s, -, input gain). The state is
    [x_r, x_r', x_f1, x_f1', ..., x_fM, x_fM'] with x_r'' = -rigid_damping x_r' + b2 u and
    x_fi'' = -omega_ni^2 x_fi - 2 zeta_i omega_ni x_fi' + b4i u. ``rigid_damping`` is 0 for the pure
    rigid body of eq. (1) and Kt^2/(R J) with back EMF (paper 002, Sec. I and Fig. 5). Outputs are
    the rigid-body position and each modal deflection.

    Examples
    --------
    >>> plant = rigid_flexible(2.0, [(10.0, 0.1, -2.0)])  # one mode at 10 rad/s, 10 % damping
    >>> plant.n_states, plant.outputs, [(round(w, 9), round(z, 9)) for w, z in plant.flexible_modes()]
    (4, ('position', 'deflection_1'), [(10.0, 0.1)])
    """
    b2 = check_finite(b2, "b2")
    if b2 == 0.0:
        raise ValueError("b2 must be non-zero, got 0.0: the rigid body would not be driven")
    rigid_damping = check_finite(rigid_damping, "rigid_damping")
    if rigid_damping < 0:
        raise ValueError(f"rigid_damping must be >= 0 1/s, got {rigid_damping!r}")
    checked = []
    for i, mode in enumerate(modes, start=1):
        if len(mode) != 3:
            raise ValueError(f"modes[{i - 1}] must be (omega_n, zeta, b4), got {mode!r}")
        w, z, b4 = mode
        checked.append((check_positive(w, f"omega_{i}"), check_zeta(z, f"zeta_{i}"), check_finite(b4, f"b4_{i}")))
    n = 2 + 2 * len(checked)
    A = np.zeros((n, n))
    B = np.zeros((n, 1))
    A[0, 1] = 1.0
    A[1, 1] = -rigid_damping
    B[1, 0] = b2
    for i, (w, z, b4) in enumerate(checked):
        k = 2 + 2 * i
        A[k, k + 1] = 1.0
        A[k + 1, k] = -w * w
        A[k + 1, k + 1] = -2.0 * z * w
        B[k + 1, 0] = b4
    # Outputs: x_r and the modal deflections x_fi (rows of the identity on the position states).
    C = np.eye(n)[0::2]
    states = ["x_r", "v_r"] + [s for i in range(1, len(checked) + 1) for s in (f"x_f{i}", f"v_f{i}")]
    outputs = ["position"] + [f"deflection_{i}" for i in range(1, len(checked) + 1)]
    parameters = {
        "b2": Parameter(b2, "1/(V*s^2)"),
        "rigid_damping": Parameter(rigid_damping, "1/s"),
        "omega": Parameter(tuple(w for w, _, _ in checked), "rad/s"),
        "zeta": Parameter(tuple(z for _, z, _ in checked), "1"),
        "b4": Parameter(tuple(b for _, _, b in checked), "1/(V*s^2)"),
    }
    limits = {} if u_max is None else {input_name: check_positive(u_max, "u_max")}
    return Plant(A, B, C, np.zeros((len(outputs), 1)), inputs=(input_name,), outputs=outputs, states=states,
                 parameters=parameters, limits=limits, name=name, kind="rigid_flexible")


# Paper 002, Table I and Sec. IV: voice-coil motor and flexible structure of a disk drive.
DISK_DRIVE_B2 = 2.7e3  # 1/(V s^2), b2 = -b4i
DISK_DRIVE_U = 11.0  # V
DISK_DRIVE_MODES_HZ = (2.0e3, 3.0e3)
DISK_DRIVE_ZETA = 0.01
DISK_DRIVE_KT = 9.8e-2  # N m/A
DISK_DRIVE_R = 7.25  # ohm
DISK_DRIVE_J = 5e-6  # kg m^2


def disk_drive(back_emf: bool = False, n_modes: int = 2) -> Plant:
    """The disk drive of paper 002 (Table I, Fig. 5): b2 = -b4i = 2.7e3 /(V s^2), U = 11 V, modes
    at 2.0 and 3.0 kHz with zeta = 0.01.

    With ``back_emf`` the rigid body is damped by the back EMF of the voice coil,
    x_r'' = -(Kt^2/(R J)) x_r' + b2 u, with Kt, R, J from Table I (Kt^2/(R J) = 264.9 1/s).
    ``n_modes`` keeps the first 0, 1 or 2 flexible modes.

    Examples
    --------
    >>> import math
    >>> plant = disk_drive()
    >>> [round(w / (2 * math.pi), 6) for w, _ in plant.flexible_modes()], dict(plant.limits)
    ([2000.0, 3000.0], {'voltage': 11.0})
    >>> round(float(-disk_drive(back_emf=True).A[1, 1]), 1)  # Kt^2 / (R J)
    264.9
    """
    if n_modes not in (0, 1, 2):
        raise ValueError(f"n_modes must be 0, 1 or 2 (the disk drive has two modelled modes), got {n_modes!r}")
    modes = [(2.0 * math.pi * f, DISK_DRIVE_ZETA, -DISK_DRIVE_B2) for f in DISK_DRIVE_MODES_HZ[:n_modes]]
    damping = DISK_DRIVE_KT**2 / (DISK_DRIVE_R * DISK_DRIVE_J) if back_emf else 0.0
    name = "disk_drive_back_emf" if back_emf else "disk_drive"
    return rigid_flexible(DISK_DRIVE_B2, modes, damping, u_max=DISK_DRIVE_U, name=name, input_name="voltage")


# Paper 001, eq. (33): identified transfer function of the linear synchronous motor.
LSM_NUM = (0.003346, 0.0108, -885.1, -1.224e5, 9.687e7)
LSM_DEN = (1.0, 76.17, 4.944e4, 2.822e6, 1.016e8)


def transfer_function(num: Sequence[float], den: Sequence[float], name: str = "transfer_function",
                      input_name: str = "u", output_name: str = "y") -> Plant:
    """A single-input single-output plant num(s)/den(s) (coefficients in descending powers of s).

    Examples
    --------
    >>> plant = transfer_function([100.0], [1.0, 2.0, 100.0])  # omega_n = 10 rad/s, zeta = 0.1
    >>> mode = plant.modes()[0]
    >>> round(mode.omega, 9), round(mode.zeta, 9)
    (10.0, 0.1)
    """
    num = tuple(check_finite(c, f"num[{i}]") for i, c in enumerate(num))
    den = tuple(check_finite(c, f"den[{i}]") for i, c in enumerate(den))
    if not den or den[0] == 0.0:
        raise ValueError(f"den must start with a non-zero leading coefficient, got {den}")
    if len(num) > len(den):
        raise ValueError(f"the transfer function must be proper: num has degree {len(num) - 1} > {len(den) - 1}")
    system = control.ss(control.tf(list(num), list(den)))
    # The companion form of a transfer function mixes entries of 1 and 1e8 (eq. 33 of paper 001);
    # a diagonal similarity that balances A keeps expm, eigenvalues and rank tests accurate.
    _, (scale, _) = matrix_balance(system.A, permute=False, separate=True)
    A = system.A * scale[None, :] / scale[:, None]
    return Plant(A, system.B / scale[:, None], system.C * scale[None, :], system.D,
                 inputs=(input_name,), outputs=(output_name,),
                 parameters={"num": Parameter(num, "1"), "den": Parameter(den, "1")},
                 name=name, kind="transfer_function")


def linear_synchronous_motor() -> Plant:
    """The linear synchronous motor of paper 001, eq. (33): position command in, position out.

    Examples
    --------
    >>> plant = linear_synchronous_motor()
    >>> [(round(m.omega, 2), round(m.zeta, 4)) for m in plant.modes()]
    [(46.85, 0.6426), (215.14, 0.0371)]
    """
    return transfer_function(LSM_NUM, LSM_DEN, name="linear_synchronous_motor",
                             input_name="position_command", output_name="position")


def pendula(lengths: Sequence[float], g: float = STANDARD_GRAVITY, zeta: float = 0.0, name: str = "pendula") -> Plant:
    """Pendula hanging from one cart: cart acceleration in, cart position and swing angles out.

    Linearised about hanging rest, a pendulum of length L on a cart with acceleration a swings as
    L theta'' + 2 zeta omega L theta' + g theta = -a, omega = sqrt(g / L). The state is
    [x, x', theta_1, theta_1', ...]; the cart is the rigid body x'' = a.

    Examples
    --------
    >>> import math
    >>> plant = pendula([1.0, 0.5])  # omega = sqrt(g / L)
    >>> [round(w, 9) for w, _ in plant.flexible_modes()] == [round(math.sqrt(9.80665 / L), 9) for L in (1.0, 0.5)]
    True
    """
    lengths = tuple(check_positive(L, f"lengths[{i}]") for i, L in enumerate(lengths))
    if not lengths:
        raise ValueError("lengths must hold at least one pendulum length")
    g = check_positive(g, "g")
    zeta = check_zeta(zeta, "zeta")
    modes = [(math.sqrt(g / L), zeta, -1.0 / L) for L in lengths]
    base = rigid_flexible(1.0, modes, name=name, input_name="acceleration")
    outputs = ["cart_position"] + [f"theta_{i}" for i in range(1, len(lengths) + 1)]
    states = ["x", "v"] + [s for i in range(1, len(lengths) + 1) for s in (f"theta_{i}", f"omega_{i}")]
    parameters = {"lengths": Parameter(lengths, "m"), "g": Parameter(g, "m/s^2"), "zeta": Parameter(zeta, "1")}
    return Plant(base.A, base.B, base.C, base.D, inputs=("acceleration",), outputs=outputs, states=states,
                 parameters=parameters, name=name, kind="pendula")


# Paper 003, Sec. V: ten pendula whose masses are evenly spaced from 28.8 in to 34.2 in below the
# cart, giving natural frequencies from 3.66 to 3.36 rad/s.
TEN_PENDULA_LENGTHS = tuple(INCH * (28.8 + 0.6 * i) for i in range(10))


def ten_pendula() -> Plant:
    """The ten-pendula comb of paper 003 (cart acceleration in, cart position and ten angles out).

    Examples
    --------
    >>> plant = ten_pendula()
    >>> plant.n_states, len(plant.flexible_modes())
    (22, 10)
    """
    return pendula(TEN_PENDULA_LENGTHS, name="ten_pendula")


def mass_spring_chain(masses: Sequence[float], springs: Sequence[float], dampers: Sequence[float] | None = None,
                      name: str = "mass_spring_chain") -> Plant:
    """N free masses joined by N - 1 springs (and dampers), a force on the first mass.

    m_i x_i'' = k_{i-1} (x_{i-1} - x_i) + k_i (x_{i+1} - x_i) + the same with c and velocities,
    plus the force F on mass 1. With no spring to ground the chain has a rigid-body mode.
    The state is [x_1, x_1', ..., x_N, x_N']; outputs are the positions of all masses.

    Examples
    --------
    >>> import math
    >>> plant = mass_spring_chain([1.0, 1.0], [100.0])  # two unit masses: sqrt(2 k / m)
    >>> math.isclose(plant.flexible_modes()[0][0], math.sqrt(200.0))
    True
    """
    masses = tuple(check_positive(m, f"masses[{i}]") for i, m in enumerate(masses))
    n = len(masses)
    if n < 1:
        raise ValueError("masses must hold at least one mass")
    springs = tuple(check_positive(k, f"springs[{i}]") for i, k in enumerate(springs))
    dampers = (0.0,) * (n - 1) if dampers is None else tuple(check_finite(c, f"dampers[{i}]") for i, c in enumerate(dampers))
    if len(springs) != n - 1 or len(dampers) != n - 1:
        raise ValueError(f"a chain of {n} masses needs {n - 1} springs and dampers, got {len(springs)} and {len(dampers)}")
    if any(c < 0 for c in dampers):
        raise ValueError(f"dampers must be >= 0 N*s/m, got {dampers}")
    K = np.zeros((n, n))
    Cd = np.zeros((n, n))
    for i, (k, c) in enumerate(zip(springs, dampers)):
        for M, value in ((K, k), (Cd, c)):
            M[i, i] += value
            M[i + 1, i + 1] += value
            M[i, i + 1] -= value
            M[i + 1, i] -= value
    inv_m = np.diag(1.0 / np.array(masses))
    A = np.zeros((2 * n, 2 * n))
    A[0::2, 1::2] = np.eye(n)
    A[1::2, 0::2] = -inv_m @ K
    A[1::2, 1::2] = -inv_m @ Cd
    B = np.zeros((2 * n, 1))
    B[1, 0] = 1.0 / masses[0]
    C = np.eye(2 * n)[0::2]
    states = [s for i in range(1, n + 1) for s in (f"x_{i}", f"v_{i}")]
    parameters = {"masses": Parameter(masses, "kg"), "springs": Parameter(springs, "N/m"),
                  "dampers": Parameter(dampers, "N*s/m")}
    return Plant(A, B, C, np.zeros((n, 1)), inputs=("force",), outputs=[f"x_{i}" for i in range(1, n + 1)],
                 states=states, parameters=parameters, name=name, kind="mass_spring_chain")


def sprung_masses(masses: Sequence[float], stiffnesses: Sequence[float], dampers: Sequence[float] | None = None,
                  name: str = "sprung_masses") -> Plant:
    """Masses on springs (and dampers) carried by a driven carriage: carriage acceleration in.

    A printer's bed on its belt, a toolhead on its frame: the drive imposes the carriage acceleration
    a, and mass i, joined to the carriage by a spring k_i and a damper c_i, deflects from it by e_i,

        m_i e_i'' + c_i e_i' + k_i e_i = -m_i a,

    so its mode is omega_i = sqrt(k_i / m_i), zeta_i = c_i / (2 sqrt(k_i m_i)) (the belt-driven bed of
    Marlin #26655: 1 kg at 30 Hz, 1.3 kg at 30 / sqrt(1.3) = 26.3 Hz). The state is
    [x, v, e_1, e_1', ...]; the outputs are the carriage position, each deflection e_i, then each
    mass's acceleration a + e_i'' = -(k_i e_i + c_i e_i') / m_i, what an accelerometer on it reads.

    Examples
    --------
    >>> import math
    >>> bed = sprung_masses([1.0], [35530.57584392168], [18.84955592153876])  # Marlin #26655's bed
    >>> [(round(w / (2 * math.pi), 6), round(z, 6)) for w, z in bed.flexible_modes()]  # sqrt(k/m), c/(2 sqrt(km))
    [(30.0, 0.05)]
    >>> bed.outputs
    ('carriage_position', 'deflection_1', 'acceleration_1')
    """
    masses = tuple(check_positive(m, f"masses[{i}]") for i, m in enumerate(masses))
    if not masses:
        raise ValueError("masses must hold at least one mass")
    n = len(masses)
    stiffnesses = tuple(check_positive(k, f"stiffnesses[{i}]") for i, k in enumerate(stiffnesses))
    dampers = (0.0,) * n if dampers is None else tuple(check_finite(c, f"dampers[{i}]") for i, c in enumerate(dampers))
    if len(stiffnesses) != n or len(dampers) != n:
        raise ValueError(f"{n} sprung masses need {n} stiffnesses and dampers, got {len(stiffnesses)} and {len(dampers)}")
    if any(c < 0 for c in dampers):
        raise ValueError(f"dampers must be >= 0 N*s/m, got {dampers}")
    A, B, C, D = sprung_masses_matrices(masses, stiffnesses, dampers)
    states = ["x", "v"] + [s for i in range(1, n + 1) for s in (f"e_{i}", f"de_{i}")]
    outputs = (["carriage_position"] + [f"deflection_{i}" for i in range(1, n + 1)]
               + [f"acceleration_{i}" for i in range(1, n + 1)])
    parameters = {"masses": Parameter(masses, "kg"), "stiffnesses": Parameter(stiffnesses, "N/m"),
                  "dampers": Parameter(dampers, "N*s/m")}
    return Plant(A, B, C, D, inputs=("acceleration",), outputs=outputs, states=states,
                 parameters=parameters, name=name, kind="sprung_masses")


def sprung_masses_matrices(masses, stiffnesses, dampers, zeros=lambda rows, columns: np.zeros((rows, columns))):
    """A, B, C, D of ``sprung_masses`` (state [x, v, e_1, e_1', ...]) from unchecked parameters of
    any type that divides and negates: floats here, CasADi symbols in the plant-FMU generator
    (``shapefmu.fmi.native.linear``), whose ``zeros(rows, columns)`` makes the matrices.

    Examples
    --------
    >>> A, B, C, D = sprung_masses_matrices([2.0], [50.0], [4.0])
    >>> A[3].tolist(), C[2].tolist()  # e'' = -(k/m) e - (c/m) e' - a; the accelerometer reads a + e''
    ([0.0, 0.0, -25.0, -2.0], [0.0, 0.0, -25.0, -2.0])
    """
    n = len(masses)
    A, B, C, D = zeros(2 + 2 * n, 2 + 2 * n), zeros(2 + 2 * n, 1), zeros(1 + 2 * n, 2 + 2 * n), zeros(1 + 2 * n, 1)
    A[0, 1] = 1.0
    B[1, 0] = 1.0
    C[0, 0] = 1.0
    for i, (m, k, c) in enumerate(zip(masses, stiffnesses, dampers)):
        e = 2 + 2 * i
        A[e, e + 1] = 1.0
        A[e + 1, e] = -k / m
        A[e + 1, e + 1] = -c / m
        B[e + 1, 0] = -1.0
        C[1 + i, e] = 1.0
        C[1 + n + i, e] = -k / m
        C[1 + n + i, e + 1] = -c / m
    return A, B, C, D
