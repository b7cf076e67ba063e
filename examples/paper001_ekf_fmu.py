"""Paper 001 (Huang, Lee & Ma, 2018) through FMUs: the EKF-tuned ZV / ZVD / ZVDD table (Table 1).

The mode of examples/ekf_shaping.py (10 Hz damped, decay time constant 1.2 s, a unit impulse
ringing with amplitude 0.1) is a single-mode plant FMU (``plants.rigid_flexible`` with
omega_n = sqrt(omega_d^2 + sigma^2), zeta = sigma / omega_n and modal gain b4 = 0.1 omega_d), of
which the system holds two instances, run by the master at the EKF's 1 kHz:

    exciter (ReferencePlayer) -> rig      (a unit impulse at t = 0: the ring-down to watch)
    rig.deflection_1          -> tuner.vibration           (EKFTuner FMU, paper 001 Fig. 20)
    command (ReferencePlayer) -> tuner.u -> machine        (a unit impulse at t = 1 s, shaped)

The tuner watches the rig for 1 s (from an initial guess of 50, 60 or 70 rad/s), designs its
shaper once the EKF has converged and shapes the command; the machine's response is the shaped
one. An impulse is a one-sample pulse of height 1 / Ts, which the players hand over as ``y_mean``
(the exact mean over the coming step), so each plant's zero-order hold receives exactly that pulse.
Table 1's columns are computed from the recorded responses by examples/ekf_shaping.py's
``metrics`` (largest amplitude, settling time to 3 % of the unshaped amplitude, damping ratio by
eq. (31) from the peaks after the shaper's last impulse).

Two differences from the design-layer table, both deliberate and both visible in its numbers: the
FMU path watches the noise-free ring-down (the master connects outputs to inputs one to one and has
no summing junction to add the design example's 40 dB measurement noise), and its impulse is a
1 ms pulse through a zero-order hold rather than a sampled impulse response (the response lags by
half a sample). ``run`` also recomputes the machine's response from the recorded signals by the
design layer (``estimation.EKFTunedShaper`` on the samples the tuner consumed, convolved with the
rig's recorded pulse response): that second method must agree with the co-simulation to rounding.

Writes results/paper001_ekf_fmu.png (like Figs. 8-10, guess 60 rad/s).

    .venv/bin/python examples/paper001_ekf_fmu.py
"""

from __future__ import annotations

import json
import math
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import ekf_shaping as design_example  # noqa: E402  (examples/ekf_shaping.py: the design layer's table)

from shapefmu.cosim import Master  # noqa: E402
from shapefmu.estimation import EKFTunedShaper  # noqa: E402
from shapefmu.fmi import build_fmu  # noqa: E402
from shapefmu.fmi.native import build_plant_fmu  # noqa: E402
from shapefmu.fmi.ssp import System  # noqa: E402
from shapefmu.plants.library import rigid_flexible  # noqa: E402

RESULTS = Path(__file__).resolve().parents[1] / "results"
FS = design_example.FS
TS = 1.0 / FS
OMEGA_D, SIGMA, AMPLITUDE = design_example.OMEGA_D, design_example.SIGMA, design_example.AMPLITUDE
OMEGA_N = math.hypot(OMEGA_D, SIGMA)
ZETA = SIGMA / OMEGA_N
WATCH = 1.0  # s of ring-down watched before the command
UNSHAPED_STOP = 6.0  # s: the unshaped rig needs ~4.2 s to settle to 3 %
SHAPED_STOP = WATCH + 1.0  # s: the shaped responses settle in < 0.2 s
GUESSES, SHAPERS, PAPER_TABLE_1 = design_example.GUESSES, design_example.SHAPERS, design_example.PAPER_TABLE_1
RECORD = ["rig.deflection_1", "machine.deflection_1", "tuner.u", "tuner.vibration", "tuner.y", "tuner.omega_est",
          "tuner.zeta_est"]


def pulse_table(start: float) -> str:
    """A unit impulse at ``start`` as a one-sample pulse of height 1 / Ts (a ReferencePlayer table)."""
    return json.dumps({"kind": "signal_table", "interpolation": "hold", "time": [start, start + TS],
                       "value": [1.0 / TS, 0.0]})


