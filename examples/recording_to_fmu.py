"""From a recording of a machine to its shaper FMU (issue 25), on a machine whose modes we know.

A two-mode machine (25 Hz, zeta 0.05 and 62 Hz, zeta 0.08) is recorded as Klipper's TEST_RESONANCES
records it (a 60 s sweep, 3.2 kHz, jittered timestamps, noise) into results/resonances_x.csv. Then,
as a user would: identify the modes, judge every shaper family by Klipper's measures, build the pick
as a native Shaper or ShapeFilter FMU with its .ssv, and co-simulate a move through that FMU in
shapefmu's master, driving a native plant FMU of each of the machine's modes (built from
``synthetic.plant_model``). The machine's response to the shaped and the unshaped move is drawn in
results/recording_to_fmu.png, the spectrum with the pick and Klipper's pick in results/recommendation.png.

    .venv/bin/python examples/recording_to_fmu.py
"""

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from shapefmu.cli import main  # noqa: E402
from shapefmu.cosim.master import simulate  # noqa: E402
from shapefmu.fmi.ssp import System  # noqa: E402
from shapefmu.identification import identify, klipper, recommend  # noqa: E402
from shapefmu.identification import synthetic as syn  # noqa: E402

RESULTS = Path("results")
MACHINE = [syn.SyntheticMode(25.0, 0.05, 0.6), syn.SyntheticMode(62.0, 0.08, 0.4)]


def main_example() -> None:
    RESULTS.mkdir(exist_ok=True)
    recording = RESULTS / "resonances_x.csv"
    t, xyz = syn.record(MACHINE)
    syn.write_klipper_raw(recording, t, xyz)
    print(f"recorded {recording} ({len(t)} samples); the machine: "
          + ", ".join(f"{m.frequency} Hz / zeta {m.zeta}" for m in MACHINE))

    # the command line a user runs: identify, rank, plot, build
    fmu = RESULTS / "MachineShaper.fmu"
    main(["recommend", str(recording), "--axis", "x", "--plot", str(RESULTS / "recommendation.png"),
          "--build", str(fmu)])
    found = identify(recording, axis="x")
    # what the command picked with --build: among the designs an FMU holds, judged as Klipper judges
    pick = recommend(klipper.judged_spectra(found.recording, recording), found.modes.modes, buildable=True).pick

    # the machine as plant FMUs, one per mode; the shaper FMU shapes a unit step (its input held at 1)
    system = System("machine").add("shaper", fmu, parameters={"u": 1.0}, ssv=fmu.with_suffix(".ssv"))
    for i, mode in enumerate(MACHINE):
        model = RESULTS / f"machine_mode{i}.toml"
        model.write_text(syn.plant_model(mode, f"machine_mode{i}"))
        main(["plant", "build", str(model), "-o", str(RESULTS / f"MachineMode{i}.fmu")])
        system.add(f"shaped{i}", RESULTS / f"MachineMode{i}.fmu").connect("shaper.y", f"shaped{i}.position_command")
        system.add(f"unshaped{i}", RESULTS / f"MachineMode{i}.fmu", parameters={"position_command": 1.0})
    result = simulate(system, 0.25, 2e-5)
    time = result["time"]
    after = time > pick.duration
    for i, mode in enumerate(MACHINE):  # the residual of each mode, shaped over unshaped: what "at modes" bounds
        ring = [abs(result[f"{k}{i}.position"] - 1.0)[after].max() for k in ("unshaped", "shaped")]
        # Singer and Seering's percent residual compares with the unshaped vibration at the first
        # impulse, which has decayed by exp(-zeta w D) when the shaped one is measured after the last
        percent = ring[1] / ring[0] * math.exp(-mode.zeta * 2 * math.pi * mode.frequency * pick.duration)
        print(f"mode {mode.frequency} Hz: residual after the shaper, shaped / unshaped {100 * ring[1] / ring[0]:.1f} %, "
              f"as a percent residual {100 * percent:.1f} % (the table's worst case at the modes: "
              f"{100 * pick.at_modes:.1f} %, ours)")

    machine = {k: sum(m.share * result[f"{k}{i}.position"] for i, m in enumerate(MACHINE)) for k in ("unshaped", "shaped")}
    fig, ax = plt.subplots(figsize=(9, 4.5))
    ax.plot(time, result["shaper.y"], "k:", lw=1, label=f"shaped command (FMU, {pick.label})")
    ax.plot(time, machine["unshaped"], label="machine, unshaped step")
    ax.plot(time, machine["shaped"], label="machine, shaped step")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("toolhead position (per unit step)")
    ax.set_title("co-simulated in shapefmu's master: shaper FMU -> plant FMU of each mode")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(RESULTS / "recording_to_fmu.png", dpi=120)
    print(f"plots: {RESULTS / 'recommendation.png'}, {RESULTS / 'recording_to_fmu.png'}")


if __name__ == "__main__":
    main_example()
