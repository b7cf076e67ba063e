"""Resonance EKF: speed against filterpy, accuracy against the Cramer-Rao lower bound, in one run.

(a) Microseconds per EKF step of the runtime kernel (pure Python, written out for 4x4) beside
    filterpy's ``ExtendedKalmanFilter`` running the same model (eq. 24 transition, its Jacobian,
    the measurement H = [1, 0, 0, 0]) on the same samples; filterpy is the ``bench`` extra. And the
    native EKFTuner FMU's step through the C loop of benchmarks/fmu_loop.c (set the vibration,
    fmi2DoStep: one EKF step and the tuner's, get the estimate), nanoseconds per sample, with its
    ratio to filterpy (goal: at least 50x).
(b) RMS error of the frequency estimate after N samples over 200 noise seeds beside the
    Cramer-Rao lower bound for a damped sinusoid in white noise, from the Fisher information of
    (A, phi, omega_d, sigma) averaged over the seeds' phases.

    .venv/bin/python benchmarks/ekf.py
"""

import math
import tempfile
import time
from pathlib import Path

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter

from native_loop import c_loop_seconds

from shapefmu.estimation import estimate_mode
from shapefmu.fmi.native.ekf_tuner import build_native_ekf_tuner
from shapefmu.runtime.ekf import ResonanceEKF, default_tuning

F_HZ, ZETA, SPP, PERIODS, SNR_DB, SEEDS = 10.0, 0.02, 50, 5, 20.0, 200
OMEGA_N = 2 * math.pi * F_HZ
OMEGA_D, SIGMA = OMEGA_N * math.sqrt(1 - ZETA**2), ZETA * OMEGA_N
FS = SPP * OMEGA_D / (2 * math.pi)
NOISE = math.sqrt(0.5 / 10 ** (SNR_DB / 10))


def signal(seed, n):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FS
    phi = rng.uniform(0, 2 * math.pi)
    return np.exp(-SIGMA * t) * np.sin(OMEGA_D * t + phi) + NOISE * rng.normal(size=n), phi


class FilterpyResonance(ExtendedKalmanFilter):
    """filterpy's EKF with eq. (24) as the (nonlinear) state transition."""

    def predict_x(self, u=0):
        x1, x2, w, s = self.x[:, 0]
        e = math.exp(-s / FS)
        c, sn = e * math.cos(w / FS), e * math.sin(w / FS)
        f1, f2 = c * x1 + sn * x2, -sn * x1 + c * x2
        self.F = np.array([[c, sn, f2 / FS, -f1 / FS], [-sn, c, -f1 / FS, -f2 / FS], [0, 0, 1, 0], [0, 0, 0, 1.0]])
        self.x = np.array([[f1], [f2], [w], [s]])


H = np.array([[1.0, 0.0, 0.0, 0.0]])


def run_filterpy(y, omega0):
    p0, q, r = default_tuning(FS, omega0)
    ekf = FilterpyResonance(dim_x=4, dim_z=1)
    ekf.x = np.array([[0.0], [0.0], [omega0], [0.0]])
    ekf.P, ekf.Q, ekf.R = np.diag(p0), np.diag(q), np.array([[r]])
    for z in y:
        # filterpy's predict() propagates P with self.F, which predict_x has just set: eqs. (15)-(16).
        ekf.predict()
        ekf.update(np.array([[z]]), lambda x: H, lambda x: H @ x)
    return float(ekf.x[2, 0])


def run_runtime(y, omega0):
    ekf = ResonanceEKF(FS, omega0)
    for z in y:
        ekf.step(z)
    return ekf.omega_d


def speed():
    y, _ = signal(0, 5000)
    samples = y.tolist()
    start = time.perf_counter()
    ours = run_runtime(samples, 0.8 * OMEGA_D)
    runtime_us = 1e6 * (time.perf_counter() - start) / len(samples)
    start = time.perf_counter()
    theirs = run_filterpy(samples, 0.8 * OMEGA_D)
    filterpy_us = 1e6 * (time.perf_counter() - start) / len(samples)
    print("(a) speed, one EKF step (predict + update), same model, tuning and samples")
    print(f"    runtime kernel {runtime_us:8.2f} us/step   filterpy {filterpy_us:8.2f} us/step"
          f"   filterpy/runtime = {filterpy_us / runtime_us:.1f}")
    print(f"    final omega_d: runtime {ours:.6f}, filterpy {theirs:.6f} rad/s (same filter: difference"
          f" {abs(ours - theirs):.1e})")
    steps = 1_000_000
    with tempfile.TemporaryDirectory() as temp:
        fmu = build_native_ekf_tuner(Path(temp) / "EKFTuner.fmu", Ts=1.0 / FS, omega0=0.8 * OMEGA_D)
        native_ns = min(c_loop_seconds(steps, 1.0 / FS, [(fmu, "vibration", "omega_est")]) for _ in range(5)) / steps * 1e9
    print(f"    native EKFTuner FMU, C loop {native_ns:8.1f} ns/step   filterpy/native = {1e3 * filterpy_us / native_ns:.0f}"
          f"   (goal >= 50)")


def crlb_omega(n, phases):
    t = np.arange(n) / FS
    variance = NOISE**2
    c33 = []
    for phi in phases:
        e = np.exp(-SIGMA * t)
        s, c = e * np.sin(OMEGA_D * t + phi), e * np.cos(OMEGA_D * t + phi)
        G = np.stack([s, c, t * c, -t * s])  # d/dA, d/dphi, d/d omega_d, d/d sigma
        c33.append(np.linalg.inv(G @ G.T / variance)[2, 2])
    return math.sqrt(np.mean(c33))


def accuracy():
    n = PERIODS * SPP + 1
    errors = {1: [], 2: []}
    phases = []
    for seed in range(SEEDS):
        y, phi = signal(seed, n)
        phases.append(phi)
        guess = OMEGA_D * (0.8 if seed % 2 else 1.2)
        for passes in errors:
            errors[passes].append(estimate_mode(y, FS, guess, passes=passes).omega_d - OMEGA_D)
    bound = crlb_omega(n, phases)
    print(f"\n(b) frequency accuracy after N = {n} samples ({PERIODS} periods, {SPP} samples/period),"
          f" zeta = {ZETA}, {SNR_DB:g} dB SNR, guesses +-20 %, {SEEDS} seeds")
    print(f"    Cramer-Rao bound  {bound:.5f} rad/s ({100 * bound / OMEGA_D:.3f} %)")
    for passes, e in errors.items():
        rms = math.sqrt(np.mean(np.square(e)))
        print(f"    EKF, {passes} pass{'es' if passes > 1 else '  '}     {rms:.5f} rad/s ({100 * rms / OMEGA_D:.3f} %)"
              f"   RMS / bound = {rms / bound:.2f}")


if __name__ == "__main__":
    speed()
    accuracy()
