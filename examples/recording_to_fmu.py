"""From a recording of a machine to its shaper FMU (issue 25), on a machine whose modes we know.

A two-mode machine (25 Hz, zeta 0.05 and 62 Hz, zeta 0.08) is recorded as Klipper's TEST_RESONANCES
records it (a 60 s sweep, 3.2 kHz, jittered timestamps, noise) into results/resonances_x.csv. Then,
as a user would: identify the modes, rank every shaper family on Klipper's metrics, build the pick
as a native Shaper or ShapeFilter FMU with its .ssv, and run a move through that FMU in fmpy; the
machine's response to the shaped and the unshaped move is drawn in results/recording_to_fmu.png,
the spectrum with every candidate in results/recommendation.png.

    .venv/bin/python examples/recording_to_fmu.py
"""

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from fmpy import simulate_fmu  # noqa: E402
from scipy.signal import lsim  # noqa: E402

from shapefmu.cli import main  # noqa: E402
from shapefmu.identification import identify, recommend  # noqa: E402
from shapefmu.identification import synthetic as syn  # noqa: E402

RESULTS = Path("results")
MACHINE = [syn.SyntheticMode(25.0, 0.05, 0.6), syn.SyntheticMode(62.0, 0.08, 0.4)]


def machine_response(t, command):
    """Toolhead position of the machine for a commanded position (each mode's transmissibility)."""
    total = np.zeros_like(command)
    for mode in MACHINE:
        w = 2 * math.pi * mode.frequency
        total += mode.share * lsim(([2 * mode.zeta * w, w * w], [1, 2 * mode.zeta * w, w * w]), command, t)[1]
    return total


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
    advice = recommend([found.spectrum], found.modes.modes)
    step = 5e-5
    stop = 0.3
    moves = np.array([(0.0, 0.0), (0.01, 0.0), (0.03, 1.0), (stop, 1.0)], dtype=[("time", float), ("u", float)])
    result = simulate_fmu(str(fmu), stop_time=stop, step_size=step, output_interval=step, input=moves, output=["y"])
    time = result["time"]
    unshaped = np.interp(time, moves["time"], moves["u"])
    shaped = result["y"]
    after = time > 0.03 + advice.pick.duration
    for mode in MACHINE:  # the residual of each mode, shaped over unshaped: what "at modes" bounds
        w = 2 * math.pi * mode.frequency
        ring = [np.abs(lsim(([w * w], [1, 2 * mode.zeta * w, w * w]), u, time)[1] - u)[after].max()
                for u in (unshaped, shaped)]
        # Singer and Seering's percent residual compares with the unshaped vibration at the first
        # impulse, which has decayed by exp(-zeta w D) when the shaped one is measured after the last
        percent = ring[1] / ring[0] * math.exp(-mode.zeta * w * advice.pick.duration)
        print(f"mode {mode.frequency} Hz: residual of the move after the shaper, shaped / unshaped "
              f"{100 * ring[1] / ring[0]:.1f} %, as a percent residual {100 * percent:.1f} % "
              f"(the table's worst case at the modes: {100 * advice.pick.at_modes:.1f} %)")

    fig, ax = plt.subplots(figsize=(9, 4.5))
    ax.plot(time, unshaped, "k:", lw=1, label="commanded move")
    ax.plot(time, machine_response(time, unshaped), label="machine, unshaped")
    ax.plot(time, machine_response(time, shaped), label=f"machine, shaped by the FMU ({advice.pick.label})")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("position")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(RESULTS / "recording_to_fmu.png", dpi=120)
    print(f"plots: {RESULTS / 'recommendation.png'}, {RESULTS / 'recording_to_fmu.png'}")


if __name__ == "__main__":
    main_example()
