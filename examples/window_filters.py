"""Paper 000 (Zhou & Misawa): vibration-suppression shape filters from window functions.

Reproduces Fig. 2-3 (sensitivity of the rectangle and Hanning filters, omega = 1 rad/s,
zeta = 0, 0.05, 0.2, Ts = pi / (100 omega_d)) and Fig. 4 (the Hanning filter as a velocity profile,
zeta = 0.2) in results/window_filters.png, and prints the headline: the Hanning filter's 5 % band is
wider than the rectangle's and its residual above q = 3 is lower.

    .venv/bin/python examples/window_filters.py
"""

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from shapefmu.analysis import insensitivity, residual_vibration  # noqa: E402
from shapefmu.shapers.profile import velocity_profile  # noqa: E402
from shapefmu.shapers.window import blackman_filter, hanning_filter, rectangle_filter  # noqa: E402

RESULTS = Path(__file__).resolve().parents[1] / "results"


def paper_ts(zeta):
    return math.pi / (100.0 * math.sqrt(1.0 - zeta * zeta))


def main():
    print(f"M at Ts = pi/(100 omega_d): Hanning {len(hanning_filter(1, 0, paper_ts(0))) - 1}, "
          f"Blackman {len(blackman_filter(1, 0, paper_ts(0))) - 1}")
    zeta = 0.05
    q3 = np.linspace(3.0, 10.0, 1401)
    for name, design in (("rectangle", rectangle_filter), ("Hanning", hanning_filter)):
        shaper = design(1.0, zeta, paper_ts(zeta))
        band = insensitivity(shaper, 1.0, zeta, 0.05)
        tail = residual_vibration(shaper, q3, zeta).max()
        print(f"{name:9} zeta = {zeta}: V <= 5 % for q in [{band.q_low:.4f}, {band.q_high:.4f}] "
              f"(width {band.width:.4f}), max V for q >= 3: {100 * tail:.3f} %")

    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    q = np.linspace(0.0, 4.0, 1601)
    panels = (("Rectangle (Fig. 2)", rectangle_filter), ("Hanning (Fig. 3)", hanning_filter))
    for ax, (name, design) in zip(axes[0], panels):
        for z in (0.0, 0.05, 0.2):
            shaper = design(1.0, z, paper_ts(z))
            ax.plot(q, residual_vibration(shaper, q, z, definition="absolute"), label=f"zeta = {z}")
        ax.set(title=f"{name} shape filter f1[k]", xlabel="actual natural frequency [rad/s]",
               ylabel="residual vibration, eq. (4)")
        ax.legend()
    profile = velocity_profile(hanning_filter(1.0, 0.2, paper_ts(0.2)), distance=1.0)
    axes[1, 0].plot(profile.t, profile.acceleration, label="acceleration")
    axes[1, 0].plot(profile.t, profile.velocity, label="velocity")
    axes[1, 0].plot(profile.t, profile.position, label="position")
    axes[1, 0].set(title="Fig. 4: Hanning filter as a velocity profile (zeta = 0.2)", xlabel="t [s]")
    axes[1, 0].legend()
    for order in (1, 2, 3):
        shaper = hanning_filter(1.0, 0.05, paper_ts(0.05), order)
        axes[1, 1].semilogy(q, np.maximum(residual_vibration(shaper, q, 0.05), 1e-12), label=f"order {order}")
    axes[1, 1].set(title="Hanning filter, robustness order n (eq. 1), zeta = 0.05", xlabel="q", ylabel="V (eq. 5)")
    axes[1, 1].legend()
    fig.tight_layout()
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / "window_filters.png"
    fig.savefig(path, dpi=120)
    print(f"figure: {path}")


if __name__ == "__main__":
    main()
