"""Paper 003 (Bowling, Starr, Wood & Lumia) through FMUs: classic twin pulse vs M-BC:TZ:TP on ten pendula.

The ProfileGenerator FMU plays the move (notch 3.5 rad/s, 1.7 m at a desired 0.7 m/s; M-BC:TZ:TP
mis-aligned by delta_omega = 0.05 rad/s; the classic TP's pulses one kernel sample, 1 ms, wide as in
examples/ten_pendula.py) into the ten-pendula plant FMU generated from models/ten_pendula.toml,
run by the co-simulation master. The ten pendula are a sweep (``shapefmu.sweep`` on a Dask
``LocalCluster``): one run per pendulum, varying ``plant.lengths[1]`` over the lengths whose
natural frequencies are those of examples/ten_pendula.py (evenly spaced over 3.36-3.66 rad/s with
g = 9.81 m/s^2), the residual swing being the sweep's ``residual`` metric (largest |theta| from the
end of the commanded acceleration on, over 2 s, longer than the slowest pendulum's period).

Sampling. The generator's outputs are the exact continuous move at each communication point, held
by the plant over the master's step H = 0.25 ms (a quarter of the kernel sample). A pendulum's swing
amplitude is |A(omega)| omega / g, A the spectrum of the cart acceleration, and holding point
values moves each acceleration break b_i (jump J_i) to the next communication point, b_i + delta_i
with delta_i < H, which changes A(omega) by at most |J_i| delta_i: the FMU path's swing is within
(omega / g) H sum_i |J_i| of the continuous move's (``sampling_bound``). When every segment of the
move is a whole number of steps long, as the classic TP's 1 ms pulses (four steps each), each
segment of area S_i moves rigidly by delta_i < H and the bound tightens to (omega^2 / g) H sum |S_i|:
4 * 0.35 * 3.66^2 / 9.81 * H = 4.8e-4 rad = 0.027 deg. The design layer's sampled profile (each
pulse integrated over its samples) is itself within a few 1e-5 deg of the continuous move
(``TwinPulseProfile.residual_swing``). Paper: 0.374 deg vs 0.012 deg (97 %);
examples/ten_pendula.py's 1 ms pulses give a larger classic swing than the paper's (its pulse
width is unstated; ``tests/test_twin_pulse.py`` notes ~1.45 s pulses reproduce 0.374 deg).

Writes results/paper003_ten_pendula_fmu.png (swing of each pendulum, FMU sweep beside the design
layer) and results/paper003_ten_pendula_fmu.csv (the sweep's rows).

    .venv/bin/python examples/paper003_ten_pendula_fmu.py
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import ten_pendula as design_example  # noqa: E402  (examples/ten_pendula.py: the design layer's numbers)

from shapefmu import sweep  # noqa: E402
from shapefmu.fmi import build_fmu  # noqa: E402
from shapefmu.fmi.native import build_plant_fmu  # noqa: E402
from shapefmu.fmi.ssp import System  # noqa: E402
from shapefmu.plants.library import INCH  # noqa: E402
from shapefmu.runtime.twin_pulse import twin_pulse_profile  # noqa: E402
from shapefmu.shapers.twin_pulse import m_bc_tz_tp, tp  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results"
MODEL = ROOT / "models" / "ten_pendula.toml"
NOTCH, DISTANCE, SPEED, DELTA_OMEGA, KERNEL_TS = 3.5, 1.7, 0.7, 0.05, 1e-3
STEP = KERNEL_TS / 4  # master step: four held samples per 1 ms pulse (module docstring)
WINDOW = 2.0  # s of free swing after the move, longer than the slowest period 2 pi / 3.36
GRAVITY = design_example.GRAVITY
PENDULA = design_example.PENDULA  # rad/s
PROFILES = {
    "classic twin pulse": {"profile": "TP"},
    "M-BC:TZ:TP": {"profile": "M-BC:TZ:TP", "delta_omega": DELTA_OMEGA, "attenuation": 0.0},
}
PAPER_DEG = {"classic twin pulse": 0.374, "M-BC:TZ:TP": 0.012}
SWING = sweep.residual("plant.theta_1", command="profile.acceleration", name="swing")


def design_layer():
    """The designs of examples/ten_pendula.py (1 ms samples)."""
    return {"classic twin pulse": tp(NOTCH, DISTANCE, SPEED, ts=KERNEL_TS),
            "M-BC:TZ:TP": m_bc_tz_tp(NOTCH, DISTANCE, SPEED, delta_omega=DELTA_OMEGA, ts=KERNEL_TS)}


def sampling_bound(name: str, omega) -> np.ndarray:
    """Largest difference (rad) between the FMU path's swing and the continuous move's, at the
    natural frequencies ``omega`` (module docstring), from the move the generator plays."""
    options = {k: v for k, v in PROFILES[name].items() if k == "delta_omega"}
    motion = twin_pulse_profile(PROFILES[name]["profile"], NOTCH, DISTANCE, SPEED, ts=KERNEL_TS, **options).motion
    widths, levels = np.diff(motion.breaks), np.array(motion.levels)
    steps = widths / STEP
    omega = np.asarray(omega, dtype=float)
    if np.all(np.abs(steps - np.round(steps))[levels != 0.0] < 1e-6):
        return omega**2 / GRAVITY * STEP * np.sum(np.abs(levels * widths))
    return omega / GRAVITY * STEP * np.sum(np.abs(np.diff(np.concatenate([[0.0], levels, [0.0]]))))


def build(folder) -> dict[str, Path]:
    """The ProfileGenerator FMU and the ten-pendula plant FMU, built into ``folder``."""
    folder = Path(folder)
    return {"profile": build_fmu("ProfileGenerator", folder / "ProfileGenerator.fmu", Ts=KERNEL_TS),
            "plant": build_plant_fmu(MODEL, folder / "TenPendula.fmu")}


def pendulum_lengths_in() -> np.ndarray:
    """Lengths (in, the model file's unit) of pendula with the design example's frequencies."""
    return GRAVITY / PENDULA**2 / INCH


def system(fmus, profile: dict) -> System:
    starts = {"distance": DISTANCE, "speed": SPEED, "omega_n": NOTCH, "Ts": KERNEL_TS, "t_start": 0.0, **profile}
    return (System("ten_pendula_move")
            .add("profile", fmus["profile"], starts)
            .add("plant", fmus["plant"], {"g": GRAVITY})
            .connect("profile.acceleration", "plant.acceleration"))


def run(fmus=None, client=None) -> dict:
    """Sweep both moves over the ten pendula through the FMUs; returns, per move, the FMU path's
    swing of each pendulum (deg), the design layer's, and the sweep's rows."""
    with tempfile.TemporaryDirectory(prefix="paper003_") as folder:
        fmus = fmus or build(folder)
        designs = design_layer()
        opened = None
        if client is None:
            from distributed import Client, LocalCluster

            opened = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0")
            client = Client(opened)
        try:
            results = {}
            points = sweep.grid(("plant.lengths[1]", pendulum_lengths_in()))
            for name, profile in PROFILES.items():
                stop = designs[name].duration + WINDOW
                target = sweep.cosim(system(fmus, profile), step=STEP, stop_time=stop, algorithm="jacobi",
                                     record=["profile.acceleration", "plant.theta_1"])
                rows = sweep.sweep(target, points, metrics=[SWING], client=client, progress=False)
                bad = rows[rows["status"] != "ok"]
                if bad.size:
                    raise RuntimeError(f"{name}: {bad.size} runs failed, first: {bad['error'][0]}")
                design_deg = np.array([design_example.swing(designs[name].profile, w)[2] for w in PENDULA])
                results[name] = {"fmu_deg": np.degrees(rows["swing"]), "design_deg": design_deg, "rows": rows,
                                 "continuous_deg": np.degrees(designs[name].residual_swing(PENDULA, GRAVITY)),
                                 "bound_deg": np.degrees(sampling_bound(name, PENDULA))}
        finally:
            if opened is not None:
                client.close()
                opened.close()
    return results


def main():
    results = run()
    print(f"ten pendula, {len(PENDULA)} runs per move (shapefmu.sweep on a LocalCluster), "
          f"master step {STEP * 1e3:g} ms")
    print(f"{'move':<20} {'FMU max [deg]':>14} {'design [deg]':>13} {'paper [deg]':>12} {'max |FMU - design|':>19} "
          f"{'sampling bound':>15}")
    for name, r in results.items():
        print(f"{name:<20} {r['fmu_deg'].max():14.4f} {r['design_deg'].max():13.4f} {PAPER_DEG[name]:12.3f} "
              f"{np.max(np.abs(r['fmu_deg'] - r['design_deg'])):19.2e} {r['bound_deg'].max():15.2e}")
    fmu = {n: r["fmu_deg"].max() for n, r in results.items()}
    design = {n: r["design_deg"].max() for n, r in results.items()}
    print(f"reduction: FMU {100 * (1 - fmu['M-BC:TZ:TP'] / fmu['classic twin pulse']):.1f} %, design layer "
          f"{100 * (1 - design['M-BC:TZ:TP'] / design['classic twin pulse']):.1f} %, paper 97 %")

    RESULTS.mkdir(exist_ok=True)
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for (name, r), color in zip(results.items(), ("tab:blue", "tab:red")):
        ax.semilogy(PENDULA, r["design_deg"], "-", color=color, lw=1.0, label=f"{name}, design layer")
        ax.semilogy(PENDULA, r["fmu_deg"], "o", color=color, mfc="none", label=f"{name}, FMU sweep")
        ax.axhline(PAPER_DEG[name], color=color, ls=":", lw=0.8, label=f"{name}, paper (max)")
    ax.set(xlabel="pendulum natural frequency [rad/s]", ylabel="residual swing [deg]",
           title="Paper 003, Fig. 15: residual swing of the ten pendula, ProfileGenerator FMU -> plant FMU")
    ax.legend(fontsize=8)
    fig.tight_layout()
    figure = RESULTS / "paper003_ten_pendula_fmu.png"
    fig.savefig(figure, dpi=120)
    table = RESULTS / "paper003_ten_pendula_fmu.csv"
    lines = ["move,omega_rad_s,length_in,fmu_swing_deg,design_swing_deg"]
    for name, r in results.items():
        for w, row, f, d in zip(PENDULA, r["rows"], r["fmu_deg"], r["design_deg"]):
            lines.append(f"{name},{w:.6f},{row['plant.lengths[1]']:.6f},{f:.8g},{d:.8g}")
    table.write_text("\n".join(lines) + "\n")
    print(f"figure: {figure}\nsweep rows: {table}")


if __name__ == "__main__":
    main()
