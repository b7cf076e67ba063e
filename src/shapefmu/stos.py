"""Shaped time-optimal servomechanism (STOS, paper 002): design, sampled closed-loop simulation, plots.

``stos_law`` builds the law for a plant in the modal form of eq. (1) (a rigid body, optionally
damped by back EMF, plus flexible modes) from any positive impulse shaper: the switching curves
come from ``shapefmu.runtime.stos.stos_curves`` (the same code the STOS FMU runs), and the linear
settle controller that takes over near the target is placed with python-control (``design_settle``).
``simulate_stos`` closes the loop at a sampling period Ts with a zero-order hold on the exact
continuous plant (one matrix exponential per Ts) and measures move time, residual flexible
vibration, peak input and chattering.

Where the OCR'd paper and the construction disagree (tests/test_stos.py shows each by exact
simulation of the shaped bang-bang):

- the switching curves of eqs. (7)-(16) and S1-S7 all agree with the construction (to 1e-12) once
  one notes that eq. (4) assumes T1 < T2, so "mode 1" of the convolution formulas is the higher
  mode (3 kHz on the disk drive);
- eq. (18) gives the last decelerating level as -a2 a3 U; eq. (4) and the shaped bang-bang give
  -a2 a4 U (the level that brings the velocity S10 = a2 a4 U b2 T1 to 0 in T1);
- eq. (22) gives the first level as (a2 + a3) U; eq. (21) and the shaped bang-bang give a1 U
  (the level that reaches S1 = a1 U b2 T1 in T1).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import control
import numpy as np
from scipy.linalg import expm

from shapefmu.files import save_figure
from shapefmu.plants import Plant, as_plant
from shapefmu.runtime.checks import check_finite, check_positive, check_size
from shapefmu.runtime.stos import STOSKernel, stos_curves
from shapefmu.shapers import ImpulseShaper, convolve_modes, design

SHAPERS = ("convolution", "simultaneous", "zvd", "ei")


def rigid_body(plant) -> tuple[float, float]:
    """(b, damping) of the rigid body x_r'' = -damping x_r' + b u of a plant in the form of eq. (1).

    The plant's states 0 and 1 must be the rigid-body position and velocity, decoupled from the
    flexible modes (the modal form that ``library.rigid_flexible`` and ``models/disk_drive*.toml``
    build), with a free integrator: A[0] = e_1, A[1] = [0, -damping, 0, ...], B[1] = b > 0.

    Examples
    --------
    >>> from shapefmu.plants.library import disk_drive
    >>> rigid_body(disk_drive())  # paper 002, Table I: b = 2.7e3, no back EMF
    (2700.0, 0.0)
    """
    plant = as_plant(plant)
    A, B = plant.A, plant.B
    n = plant.n_states
    if B.shape[1] != 1:
        raise ValueError(f"plant {plant.name!r} has {B.shape[1]} inputs; STOS needs exactly one")
    scale = max(float(np.max(np.abs(A))), 1.0)
    row0 = np.zeros(n)
    if n >= 2:
        row0[1] = 1.0
    rigid = (
        n >= 2
        and np.allclose(A[0], row0, atol=1e-12 * scale)
        and abs(A[1, 0]) <= 1e-12 * scale
        and np.allclose(A[1, 2:], 0.0, atol=1e-12 * scale)
        and np.allclose(A[2:, :2], 0.0, atol=1e-12 * scale)
        and -A[1, 1] >= 0.0
    )
    if not rigid:
        raise ValueError(f"plant {plant.name!r} has no rigid-body mode in the form of eq. (1) of paper 002: states "
                         "0 and 1 must be a free position and velocity (x'' = -d x' + b u) decoupled from the rest")
    b = float(B[1, 0])
    if b <= 0.0:
        raise ValueError(f"plant {plant.name!r} must have a rigid-body input gain b > 0, got {b!r}")
    return b, float(-A[1, 1])


def with_mode_error(plant, factor: float) -> Plant:
    """The plant of eq. (1) with every flexible natural frequency multiplied by ``factor`` (zeta kept):
    the plant a law designed for the nominal one meets under a frequency error.

    Examples
    --------
    >>> import math
    >>> from shapefmu.plants.library import disk_drive
    >>> faster = with_mode_error(disk_drive(), 1.1)  # 2.0 and 3.0 kHz become 2.2 and 3.3 kHz
    >>> [round(math.sqrt(-faster.A[k + 1, k]) / (2 * math.pi), 6) for k in (2, 4)]
    [2200.0, 3300.0]
    """
    plant = as_plant(plant)
    rigid_body(plant)
    factor = check_positive(factor, "factor")
    A = np.array(plant.A)
    for k in range(2, plant.n_states, 2):
        A[k + 1, k] *= factor**2
        A[k + 1, k + 1] *= factor
    return Plant(A, plant.B, plant.C, plant.D, inputs=plant.inputs, outputs=plant.outputs, states=plant.states,
                 limits=dict(plant.limits), name=f"{plant.name} (modes x {factor:g})", kind=plant.kind)


def _u_max(plant: Plant, u_max) -> float:
    if u_max is not None:
        return check_positive(u_max, "u_max")
    if plant.inputs[0] not in plant.limits:
        raise ValueError(f"u_max not given and plant {plant.name!r} declares no limit for input {plant.inputs[0]!r}")
    return plant.limits[plant.inputs[0]]


def _flexible_modes(plant: Plant) -> list[tuple[float, float]]:
    modes = []
    for k in range(2, plant.n_states, 2):
        omega = math.sqrt(-plant.A[k + 1, k])
        modes.append((omega, -plant.A[k + 1, k + 1] / (2.0 * omega)))
    return modes


def shaper_for(plant, kind: str = "simultaneous") -> ImpulseShaper:
    """A positive multi-mode shaper for the plant's flexible modes: ``convolution`` (ZV per mode,
    paper 002 Sec. II-A), ``simultaneous`` (eq. 20), or a robust ``zvd`` / ``ei`` per mode convolved.

    Examples
    --------
    >>> from shapefmu.plants.library import disk_drive
    >>> len(shaper_for(disk_drive(), "convolution")), len(shaper_for(disk_drive(), "simultaneous"))
    (4, 3)
    """
    plant = as_plant(plant)
    rigid_body(plant)
    modes = _flexible_modes(plant)
    if not modes:
        raise ValueError(f"plant {plant.name!r} has no flexible modes to shape")
    if kind == "convolution":
        return convolve_modes(modes)
    if kind in ("simultaneous", "zvd", "ei"):
        return design(kind, modes)
    raise ValueError(f"shaper must be one of {', '.join(SHAPERS)}, got {kind!r}")


def design_settle(b: float, U: float, Ts: float, damping: float = 0.0, bandwidth: float | None = None,
                  fill: float = 0.5, exit_factor: float = 2.0) -> dict:
    """Gains and hand-over region of the linear settle controller u = -(kp x_e + kd v + ki I).

    The rigid body x'' = -damping x' + b u is discretised exactly with a zero-order hold at ``Ts``
    (python-control ``c2d``) and augmented with the integrator I_{k+1} = I_k + Ts x_e,k; Ackermann's
    formula (``control.acker``) puts the three closed-loop poles at z = exp(-bandwidth Ts), the
    triple real pole of a critically damped third-order loop. The hand-over region
    |x_e|/x_enter + |v|/v_enter <= 1 is where the PD part stays within ``fill`` U (x_enter =
    fill U/kp, v_enter = fill U/kd); the loop returns to STOS outside ``exit_factor`` times it.
    ``bandwidth`` (rad/s) defaults to 0.1/Ts.

    Examples
    --------
    >>> gains = design_settle(2700.0, 11.0, 1e-5)  # the disk drive's rigid body at 100 kHz
    >>> gains["bandwidth"], round(gains["x_enter"] * gains["kp"] / 11.0, 12)  # x_enter = fill U / kp
    (10000.0, 0.5)
    """
    b = check_positive(b, "b")
    U = check_positive(U, "U")
    Ts = check_positive(Ts, "Ts")
    damping = check_finite(damping, "damping")
    bandwidth = 0.1 / Ts if bandwidth is None else check_positive(bandwidth, "bandwidth")
    fill = check_positive(fill, "fill")
    if exit_factor < 1.0:
        raise ValueError(f"exit_factor must be >= 1, got {exit_factor!r}")
    rigid = control.ss([[0.0, 1.0], [0.0, -damping]], [[0.0], [b]], np.eye(2), np.zeros((2, 1)))
    discrete = control.c2d(rigid, Ts, method="zoh")
    A = np.zeros((3, 3))
    A[:2, :2] = discrete.A
    A[2, 0] = Ts
    A[2, 2] = 1.0
    B = np.vstack([discrete.B, [[0.0]]])
    pole = math.exp(-bandwidth * Ts)
    kp, kd, ki = np.asarray(control.acker(A, B, [pole, pole, pole])).ravel()
    if min(kp, kd) <= 0.0:
        raise ValueError(f"bandwidth {bandwidth!r} rad/s at Ts = {Ts!r} s gives non-positive PD gains; lower it")
    kp, kd, ki = float(kp), float(kd), float(ki)
    x_enter, v_enter = fill * U / kp, fill * U / kd
    return {"kp": kp, "kd": kd, "ki": ki, "Ts": Ts, "x_enter": x_enter, "v_enter": v_enter,
            "x_exit": exit_factor * x_enter, "v_exit": exit_factor * v_enter, "bandwidth": bandwidth}


@dataclass(frozen=True)
class STOSLaw:
    """A STOS design: the shaper, the switching curves (``runtime.stos.stos_curves``) and the settle
    controller's parameters (None: the pure law of the paper). Serialises to JSON as the FMU's
    parameter set.

    Examples
    --------
    >>> from shapefmu.plants.library import disk_drive
    >>> law = stos_law(disk_drive())
    >>> law.U, law.settle, law.to_dict()["kind"]
    (11.0, None, 'stos')
    """

    shaper: ImpulseShaper
    curves: dict
    settle: dict | None

    @property
    def U(self) -> float:
        return self.curves["U"]

    @property
    def min_distance(self) -> float:
        """The shortest move for which the paper's assumption (pulses longer than the shaper) holds."""
        return self.curves["min_distance"]

    def kernel(self) -> STOSKernel:
        return STOSKernel(self.curves, self.settle)

    def to_dict(self) -> dict:
        return {"kind": "stos", "curves": self.curves, "settle": self.settle}

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2)


