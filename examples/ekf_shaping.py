"""Paper 001 (Huang, Lee & Ma, 2018), Sec. III: EKF-tuned ZV / ZVD / ZVDD shaping of a 10 Hz mode.

The mode: 10 Hz (62.8 rad/s) damped frequency, decay time constant 1.2 s (sigma = 1/1.2 1/s), an
impulse exciting 0.1 of amplitude. For each initial EKF guess (50, 60, 70 rad/s) an
``EKFTunedShaper`` watches 1 s of the unshaped ring-down (with 40 dB measurement noise), designs its
shaper once converged, and shapes the next impulse command. Printed beside the paper's Table 1:
maximum vibration amplitude, settling time to 3 % of the initial (unshaped) amplitude, and the
damping ratio by eq. (31) from the largest peak x_1 and the largest peak x_2 after the shaper's last
impulse (n = 2; for the unshaped response, two successive peaks). Plots like Figs. 5-10 go to
results/ekf_convergence.png and results/ekf_shaping.png.

    .venv/bin/python examples/ekf_shaping.py
"""

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from shapefmu.analysis import log_decrement_damping, settling_time  # noqa: E402
from shapefmu.estimation import EKFTunedShaper, estimate_mode  # noqa: E402

FS = 1000.0
OMEGA_D = 2 * math.pi * 10.0
SIGMA = 1 / 1.2
AMPLITUDE = 0.1
GUESSES = (50.0, 60.0, 70.0)
SHAPERS = ("zv", "zvd", "zvdd")
PAPER_TABLE_1 = {"none": (0.0970, 2.925, 0.0191), "zv": (0.0498, 0.075, 0.6090),
                 "zvd": (0.0264, 0.125, 0.7611), "zvdd": (0.0249, 0.175, 0.8759)}
RESULTS = Path(__file__).resolve().parents[1] / "results"


def impulse_response(t):
    return AMPLITUDE * np.exp(-SIGMA * t) * np.sin(OMEGA_D * t)


def tuned_response(kind, guess, t, watched):
    """Watch the ring-down, then shape a unit impulse and return (plant response, shaper, tuner)."""
    tuner = EKFTunedShaper(FS, guess, kind, amplitude=AMPLITUDE)
    tuner.run(np.zeros(watched.size), watched)
    impulse = np.zeros(t.size)
    impulse[0] = 1.0
    # Nothing more is measured while the shaped command plays: the samples are missing (NaN).
    taps = tuner.run(impulse, np.full(t.size, np.nan))
    return np.convolve(taps, impulse_response(t))[: t.size], tuner.shaper, tuner


def metrics(t, y, duration, initial_amplitude):
    peaks = [k for k in range(1, y.size - 1) if y[k] > y[k - 1] and y[k] >= y[k + 1] and y[k] > 0]
    largest = max(peaks, key=lambda k: y[k])
    later = [k for k in peaks if t[k] > max(duration, t[largest])]
    x2 = max(later, key=lambda k: y[k]) if duration > 0 else later[0]
    zeta = log_decrement_damping([y[largest], y[x2]])  # eq. (31) with n = 2
    settle = settling_time(t, y, 0.03 * initial_amplitude)
    return float(np.max(np.abs(y))), settle, zeta


def main():
    RESULTS.mkdir(exist_ok=True)
    t = np.arange(int(6 * FS)) / FS  # the unshaped response needs ~4.2 s to settle to 3 %
    unshaped = impulse_response(t)
    rng = np.random.default_rng(0)
    watched = unshaped[: int(FS)] + AMPLITUDE * 0.00707 * rng.normal(size=int(FS))  # 40 dB SNR
    initial = float(np.max(np.abs(unshaped)))

    print("EKF estimate from 1 s of ring-down (true omega_d = 62.832 rad/s, sigma = 0.8333 1/s):")
    for guess in GUESSES:
        e = estimate_mode(watched, FS, guess)
        print(f"  guess {guess:4.0f} rad/s -> omega_d {e.omega_d:8.4f} rad/s ({100 * (e.omega_d / OMEGA_D - 1):+.3f} %),"
              f" sigma {e.sigma:.4f} 1/s, zeta {e.zeta:.5f}, converged {e.converged}")

    header = f"{'guess':>6} {'shaper':>6} | {'max amp':>8} {'settle [s]':>10} {'zeta eq.31':>10} |" \
             f" {'paper max':>9} {'paper ts':>8} {'paper zeta':>10}"
    print("\n" + header + "\n" + "-" * len(header))
    none = metrics(t, unshaped, 0.0, initial)
    print(f"{'':>6} {'none':>6} | {none[0]:8.4f} {none[1]:10.3f} {none[2]:10.4f} |"
          f" {PAPER_TABLE_1['none'][0]:9.4f} {PAPER_TABLE_1['none'][1]:8.3f} {PAPER_TABLE_1['none'][2]:10.4f}")
    responses = {}
    for guess in GUESSES:
        for kind in SHAPERS:
            y, shaper, _ = tuned_response(kind, guess, t, watched)
            responses[guess, kind] = y
            m = metrics(t, y, shaper.duration, initial)
            p = PAPER_TABLE_1[kind]
            print(f"{guess:6.0f} {kind:>6} | {m[0]:8.4f} {m[1]:10.3f} {m[2]:10.4f} | {p[0]:9.4f} {p[1]:8.3f} {p[2]:10.4f}")

    fig, axes = plt.subplots(len(SHAPERS), 1, figsize=(8, 8), sharex=True)
    for ax, kind in zip(axes, SHAPERS):
        ax.plot(t, unshaped, color="tab:blue", lw=0.8, label="unshaped")
        ax.plot(t, responses[60.0, kind], color="tab:red", lw=1.0, label=f"EKF-{kind.upper()} (guess 60 rad/s)")
        inset = ax.inset_axes([0.55, 0.45, 0.4, 0.5])
        inset.plot(t, unshaped, color="tab:blue", lw=0.8)
        inset.plot(t, responses[60.0, kind], color="tab:red", lw=1.0)
        inset.set_xlim(0, 0.3)
        ax.set_ylabel("vibration")
        ax.legend(loc="lower right", fontsize=8)
    axes[-1].set_xlabel("time [s]")
    axes[-1].set_xlim(0, 6)
    fig.suptitle("Paper 001, Figs. 8-10: unshaped vs EKF-tuned shaping")
    fig.tight_layout()
    fig.savefig(RESULTS / "ekf_shaping.png", dpi=120)

    fig, ax = plt.subplots(figsize=(8, 4))
    tw = t[: watched.size]
    for guess in GUESSES:
        history = estimate_mode(watched, FS, guess, passes=1).history
        ax.plot(tw, history[:, 0], label=f"initial guess {guess:g} rad/s")
    ax.axhline(OMEGA_D, color="0.3", ls="--", lw=0.8, label="true 62.83 rad/s")
    ax.set_xlabel("time [s]")
    ax.set_ylabel(r"EKF $\omega_d$ estimate [rad/s]")
    ax.legend()
    fig.tight_layout()
    fig.savefig(RESULTS / "ekf_convergence.png", dpi=120)
    print(f"\nplots: {RESULTS / 'ekf_shaping.png'}, {RESULTS / 'ekf_convergence.png'}")


if __name__ == "__main__":
    main()