def build(folder, have=None) -> dict[str, Path]:
    """The EKFTuner, ReferencePlayer and single-mode plant FMUs (those not in ``have``), into ``folder``."""
    folder, fmus = Path(folder), dict(have or {})
    if "tuner" not in fmus:
        fmus["tuner"] = build_fmu("EKFTuner", folder / "EKFTuner.fmu", Ts=TS)
    if "player" not in fmus:
        fmus["player"] = build_fmu("ReferencePlayer", folder / "ReferencePlayer.fmu")
    if "plant" not in fmus:
        mode = rigid_flexible(1.0, [(OMEGA_N, ZETA, AMPLITUDE * OMEGA_D)], name="ring_down_mode")
        fmus["plant"] = build_plant_fmu(mode, folder / "RingDownMode.fmu")
    return fmus


def system(fmus) -> System:
    tuner = {"Ts": TS, "amplitude": AMPLITUDE, "omega0": GUESSES[0], "kind": SHAPERS[0]}
    return (System("ekf_tuned_shaping")
            .add("exciter", fmus["player"], {"table": pulse_table(0.0)})
            .add("command", fmus["player"], {"table": pulse_table(WATCH)})
            .add("rig", fmus["plant"])
            .add("tuner", fmus["tuner"], tuner)
            .add("machine", fmus["plant"])
            .connect("exciter.y_mean", "rig.u")
            .connect("rig.deflection_1", "tuner.vibration")
            .connect("command.y_mean", "tuner.u")
            .connect("tuner.y", "machine.u"))


def second_method(record, guess: float, kind: str) -> np.ndarray:
    """The machine's deflection recomputed by the design layer from what the tuner consumed.

    After a step the record holds the inputs the tuner used in it, so row k + 1 gives sample k.
    The machine, stepping after the tuner, holds its sample y[k] over [t_k, t_k+1], and a held
    unit sample gives Ts times the rig's response to its 1 / Ts pulse on [0, Ts]: the machine's
    row n is Ts sum_k y[k] rig[n - k].
    """
    tuner = EKFTunedShaper(FS, guess, kind, amplitude=AMPLITUDE)
    shaped = tuner.run(record["tuner.u"][1:], record["tuner.vibration"][1:])
    return TS * np.convolve(shaped, record["rig.deflection_1"])[: record.size]


def run(fmus=None) -> dict:
    """Every (guess, shaper) of Table 1 through the FMUs; the table rows, the second method's
    largest deviation, and the design example's table (noisy watching, sampled impulse)."""
    with tempfile.TemporaryDirectory(prefix="paper001_") as folder:
        fmus = build(folder, fmus)
        rows, responses, deviation = {}, {}, 0.0
        with Master(system(fmus), TS, record=RECORD) as master:
            for guess in GUESSES:
                for kind in SHAPERS:
                    # The first run is long enough for the unshaped rig to settle (the "none" row).
                    stop = UNSHAPED_STOP if "none" not in rows else SHAPED_STOP
                    record = master.run(stop, parameters={"tuner.omega0": guess, "tuner.kind": kind})
                    t, unshaped = record["time"], record["rig.deflection_1"]
                    initial = float(np.max(np.abs(unshaped)))
                    if "none" not in rows:
                        rows["none"] = design_example.metrics(t, unshaped, 0.0, initial)
                        responses["none"] = (t, unshaped)
                    after = t >= WATCH - 1e-9
                    shaped, y = record["machine.deflection_1"][after], record["tuner.y"][after]
                    duration = t[after][np.flatnonzero(y)[-1]] - WATCH  # the shaper's last impulse
                    rows[guess, kind] = design_example.metrics(t[after] - WATCH, shaped, duration, initial)
                    responses[guess, kind] = (t[after] - WATCH, shaped)
                    rows["estimate", guess] = (float(record["tuner.omega_est"][-1]),
                                               float(record["tuner.zeta_est"][-1]))
                    deviation = max(deviation, float(np.max(np.abs(second_method(record, guess, kind)
                                                                   - record["machine.deflection_1"]))))
    return {"rows": rows, "second_method_deviation": deviation, "design": design_table(), "responses": responses}