def stos_law(plant, shaper: ImpulseShaper | str = "simultaneous", Ts: float | None = None,
             u_max: float | None = None, settle_bandwidth: float | None = None) -> STOSLaw:
    """The STOS law for ``plant`` (eq. 1 form, ``rigid_body``) and ``shaper`` (an ``ImpulseShaper``
    with positive amplitudes, or a name from ``SHAPERS`` designed for the plant's modes).

    With ``Ts`` a settle controller for that sampling period is added (``design_settle``); its
    bandwidth defaults to a tenth of the lowest flexible mode, so that it barely excites the modes,
    and at most 0.2/Ts.

    Examples
    --------
    >>> from shapefmu.plants.library import disk_drive
    >>> law = stos_law(disk_drive(), "simultaneous", Ts=1e-5)
    >>> len(law.shaper), round(law.shaper.duration * 1e6, 2), sorted(law.settle)[:3]  # 3 impulses over 400 us
    (3, 400.02, ['Ts', 'bandwidth', 'kd'])
    """
    plant = as_plant(plant)
    b, damping = rigid_body(plant)
    U = _u_max(plant, u_max)
    if isinstance(shaper, str):
        shaper = shaper_for(plant, shaper)
    if not isinstance(shaper, ImpulseShaper):
        raise ValueError(f"shaper must be an ImpulseShaper or one of {SHAPERS}, got {type(shaper).__name__}")
    curves = stos_curves(b, U, shaper.times, shaper.amplitudes, damping)
    settle = None
    if Ts is not None:
        Ts = check_positive(Ts, "Ts")
        modes = _flexible_modes(plant)
        if settle_bandwidth is None:
            settle_bandwidth = min([0.1 * w for w, _ in modes] + [0.2 / Ts])
        settle = design_settle(b, U, Ts, damping, settle_bandwidth)
    return STOSLaw(shaper, curves, settle)


