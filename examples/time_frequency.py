"""Paper 004 (Zhou & Misawa): time-frequency localised seek profile for a hard disk drive.

Omega_0 = 9.68e3 rad/s, Ts = 2e-5 s, move time 2.5 ms: finds the optimal scale n (paper: 11.41,
1 - J about 1e-5), and plots Fig. 6-7 (1 - J against n), Fig. 8 (the acceleration of a 100-track
seek) and Fig. 13 (minimal 1 - J against move time) in results/time_frequency.png.

    .venv/bin/python examples/time_frequency.py
"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from shapefmu.shapers.time_frequency import energy_leakage, time_frequency_profile, tradeoff_curve  # noqa: E402

RESULTS = Path(__file__).resolve().parents[1] / "results"
OMEGA_0, TS, MOVE = 9.68e3, 2e-5, 2.5e-3


def main():
    design = time_frequency_profile(OMEGA_0, TS, MOVE, distance=100.0)
    print(f"optimal n = {design.n:.4f} (paper 11.41), 1 - J = {design.leakage:.3e} (paper about 1e-5)")
    move_times = np.arange(5, 31) * 1e-4
    _, leakage = tradeoff_curve(OMEGA_0, TS, move_times)
    print(f"0.5 ms move: minimal 1 - J = {leakage[0]:.3f} (paper about 0.45)")

    n = np.linspace(9.7, 15.5, 300)
    j = np.array([energy_leakage(x, OMEGA_0, TS, MOVE) for x in n])
    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    axes[0, 0].plot(n, j)
    axes[0, 0].set(title="Fig. 6: 1 - J against n", xlabel="n", ylabel="1 - J")
    axes[0, 1].semilogy(n, j)
    axes[0, 1].axvline(design.n, color="k", ls=":")
    axes[0, 1].set(title=f"Fig. 7: log scale, optimum n = {design.n:.2f}", xlabel="n", ylabel="1 - J")
    p = design.profile
    axes[1, 0].step(p.t * 1e3, p.acceleration, where="post")
    axes[1, 0].set(title="Fig. 8: acceleration of a 100-track seek", xlabel="t [ms]", ylabel="tracks/s^2")
    axes[1, 1].semilogy(move_times * 1e3, leakage, "o-")
    axes[1, 1].set(title="Fig. 13: minimal 1 - J against move time", xlabel="move time [ms]", ylabel="1 - J")
    fig.tight_layout()
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / "time_frequency.png"
    fig.savefig(path, dpi=120)
    print(f"figure: {path}")


if __name__ == "__main__":
    main()