def design_table() -> dict:
    """examples/ekf_shaping.py's table: 1 s of noisy sampled ring-down watched, a sampled impulse shaped."""
    t = np.arange(int(6 * FS)) / FS
    unshaped = design_example.impulse_response(t)
    rng = np.random.default_rng(0)
    watched = unshaped[: int(FS)] + AMPLITUDE * 0.00707 * rng.normal(size=int(FS))  # as the example
    initial = float(np.max(np.abs(unshaped)))
    table = {"none": design_example.metrics(t, unshaped, 0.0, initial)}
    for guess in GUESSES:
        for kind in SHAPERS:
            y, shaper, _ = design_example.tuned_response(kind, guess, t, watched)
            table[guess, kind] = design_example.metrics(t, y, shaper.duration, initial)
    return table


def main():
    result = run()
    rows, design = result["rows"], result["design"]
    print(f"single-mode plant FMUs (omega_n {OMEGA_N:.4f} rad/s, zeta {ZETA:.5f}), EKFTuner FMU at {FS:g} Hz, "
          f"by the master")
    for guess in GUESSES:
        omega, zeta = rows["estimate", guess]
        print(f"  guess {guess:4.0f} rad/s -> EKF omega_n {omega:.4f} rad/s ({100 * (omega / OMEGA_N - 1):+.3f} %), "
              f"zeta {zeta:.5f} (true {ZETA:.5f}) at the end of the run")
    header = (f"{'guess':>6} {'shaper':>6} | {'FMU max':>8} {'settle':>7} {'zeta31':>7} | {'design max':>10} "
              f"{'settle':>7} {'zeta31':>7} | {'paper max':>9} {'settle':>7} {'zeta':>7}")
    print("\n" + header + "\n" + "-" * len(header))
    for key in ["none"] + [(g, k) for g in GUESSES for k in SHAPERS]:
        guess, kind = ("", "none") if key == "none" else key
        f, d, p = rows[key], design[key], PAPER_TABLE_1[kind]
        print(f"{guess:>6} {kind:>6} | {f[0]:8.4f} {f[1]:7.3f} {f[2]:7.4f} | {d[0]:10.4f} {d[1]:7.3f} {d[2]:7.4f} | "
              f"{p[0]:9.4f} {p[1]:7.3f} {p[2]:7.4f}")
    print("(settle: s to 3 % of the unshaped amplitude; zeta31: eq. 31 from the peaks after the last impulse)")
    print(f"second method (design layer on the recorded signals) vs co-simulation: largest deviation "
          f"{result['second_method_deviation']:.2e}")

    RESULTS.mkdir(exist_ok=True)
    responses = result["responses"]
    fig, axes = plt.subplots(len(SHAPERS), 1, figsize=(8, 8), sharex=True)
    for ax, kind in zip(axes, SHAPERS):
        for key, color, label in (("none", "tab:blue", "unshaped (rig FMU)"),
                                  ((60.0, kind), "tab:red", f"EKF-{kind.upper()} (tuner FMU, guess 60 rad/s)")):
            ax.plot(*responses[key], color=color, lw=0.8, label=label)
        inset = ax.inset_axes([0.55, 0.45, 0.4, 0.5])
        for key, color in (("none", "tab:blue"), ((60.0, kind), "tab:red")):
            inset.plot(*responses[key], color=color, lw=0.8)
        inset.set_xlim(0, 0.3)
        ax.set_ylabel("vibration")
        ax.legend(loc="lower right", fontsize=8)
    axes[-1].set_xlabel("time after the command [s]")
    fig.suptitle("Paper 001, Figs. 8-10 through FMUs: unshaped vs EKF-tuned shaping")
    fig.tight_layout()
    path = RESULTS / "paper001_ekf_fmu.png"
    fig.savefig(path, dpi=120)
    print(f"plot: {path}")


if __name__ == "__main__":
    main()