def step(time: float, value: float) -> Callable[[float], float]:
    """A step disturbance: 0 before ``time``, ``value`` from then on (input units, e.g. V).

    Examples
    --------
    >>> w = step(1e-3, 0.5)
    >>> w(0.0), w(1e-3)
    (0.0, 0.5)
    """
    time, value = check_finite(time, "time"), check_finite(value, "value")
    return lambda t: value if t >= time else 0.0


@dataclass(frozen=True)
class STOSMetrics:
    """``move_time``: from t = 0 until x_r stays within ``tolerance`` |X| of the final target;
    ``handover_time``: first sample the settle controller is in charge (nan if never);
    ``residual_vibration``: per flexible mode, max |x_fi| after the move (from the hand-over, or
    from the move time without settle controller); ``peak_u``: max |u|; ``chattering``: sign
    changes of u (|u| > 1e-3 U) in the last quarter of the run; ``final_error``: max |x_r - target|
    over the last quarter, relative to |X|.

    Examples
    --------
    >>> STOSMetrics(2.9e-3, 3e-3, (4.1e-6, 3.0e-6), 11.0, 0, 5.8e-6, 1e-3).peak_u
    11.0
    """

    move_time: float
    handover_time: float
    residual_vibration: tuple[float, ...]
    peak_u: float
    chattering: int
    final_error: float
    tolerance: float


