"""Paper 004 (Zhou & Misawa) through FMUs: the time-frequency localised seek on a disk drive.

The ProfileGenerator FMU designs the seek at initialisation (``profile = time-frequency``: first
resonance Omega_0 = 9.68e3 rad/s, Ts = 2e-5 s, move time 2.5 ms, 100 tracks; the scale n optimal
by eq. 20) and plays its acceleration into the disk-drive plant FMU of models/disk_drive.toml
(paper 002's modes at 2.0 and 3.0 kHz, zeta = 0.01, both above Omega_0 = 1.54 kHz) through the SSP
linear transformation voltage = acceleration / b2, run by the master (Jacobi, step Ts). The paper's
plant is a 28th-order model we do not have: Omega_0 is taken as the lowest frequency to protect,
and the profile has to spare every mode above it.

What is read back from the FMU path, beside examples/time_frequency.py's design layer and the
paper (n = 11.41, 1 - J about 1e-5; the 100-track seek settles within +-5 % track at 2.6 ms):

- n, identified from the recorded acceleration: a_k = -K t_k exp(-4^n t_k^2 / 2) with
  t_k = (k - M/2) Ts (eq. 12, 15), so ln(a_k / -t_k) is linear in t_k^2 with slope -4^n / 2;
- 1 - J of the recorded acceleration (eq. 18-19) by numerical quadrature of its spectrum
  (``analysis.spectrum``), independent of the design layer's closed form;
- the residual vibration (largest |deflection_i| after the acceleration ends, in tracks, over 2 ms
  = four periods of the 2 kHz mode) and the settling time (every coordinate within 5 % track of
  its final value from then on), beside a rigid-body bang-bang of the same duration from the same
  FMU (``profile = bang-bang``) and the design layer's exact simulation of the design's
  acceleration on the same plant (``optimal.simulate``). The bang-bang lasts as many samples as
  the seek (126, 2.52 ms; an even number puts its switch on a sample: the generator's outputs are
  point values, and an off-grid switch would hand the plant a whole sample of the wrong sign).

A mode sitting exactly at Omega_0 is not spared: eq. (20) minimises the energy above Omega_0, and
|A(Omega_0)| is still on the edge of the main lobe. ``run`` also moves the plant's first mode onto
Omega_0 (its tunable ``f[1]``) to show that.

Writes results/paper004_time_frequency_fmu.png (Fig. 8 and Fig. 10 equivalents).

    .venv/bin/python examples/paper004_time_frequency_fmu.py
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy.integrate import simpson  # noqa: E402

from shapefmu.analysis import spectrum  # noqa: E402
from shapefmu.cosim import Master  # noqa: E402
from shapefmu.fmi import build_fmu  # noqa: E402
from shapefmu.fmi.native import build_plant_fmu  # noqa: E402
from shapefmu.fmi.ssp import System  # noqa: E402
from shapefmu.optimal import Command, simulate  # noqa: E402
from shapefmu.plants import library  # noqa: E402
from shapefmu.shapers.time_frequency import time_frequency_profile  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results"
MODEL = ROOT / "models" / "disk_drive.toml"
OMEGA_0, TS, MOVE, TRACKS = 9.68e3, 2e-5, 2.5e-3, 100.0
WINDOW = 2e-3  # s after the move: four periods of the 2 kHz mode
BAND = 0.05  # tracks: the paper's +-5 % track
PAPER = {"n": 11.41, "leakage": 1e-5, "settle": 2.6e-3}
B2 = library.DISK_DRIVE_B2
MODES_HZ = library.DISK_DRIVE_MODES_HZ
RECORD = ["profile.acceleration", "plant.position", "plant.deflection_1", "plant.deflection_2"]


def build(folder, have=None) -> dict[str, Path]:
    """The ProfileGenerator FMU and the disk-drive plant FMU (those not in ``have``), into ``folder``."""
    folder, fmus = Path(folder), dict(have or {})
    if "profile" not in fmus:
        fmus["profile"] = build_fmu("ProfileGenerator", folder / "ProfileGenerator.fmu")
    if "plant" not in fmus:
        fmus["plant"] = build_plant_fmu(MODEL, folder / "DiskDrive.fmu")
    return fmus


def system(fmus) -> System:
    profile = {"profile": "time-frequency", "omega_n": OMEGA_0, "Ts": TS, "move_time": MOVE, "distance": TRACKS,
               "t_start": 0.0}
    return (System("time_frequency_seek")
            .add("profile", fmus["profile"], profile)
            .add("plant", fmus["plant"])
            .connect("profile.acceleration", "plant.voltage", factor=1.0 / B2))


def identified_scale(acceleration) -> float:
    """n from the samples a_k = -K t_k exp(-4^n t_k^2 / 2) (module docstring), least squares."""
    m = acceleration.size - 1
    t = (np.arange(m + 1) - m / 2.0) * TS
    use = t != 0.0
    slope = np.polyfit(t[use] ** 2, np.log(acceleration[use] / -t[use]), 1)[0]
    return math.log2(-2.0 * slope) / 2.0


def leakage_by_quadrature(samples) -> float:
    """1 - J (eq. 19): the share of the energy of |G(omega)|^2 on (omega_0, pi], omega in rad/sample."""
    omega_0 = OMEGA_0 * TS
    g = (np.arange(samples.size), samples)
    inside = np.linspace(0.0, omega_0, 40001)
    outside = np.linspace(omega_0, math.pi, 40001)
    above = simpson(np.abs(spectrum(g, outside)) ** 2, x=outside)
    return above / (above + simpson(np.abs(spectrum(g, inside)) ** 2, x=inside))


def move_measures(t, position, deflections, move_end) -> dict:
    """Settling time (every coordinate within BAND of its final value from then on, ``inf`` if not
    by the end of the record) and the
    residual vibration (largest |deflection| from the move's end over WINDOW)."""
    errors = np.max(np.abs(np.vstack([position - TRACKS, *deflections])), axis=0)
    outside = np.flatnonzero(errors > BAND)
    if not outside.size:
        settle = float(t[0])
    else:
        settle = float(t[outside[-1] + 1]) if outside[-1] + 1 < t.size else math.inf  # inf: not within the record
    window = (t >= move_end - 1e-12) & (t <= move_end + WINDOW + 1e-12)
    return {"settle": settle, "residual": float(max(np.max(np.abs(d[window])) for d in deflections))}


def design_layer_run(acceleration, t) -> np.ndarray:
    """The design layer's exact simulation of a held acceleration on the same plant: deflections at t."""
    plant = library.rigid_flexible(B2, [(2 * math.pi * f, library.DISK_DRIVE_ZETA, -B2) for f in MODES_HZ])
    breaks = tuple(np.arange(acceleration.size + 1) * TS)
    _, states = simulate(plant, Command(breaks, tuple(acceleration / B2)), t=t)
    return states[:, 2::2].T


def run(fmus=None) -> dict:
    """The seek and its bang-bang contrast through the FMUs, beside the design layer."""
    design = time_frequency_profile(OMEGA_0, TS, MOVE, distance=TRACKS)
    samples = design.profile.acceleration.size - 1  # the held samples k = 0..M
    move_end = samples * TS
    stop = move_end + WINDOW
    with tempfile.TemporaryDirectory(prefix="paper004_") as folder:
        fmus = build(folder, fmus)
        with Master(system(fmus), TS, algorithm="jacobi", record=RECORD) as master:
            seek = master.run(stop)
            on_omega_0 = master.run(stop, parameters={"plant.f[1]": OMEGA_0 / (2 * math.pi)})
            # A rigid-body bang-bang over the distance in an even number of samples: a = 4 d / T^2.
            bang_end = 2 * math.ceil(samples / 2) * TS
            bang = master.run(stop, parameters={"profile.profile": "bang-bang", "profile.speed": 0.0,
                                                "profile.acceleration_limit": 4 * TRACKS / bang_end**2})
    t = seek["time"]
    acceleration = seek["profile.acceleration"][:samples]
    deflections = [seek["plant.deflection_1"], seek["plant.deflection_2"]]
    exact = design_layer_run(design.profile.acceleration[:samples], t)
    return {
        "fmu_n": identified_scale(acceleration), "design_n": design.n,
        "fmu_leakage": leakage_by_quadrature(acceleration), "design_leakage": design.leakage,
        "fmu_acceleration_deviation": float(np.max(np.abs(acceleration - design.profile.acceleration[:samples]))),
        "largest_acceleration": float(np.max(np.abs(acceleration))),
        "seek": move_measures(t, seek["plant.position"], deflections, move_end),
        "design_seek": move_measures(t, seek["plant.position"], exact, move_end),
        "deflection_deviation": float(np.max(np.abs(np.array(deflections) - exact))),
        "bang_bang": move_measures(t, bang["plant.position"], [bang["plant.deflection_1"], bang["plant.deflection_2"]],
                                   bang_end),
        "bang_bang_end": bang_end, "bang_bang_final_position": float(bang["plant.position"][-1]),
        "mode_on_omega_0": move_measures(
            t, on_omega_0["plant.position"], [on_omega_0["plant.deflection_1"], on_omega_0["plant.deflection_2"]],
            move_end),
        "move_end": move_end, "records": {"time-frequency": seek, "bang-bang": bang},
    }


def main():
    r = run()
    print(f"ProfileGenerator FMU (time-frequency, Omega_0 = {OMEGA_0:g} rad/s, Ts = {TS:g} s, move {MOVE * 1e3:g} ms, "
          f"{TRACKS:g} tracks) -> disk-drive plant FMU (modes {MODES_HZ[0]:.1f} Hz, {MODES_HZ[1]:.0f} Hz)")
    print(f"{'':<34} {'FMUs':>11} {'design layer':>13} {'paper':>9}")
    print(f"{'scale n':<34} {r['fmu_n']:11.4f} {r['design_n']:13.4f} {PAPER['n']:9.2f}")
    print(f"{'1 - J':<34} {r['fmu_leakage']:11.3e} {r['design_leakage']:13.3e} {PAPER['leakage']:9.0e}")
    print(f"{'settled within 5 % track [ms]':<34} {1e3 * r['seek']['settle']:11.3f} "
          f"{1e3 * r['design_seek']['settle']:13.3f} "
          f"{1e3 * PAPER['settle']:9.2f}")
    print(f"{'residual vibration [tracks]':<34} {r['seek']['residual']:11.3e} {r['design_seek']['residual']:13.3e} "
          f"{'-':>9}")
    bb = r["bang_bang"]
    print(f"bang-bang over {1e3 * r['bang_bang_end']:.2f} ms (same FMU): settled at {1e3 * bb['settle']:.3f} ms, "
          f"residual vibration {bb['residual']:.3e} tracks ({bb['residual'] / r['seek']['residual']:.0f} x the "
          f"time-frequency seek's), final position {r['bang_bang_final_position']:.6f}")
    on = r["mode_on_omega_0"]
    print(f"first mode moved onto Omega_0 ({OMEGA_0 / (2 * math.pi):.1f} Hz): residual vibration {on['residual']:.3e} "
          f"tracks (eq. 20 spares the modes above Omega_0, not one at it)")
    print(f"FMU acceleration vs design samples: largest difference {r['fmu_acceleration_deviation']:.1e} "
          f"(of {r['largest_acceleration']:.3e}); deflections vs the design layer's exact run: "
          f"{r['deflection_deviation']:.1e}")

    RESULTS.mkdir(exist_ok=True)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    for name, record in r["records"].items():
        ms = record["time"] * 1e3
        axes[0].step(ms, record["profile.acceleration"], where="post", lw=0.9, label=name)
        head = record["plant.position"] + record["plant.deflection_1"] + record["plant.deflection_2"]
        axes[1].plot(ms, head - TRACKS, lw=0.9, label=name)
    axes[0].set(title="Fig. 8: acceleration of the 100-track seek (ProfileGenerator FMU)", xlabel="t [ms]",
                ylabel="tracks/s^2")
    axes[1].axhspan(-BAND, BAND, color="0.85", label="+-5 % track")
    axes[1].set(title="Fig. 10: near the target (rigid + modal coordinates)", xlabel="t [ms]",
                ylabel="position - 100 [tracks]", ylim=(-0.5, 0.5), xlim=(1.5, 1e3 * (r["move_end"] + WINDOW)))
    for ax in axes:
        ax.legend(fontsize=8)
    fig.tight_layout()
    path = RESULTS / "paper004_time_frequency_fmu.png"
    fig.savefig(path, dpi=120)
    print(f"figure: {path}")


if __name__ == "__main__":
    main()
