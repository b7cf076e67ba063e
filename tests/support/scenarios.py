"""The inputs the EKF tuner and STOS controller FMUs are driven with, pythonfmu and native alike.

    EKF tuner (paper 001's case, EKF_STARTS): a noisy 10 Hz ring-down watched at 1 kHz
        ekf_signals(count, seed) -> [{"u": ..., "vibration": ...}] per sample
        drive_ekf(slave, vr, inputs, start) -> rows of EKF_OUTPUTS, steps of Ts from sample ``start``
        ekf_state_replays(fmu, inputs, at) -> the rows from sample ``at`` on: run on, replayed from the
            state saved there, and replayed in a fresh instance from the serialised state
    STOS controller (paper 002's disk drive, STOS_STARTS) closing the loop around the rigid body x'' = b u
        plant_step(x, v, u, h) -> (x, v) after h with u held (exact)
        stos_loop(slave, vr, count, state, start) -> (controls, (x, v)): u read after each measurement
        recorded_measurements(fmu, count) -> the measurements of ``fmu``'s closed loop, one {input: value}
            per sample, to replay open loop in any host
"""

from __future__ import annotations

import math

import numpy as np

from support.fixtures_fmi import EKF_STARTS, STOS_STARTS
from support.fmpy_slaves import initialised

EKF_OUTPUTS = ["y", "omega_est", "zeta_est", "converged"]
OMEGA, ZETA = 2 * math.pi * 10.0, 0.02  # the ring-down the tuner watches (paper 001: 10 Hz)
B, U, TS = STOS_STARTS["b"], STOS_STARTS["U"], STOS_STARTS["Ts"]
TARGET = 1e-3
# A hand-over region the loop enters (x within 2 um, v within 0.2 m/s), gains that keep the linear
# law within U there.
SETTLE = {"kp": 2.75e6, "kd": 27.5, "ki": 1e8, "x_enter": 2e-6, "v_enter": 0.2, "x_exit": 4e-6, "v_exit": 0.4}


def ekf_signals(count: int, seed: int = 0) -> list[dict]:
    """A noisy 10 Hz ring-down and a command that moves, rests, and moves again, at Ts."""
    rng = np.random.default_rng(seed)
    t = np.arange(count) * EKF_STARTS["Ts"]
    sigma, omega_d = ZETA * OMEGA, OMEGA * math.sqrt(1 - ZETA**2)
    vibration = np.exp(-sigma * t) * np.sin(omega_d * t) + 0.01 * rng.normal(size=count)
    command = np.where((t > 0.05) & (t < 0.3), 1.0, 0.0) + np.where(t > 1.5, 2.0, 0.0)
    return [{"u": float(u), "vibration": float(v)} for u, v in zip(command, vibration)]


def drive_ekf(slave, vr, inputs, start: int) -> list[list[float]]:
    """Steps ``start``, ``start + 1``, ... of Ts with ``inputs``: the outputs after each."""
    h = EKF_STARTS["Ts"]
    rows = []
    for k, values in enumerate(inputs, start=start):
        slave.setReal([vr["u"], vr["vibration"]], [values["u"], values["vibration"]])
        slave.doStep(k * h, h)
        rows.append(slave.getReal([vr[name] for name in EKF_OUTPUTS]))
    return rows


def ekf_state_replays(fmu, inputs, at: int) -> tuple[list, list, list]:
    """(first, again, restored): the rows from sample ``at`` on after the FMU state is taken there,
    after it is set back, and in a fresh instance from its serialised copy."""
    slave, vr = initialised(fmu)
    drive_ekf(slave, vr, inputs[:at], 0)
    state = slave.getFMUState()
    raw = slave.serializeFMUState(state)
    first = drive_ekf(slave, vr, inputs[at:], at)
    slave.setFMUState(state)
    again = drive_ekf(slave, vr, inputs[at:], at)
    slave.freeInstance()
    fresh, vr = initialised(fmu)
    fresh.setFMUState(fresh.deserializeFMUState(raw))
    restored = drive_ekf(fresh, vr, inputs[at:], at)
    fresh.freeInstance()
    return first, again, restored


def plant_step(x: float, v: float, u: float, h: float = TS) -> tuple[float, float]:
    """The rigid body x'' = b u over h with u held: exact."""
    return x + v * h + 0.5 * B * u * h * h, v + B * u * h


def stos_loop(slave, vr, count: int, state=(0.0, 0.0), start: int = 0):
    """(controls, (x, v)): ``count`` samples of the closed loop from sample ``start`` and ``state``;
    u is read right after the measurement is set (it feeds through), then the FMU steps."""
    x, v = state
    controls = []
    for k in range(start, start + count):
        slave.setReal([vr["target"], vr["x_r"], vr["x_r_dot"]], [TARGET, x, v])
        (u,) = slave.getReal([vr["u"]])
        controls.append(u)
        slave.doStep(k * TS, TS)
        x, v = plant_step(x, v, u)
    return controls, (x, v)


def recorded_measurements(fmu, count: int) -> list[dict]:
    """The inputs (target, x_r, x_r_dot) ``fmu`` sees in ``count`` samples of the closed loop."""
    slave, vr = initialised(fmu)
    x = v = 0.0
    inputs = []
    for k in range(count):
        inputs.append({"target": TARGET, "x_r": x, "x_r_dot": v})
        slave.setReal([vr["target"], vr["x_r"], vr["x_r_dot"]], [TARGET, x, v])
        x, v = plant_step(x, v, slave.getReal([vr["u"]])[0])
        slave.doStep(k * TS, TS)
    slave.freeInstance()
    return inputs