@dataclass(frozen=True)
class STOSResult:
    """Sampled closed-loop run: ``t`` (N), states ``x`` (N x n; x_r, x_r', then x_f1, x_f1', ...),
    the held input ``u`` on [t_k, t_k + Ts), the ``target`` and ``disturbance`` at each sample,
    and the ``metrics``.

    Examples
    --------
    >>> from shapefmu.plants.library import disk_drive
    >>> plant = disk_drive()
    >>> result = simulate_stos(plant, stos_law(plant, Ts=1e-5), 0.05, 1e-5, 0.012)
    >>> result.x.shape, float(result.x_r[0]), round(float(result.x_r[-1]), 5)
    ((1201, 6), 0.0, 0.05)
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    target: np.ndarray
    disturbance: np.ndarray
    settling: np.ndarray
    Ts: float
    distance: float
    metrics: STOSMetrics

    @property
    def x_r(self) -> np.ndarray:
        return self.x[:, 0]

    @property
    def x_r_dot(self) -> np.ndarray:
        return self.x[:, 1]

    @property
    def flexible(self) -> np.ndarray:
        return self.x[:, 2:]


def _zoh(plant: Plant, Ts: float) -> tuple[np.ndarray, np.ndarray]:
    n = plant.n_states
    M = np.zeros((n + 1, n + 1))
    M[:n, :n] = plant.A
    M[:n, n] = plant.B[:, 0]
    E = expm(M * Ts)
    return E[:n, :n], E[:n, n]


def _check_run_size(plant, Ts: float, t_end: float) -> None:
    """Refuse a run whose arrays (steps + 1 rows of the states, u, w, the target and the time) would
    not fit in memory, before any of it is computed."""
    check_size((t_end / Ts + 1) * (plant.n_states + 4) * 8, "MAX_RESULT_BYTES",
               f"simulating {t_end!r} s at Ts = {Ts!r} s needs", "bytes", "use a shorter t_end or a longer Ts")


def simulate_stos(plant, law: STOSLaw, X: float, Ts: float, t_end: float,
                  disturbance: Callable[[float], float] | None = None,
                  setpoint_changes: Sequence[tuple[float, float]] = (), tolerance: float = 1e-3) -> STOSResult:
    """Sampled STOS loop from rest at 0 to the target ``X`` on the exact continuous plant.

    At every t_k = k Ts the kernel reads x_r, x_r' and the current target and its input is held
    for Ts; the plant advances by x_{k+1} = e^{A Ts} x_k + int_0^Ts e^{A s} ds B (u_k + w_k), exact
    for inputs constant over the sample. ``disturbance(t)`` is an input-equivalent disturbance
    w (e.g. a torque step as the voltage that produces it), sampled and held like u.
    ``setpoint_changes`` holds (time, new target) pairs that the loop follows without re-design.

    Examples
    --------
    >>> from shapefmu.plants.library import disk_drive
    >>> plant = disk_drive()  # paper 002: 0.05 rad at |u| <= 11 V in 2.9 ms, modes left at ~4e-6
    >>> m = simulate_stos(plant, stos_law(plant, Ts=1e-5), 0.05, 1e-5, 0.012).metrics
    >>> round(m.move_time, 6), m.peak_u, max(m.residual_vibration) < 5e-6
    (0.0029, 11.0, True)
    """
    plant = as_plant(plant)
    rigid_body(plant)
    X = check_finite(X, "X")
    if X == 0.0:
        raise ValueError("X must be non-zero: a move of 0 has no move time")
    Ts = check_positive(Ts, "Ts")
    t_end = check_positive(t_end, "t_end")
    tolerance = check_positive(tolerance, "tolerance")
    changes = sorted((check_finite(t, "setpoint change time"), check_finite(x, "setpoint")) for t, x in setpoint_changes)
    _check_run_size(plant, Ts, t_end)
    steps = int(math.ceil(t_end / Ts - 1e-9))
    Ad, Bd = _zoh(plant, Ts)
    kernel = law.kernel()
    x = np.zeros(plant.n_states)
    t = np.arange(steps + 1) * Ts
    states = np.empty((steps + 1, plant.n_states))
    u = np.zeros(steps + 1)
    w = np.zeros(steps + 1)
    target = np.empty(steps + 1)
    settling = np.zeros(steps + 1, dtype=bool)
    goal, pending = X, list(changes)
    for k in range(steps + 1):
        while pending and pending[0][0] <= t[k] + 1e-12 * Ts:
            goal = pending.pop(0)[1]
        states[k] = x
        target[k] = goal
        u[k] = kernel.control(goal, x[0], x[1])
        settling[k] = kernel.get_state()[0] == 1.0
        w[k] = 0.0 if disturbance is None else disturbance(t[k])
        x = Ad @ x + Bd * (u[k] + w[k])
    metrics = _metrics(t, states, u, target, settling, law.U, abs(goal - 0.0), tolerance)
    return STOSResult(t, states, u, target, w, settling, Ts, X, metrics)


def _metrics(t, x, u, target, settling, U, distance, tolerance) -> STOSMetrics:
    error = np.abs(x[:, 0] - target[-1])
    outside = np.flatnonzero(error > tolerance * distance)
    move_time = float(t[outside[-1] + 1]) if outside.size and outside[-1] + 1 < t.size else (
        math.inf if outside.size else 0.0)
    handed = np.flatnonzero(settling)
    handover = float(t[handed[0]]) if handed.size else math.nan
    start = handed[0] if handed.size else min(outside[-1] + 1 if outside.size else 0, t.size - 1)
    residual = tuple(float(np.max(np.abs(x[start:, k]))) for k in range(2, x.shape[1], 2))
    tail = slice(3 * t.size // 4, None)
    active = u[tail][np.abs(u[tail]) > 1e-3 * U]
    chattering = int(np.count_nonzero(np.diff(np.sign(active)) != 0))
    final_error = float(np.max(error[tail]) / distance)
    return STOSMetrics(move_time, handover, residual, float(np.max(np.abs(u))), chattering, final_error, tolerance)


def plot_stos(results: dict[str, STOSResult], path, plant=None) -> None:
    """One column per run (like Fig. 6 of paper 002): u, x_r, x_r', the modal deflections x_fi and
    velocities x_fi' against time.

    Examples
    --------
    >>> import os, tempfile
    >>> from shapefmu.plants.library import disk_drive
    >>> plant = disk_drive()
    >>> result = simulate_stos(plant, stos_law(plant, Ts=1e-5), 0.05, 1e-5, 0.006)
    >>> path = os.path.join(tempfile.mkdtemp(), "stos.png")
    >>> plot_stos({"simultaneous": result}, path)
    >>> os.path.getsize(path) > 0
    True
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(results)
    fig, axes = plt.subplots(5, len(names), sharex="col", figsize=(5.5 * len(names), 10), squeeze=False)
    for j, name in enumerate(names):
        r = results[name]
        ms = r.t * 1e3
        axes[0, j].step(ms, r.u, where="post", lw=0.8)
        axes[0, j].set_title(name)
        axes[1, j].plot(ms, r.x_r, lw=0.8)
        axes[1, j].plot(ms, r.target, lw=0.6, ls="--", color="0.5")
        axes[2, j].plot(ms, r.x_r_dot, lw=0.8)
        for i in range(r.flexible.shape[1] // 2):
            style = "-" if i == 0 else "--"
            axes[3, j].plot(ms, 1e4 * r.flexible[:, 2 * i], style, lw=0.8, label=f"mode {i + 1}")
            axes[4, j].plot(ms, r.flexible[:, 2 * i + 1], style, lw=0.8)
        axes[3, j].legend(fontsize="small")
        axes[4, j].set_xlabel("time [ms]")
    for row, label in enumerate(("u", "x_r", "x_r'", "x_f [1e-4]", "x_f'")):
        axes[row, 0].set_ylabel(label)
    fig.tight_layout()
    try:
        save_figure(fig, path)
    finally:
        plt.close(fig)


def rigid_bang_bang_residual(plant, distance: float, Ts: float, window: float = 2e-3,
                             u_max: float | None = None) -> tuple[float, tuple[float, ...]]:
    """(move time, per-mode max |x_fi|) of the unshaped rigid-body time-optimal bang-bang (eq. 2, or
    its back-EMF version from ``optimal.rigid_bang_bang``) on the full plant, simulated exactly and
    read every ``Ts`` over ``window`` seconds after the command ends: the vibration STOS removes.

    Examples
    --------
    >>> import math
    >>> from shapefmu.plants.library import disk_drive
    >>> T, residual = rigid_bang_bang_residual(disk_drive(), 0.05, 1e-5)
    >>> math.isclose(T, 2 * math.sqrt(0.05 / (2700 * 11)))  # eq. 2: T = 2 sqrt(X / (b U))
    True
    """
    from shapefmu.optimal import rigid_bang_bang, simulate

    plant = as_plant(plant)
    command = rigid_bang_bang(plant, distance, _u_max(plant, u_max))
    end = command.breaks[-1]
    _, x = simulate(plant, command, end + np.arange(0.0, window, Ts))
    return end, tuple(float(np.max(np.abs(x[:, k]))) for k in range(2, plant.n_states, 2))


def stos_report(path, distance: float, shaper: str = "simultaneous", Ts: float = 1e-6, t_end: float | None = None,
                u_max: float | None = None, plot=None) -> str:
    """The text of ``shapefmu stos FILE --distance X --shaper KIND [--ts TS] [--plot out.png]``.

    Examples
    --------
    >>> print(stos_report("disk_drive", 0.05, Ts=1e-5).splitlines()[0])
    STOS on plant disk_drive: move of 0.05 with |u| <= 11, Ts = 1e-05 s, simultaneous shaper of 3 impulses, length 0.000400021 s
    """
    plant = as_plant(path)
    Ts = check_positive(Ts, "Ts")
    if t_end is not None:
        _check_run_size(plant, Ts, check_positive(t_end, "t_end"))
    law = stos_law(plant, shaper, Ts, u_max)
    distance = check_finite(distance, "distance")
    if distance == 0.0:
        raise ValueError("distance must be non-zero: a move of 0 has no move time")
    rigid_T, rigid_residual = rigid_bang_bang_residual(plant, distance, Ts, u_max=law.U)
    t_end = 2.0 * rigid_T + 2e-3 if t_end is None else t_end
    result = simulate_stos(plant, law, distance, Ts, t_end)
    m = result.metrics
    lines = [f"STOS on plant {plant.name}: move of {distance:g} with |u| <= {law.U:g}, Ts = {Ts:g} s, "
             f"{shaper} shaper of {len(law.shaper)} impulses, length {law.shaper.duration:.6g} s"]
    if abs(distance) < law.min_distance:
        lines.append(f"note: |X| < {law.min_distance:.4g}: the bang-bang pulses are shorter than the shaper "
                     "(outside the paper's assumption; the settle controller does most of the move)")
    ratios = ", ".join(f"{r / q:.3e}" for r, q in zip(m.residual_vibration, rigid_residual))
    lines += [f"move time (|x_r - X| <= {m.tolerance:g} |X|): {m.move_time:.8g} s; rigid time-optimal {rigid_T:.8g} s "
              f"+ shaper + 2 Ts = {rigid_T + law.shaper.duration + 2 * Ts:.8g} s",
              "residual vibration per mode (max |x_f| after the hand-over): "
              + ", ".join(f"{r:.3e}" for r in m.residual_vibration) + f"; / unshaped rigid bang-bang: {ratios}",
              f"hand-over to the settle controller at {m.handover_time:.6g} s; peak |u| {m.peak_u:.4g}; "
              f"chattering {m.chattering} sign changes in the last quarter; final error {m.final_error:.2e} |X|"]
    if plot is not None:
        plot_stos({f"STOS, {shaper} shaper": result}, plot)
        lines.append(f"plot written to {plot}")
    return "\n".join(lines)
