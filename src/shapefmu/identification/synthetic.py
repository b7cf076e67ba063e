"""Recordings of known machines, made as the tools of the field make them: the reference the
identification is tested against, and what the example and the benchmark run on.

The machine: the toolhead is carried by the motion system through modes k with natural frequency
f_k, damping zeta_k and share c_k (sum 1). An accelerometer on the toolhead measures

    a(s) = sum_k c_k T_k(s) a_cmd(s),  T_k = (2 zeta_k w_k s + w_k^2) / (s^2 + 2 zeta_k w_k s + w_k^2),

the base-excitation transmissibility of each mode (a belt or a frame spring between the commanded
motion and the toolhead), so the static gain is 1: a slow move is measured as commanded.

Klipper's ``TEST_RESONANCES`` (as its documentation describes it): the commanded acceleration is a
square wave whose frequency rises from ``f_min`` at ``hz_per_sec``, of amplitude ``accel_per_hz`` times
the frequency. The accelerometer samples at ``fs`` with timestamps that jitter; noise is white.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.signal import cont2discrete, lfilter

from shapefmu.identification.recordings import G


@dataclass(frozen=True)
class SyntheticMode:
    frequency: float  # Hz, natural
    zeta: float
    share: float = 1.0


def transmissibility(modes, freq) -> np.ndarray:
    """sum_k c_k T_k(j 2 pi f): the machine's toolhead acceleration per commanded acceleration."""
    s = 2j * np.pi * np.asarray(freq, dtype=float)
    total = np.zeros_like(s)
    for mode in modes:
        w = 2 * np.pi * mode.frequency
        total = total + mode.share * (2 * mode.zeta * w * s + w * w) / (s * s + 2 * mode.zeta * w * s + w * w)
    return total


def plant_model(mode: SyntheticMode, name: str) -> str:
    """A plant model file (``models/*.toml``, kind transfer_function) of one mode of the machine: the
    toolhead position per commanded position, T_k(s) (the share left out), for ``shapefmu plant build``."""
    w = 2 * math.pi * mode.frequency
    return (f'name = "{name}"\nkind = "transfer_function"\n'
            f'description = "one mode of a machine, {mode.frequency:g} Hz, zeta {mode.zeta:g}"\n[parameters]\n'
            f'num = {{ value = [{2 * mode.zeta * w!r}, {w * w!r}], unit = "1" }}\n'
            f'den = {{ value = [1.0, {2 * mode.zeta * w!r}, {w * w!r}], unit = "1" }}\n'
            f'[inputs]\nposition_command = {{ unit = "mm" }}\n[outputs]\nposition = {{ unit = "mm" }}\n')


def klipper_sweep(fs: float, f_min: float = 5.0, f_max: float = 125.0, hz_per_sec: float = 2.0,
                  accel_per_hz: float = 75.0) -> tuple[np.ndarray, np.ndarray]:
    """(t, commanded acceleration in mm/s^2) of a Klipper resonance test sampled at ``fs``."""
    duration = (f_max - f_min) / hz_per_sec
    t = np.arange(int(duration * fs)) / fs
    f = f_min + hz_per_sec * t
    phase = 2 * np.pi * (f_min * t + 0.5 * hz_per_sec * t * t)
    return t, accel_per_hz * f * np.sign(np.sin(phase))


def respond(modes, t: np.ndarray, accel: np.ndarray) -> np.ndarray:
    """The toolhead acceleration of the machine for the commanded ``accel`` on the uniform ``t``
    (each mode discretised exactly for a held input)."""
    dt = t[1] - t[0]
    out = np.zeros_like(accel)
    for mode in modes:
        w = 2 * np.pi * mode.frequency
        b, a, _ = cont2discrete(([2 * mode.zeta * w, w * w], [1.0, 2 * mode.zeta * w, w * w]), dt, method="zoh")
        out += mode.share * lfilter(np.ravel(b), np.ravel(a), accel)
    return out


def record(modes, *, fs: float = 3200.0, f_min: float = 5.0, f_max: float = 125.0, hz_per_sec: float = 2.0,
           noise: float = 50.0, jitter: float = 0.02, cross_talk: float = 0.1, seed: int = 0,
           start: float = 1234.5) -> tuple[np.ndarray, np.ndarray]:
    """(time in s, (N, 3) toolhead acceleration x, y, z in mm/s^2) of a Klipper resonance test of
    the x axis: y sees ``cross_talk`` of it, z gravity; ``noise`` (mm/s^2 rms) on every axis,
    timestamps jittered by ``jitter`` of the sampling interval around an absolute print time."""
    rng = np.random.default_rng(seed)
    oversample = 4
    t_fine, accel = klipper_sweep(fs * oversample, f_min, f_max, hz_per_sec)
    x_fine = respond(modes, t_fine, accel)
    n = int(t_fine[-1] * fs)
    t = np.arange(n) / fs + rng.uniform(-0.5, 0.5, n) * jitter / fs
    t = np.clip(t, 0.0, t_fine[-1])
    x = np.interp(t, t_fine, x_fine)
    xyz = np.column_stack([x, cross_talk * x, np.full(n, G)]) + rng.normal(0.0, noise, (n, 3))
    return start + t, xyz


def write_klipper_raw(path, t, xyz) -> None:
    """A Klipper raw accelerometer CSV (``#time,accel_x,accel_y,accel_z``)."""
    body = np.column_stack([t, xyz])
    np.savetxt(path, body, fmt=["%.6f", "%.3f", "%.3f", "%.3f"], delimiter=",", header="time,accel_x,accel_y,accel_z",
               comments="#")


def write_rrf_m956(path, t, xyz, axes: str = "XYZ") -> None:
    """A RepRapFirmware M956 recording of ``axes``: sample numbers and values in g on the uniform grid
    of the mean rate, and the ``Rate <Hz>, overflows 0`` line."""
    rate = (len(t) - 1) / (t[-1] - t[0])
    grid = t[0] + np.arange(len(t)) / rate
    columns = [np.interp(grid, t, xyz[:, "XYZ".index(a)]) / G for a in axes]
    with open(path, "w") as stream:
        stream.write("Sample," + ",".join(axes) + "\n")
        np.savetxt(stream, np.column_stack([np.arange(len(t)), *columns]), fmt=["%d"] + ["%.6f"] * len(axes),
                   delimiter=",")
        stream.write(f"Rate {rate:.3f}, overflows 0\n")


def write_klipper_spectrum(path, freq, psd_xyz) -> None:
    """A Klipper processed-spectrum CSV (``freq,psd_x,psd_y,psd_z,psd_xyz``) of three axis spectra."""
    psd = np.column_stack([psd_xyz[0], psd_xyz[1], psd_xyz[2], psd_xyz[0] + psd_xyz[1] + psd_xyz[2]])
    np.savetxt(path, np.column_stack([freq, psd]), fmt="%.6e", delimiter=",", header="freq,psd_x,psd_y,psd_z,psd_xyz",
               comments="")


def ring_down(modes, *, fs: float = 3200.0, duration: float = 3.0, noise: float = 0.01, seed: int = 0):
    """(t, y) of a free decay of the modes from a unit push (each mode's impulse response, sampled):
    what a tap on the toolhead records."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration * fs)) / fs
    y = np.zeros_like(t)
    for mode in modes:
        w = 2 * math.pi * mode.frequency
        wd = w * math.sqrt(1 - mode.zeta**2)
        y += mode.share * np.exp(-mode.zeta * w * t) * np.sin(wd * t)
    return t, y + rng.normal(0.0, noise, t.size)
