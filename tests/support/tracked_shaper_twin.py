"""The TrackedShaper's native C twin in the twin contract (tests/test_native_twin_contract.py; support/twins.py
says what a Twin declares): a printer bed's 30 Hz mode watched during its moves from a guess 10 % off.

The inputs are open loop: the command is a move (+1 for 40 ms, then -1, every 0.4 s) and the
measurement the bed's accelerometer under that command unshaped, in closed form (``bed_acceleration``),
plus noise. A run shows that the FMU was exercised when the shaper's f left the guess for 30 Hz.
"""

from __future__ import annotations

import math

import numpy as np

from support.twins import CHost, Platforms, Run, Twin, random_times, steps_of

BED_HZ, BED_ZETA = 30.0, 0.03
MOVES = ((0.05, 1.0), (0.09, -2.0), (0.13, 1.0))  # (time in the move, change of the drive's acceleration)
PERIOD = 0.4  # s between moves
H = 1e-3


def command(t: np.ndarray) -> np.ndarray:
    into = np.mod(t, PERIOD)
    return np.where((into >= 0.05) & (into < 0.09), 1.0, np.where((into >= 0.09) & (into < 0.13), -1.0, 0.0))


def bed_acceleration(t: np.ndarray) -> np.ndarray:
    """The bed's acceleration under ``command``: a mass on a spring and damper (omega, zeta) riding a
    drive whose acceleration changes by da at t_j moves, after it, by da (1 - exp(-sigma tau)
    (cos(omega_d tau) - sigma / omega_d sin(omega_d tau))), tau = t - t_j: the derivative of the
    mass's step response (its impulse response times omega^2 / omega_d, differentiated once more)."""
    omega = 2.0 * math.pi * BED_HZ
    sigma, omega_d = BED_ZETA * omega, omega * math.sqrt(1.0 - BED_ZETA**2)
    total = np.zeros_like(t)
    for start in np.arange(0.0, float(np.max(t)) + PERIOD, PERIOD):
        for at, change in MOVES:
            tau = t - start - at
            ring = 1.0 - np.exp(-sigma * tau) * (np.cos(omega_d * tau) - sigma / omega_d * np.sin(omega_d * tau))
            total += np.where(tau >= 0.0, change * ring, 0.0)
    return total


def _bed(seed: int):
    """The inputs at each communication point: the move and the bed's accelerometer with 1 % noise."""
    def inputs(pair, times):
        t = np.asarray(times[:-1], dtype=float)
        noise = 0.01 * np.random.default_rng(seed).standard_normal(t.size)
        return [{"u": float(u), "measurement": float(m)} for u, m in zip(command(t), bed_acceleration(t) + noise)]

    return inputs


def _tracked_to_30_hz(rows) -> None:
    assert abs(rows[-1][1] - BED_HZ) < 0.3  # f, read after the last step: the guess left for the mode


def _f_moved(rows) -> None:
    assert np.ptp(np.asarray(rows)[:, 1]) > 1.0


def _shaped_in_the_host(host_rows) -> None:
    """fmi2_host's rows (t, u, measurement, y, f, zeta)."""
    assert np.ptp(host_rows[:, 3]) > 0.5


class TrackedShaperTwin(Twin):
    """ZV from 27 Hz at 1 kHz and ZVD from 33 Hz at 2 kHz; rows are read before and after each step (y,
    f and zeta feed through from both inputs). The arithmetic is the same but for hypot (CPython's own
    against the C library's), so the rows are held to 1e-12 of each output's scale."""

    model = "TrackedShaper"
    outputs = ("y", "f", "zeta")
    exact = False
    read_before = True
    host_step = H
    CASES = {"zv": {"f0": 27.0, "Ts": H}, "zvd": {"kind": "zvd", "f0": 33.0, "zeta0": 0.02, "Ts": H / 2}}
    # three moves: the first shaped for the guess, the EKF has the mode by the second
    steps_of_ts = (Run("zv", steps_of(H, 1200), _bed(0), check=_tracked_to_30_hz),
                   Run("zvd", steps_of(H / 2, 2400), _bed(1), check=_tracked_to_30_hz))
    hosts = Run("zv", steps_of(H, 600), _bed(2))
    # steps of 0.3 to 2.5 Ts, one in thirteen of 1e-12 s
    random = (Run("zv", random_times(7, 1500, lambda rng, n: rng.choice([0.3, 0.5, 1.0, 1.7, 2.5], size=n) * H, 13,
                                     1e-12), _bed(5), check=_f_moved),)
    changes = (Run("zv", steps_of(H, 1600), _bed(3), check=_f_moved,
                   parameters={"kind": "mzv", "f0": 33.0, "Ts": 2e-3 / 3, "resolution": 0.0, "drift": 3e-3}),
               Run("zvd", steps_of(H, 1600), _bed(4), check=_f_moved,
                   parameters={"kind": "zv_dn", "n": 2, "Ts": H, "zeta0": 0.0, "band_low": 0.8, "omega_tol": 2e-2}))
    # random steps (a third onto the grid), the host's 20 Hz sines plus a square wave as both inputs
    c_host = CHost("zv", ("--random", 11, 1e-9 * H, 7.3 * H, 3000, H, "--period", 50 * H), _shaped_in_the_host)
    # the host drives the command with its own sequence (the measurement left at 0)
    platforms = (Platforms("zv", lambda vr: f"input {vr['u']} 1\n"
                           + "".join(f"output {vr[name]}\n" for name in TrackedShaperTwin.outputs) + "run 600 0.001\n",
                           lambda rows: rows.shape == (600, 3) and np.ptp(rows[:, 0]) > 0.5),)
    valgrind = ("zv", "valgrind_tracked_shaper")

    def starts(self, case):
        return self.CASES[case]


TRACKED_SHAPER = TrackedShaperTwin()
