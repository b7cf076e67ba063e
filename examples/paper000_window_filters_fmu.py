"""Paper 000 (Zhou & Misawa) through FMUs: residual-vibration sensitivity of the window shape filters.

The ShapeFilter FMU (rectangle or Hanning f_1[k], omega_model = 1 rad/s, Ts = pi / (100 omega_d))
shapes a unit step command into a single-mode plant FMU (generated from
``plants.rigid_flexible``: x'' + 2 zeta omega x' + omega^2 x = b4 u with b4 = omega^2, so the
step's final deflection is 1), run by the co-simulation master, once per actual frequency
omega = q omega_model (the plant's tunable ``omega[1]`` and ``b4[1]``).

Why a step, and why this is exact. The filter's output for a unit step is the staircase
sum_k f[k] H(t - k Ts), exactly the impulses f[k] at k Ts convolved with a step; the master's
Jacobi scheme holds it over each step, and the plant FMU's zero-order hold is its exact solution.
From the deflection error e = x - 1 and velocity at t_N (the last tap's time) the free oscillation
e = R e^{-zeta omega t} cos(omega_d t + phi) has the envelope
R(t_N) = sqrt(e^2 + ((e' + zeta omega e) / omega_d)^2). An unshaped unit step leaves
R(0) = 1 / sqrt(1 - zeta^2), and the shaped step's envelope is that of eq. (3)-(5)'s impulse sum, so

    V (eq. 5, percent)  = sqrt(1 - zeta^2) R(t_N),
    V (eq. 4, absolute) = omega R(t_N)   (the impulse response is the step response's derivative),

which must equal ``analysis.residual_vibration`` to rounding. The paper's sensitivity curves are
Fig. 2 (rectangle) and Fig. 3 (Hanning), zeta = 0, 0.05, 0.2 (its Figs. 5-7 show the three-Hanning
base functions and the filter architecture, not sensitivity). The headline printed beside
examples/window_filters.py: at zeta = 0.05, the 5 % band of q around 1 (edges by Brent's method on
FMU runs) and the largest V for q >= 3 (grid, then bounded refinement on FMU runs). The paper gives
no number, only that the Hanning filter is more robust "both at the model natural frequency and the
unmodeled high frequency".

Writes results/paper000_window_filters_fmu.png (Fig. 2-3 with FMU points on the design curves).

    .venv/bin/python examples/paper000_window_filters_fmu.py
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy.optimize import brentq, minimize_scalar  # noqa: E402

from shapefmu.analysis import insensitivity, residual_vibration  # noqa: E402
from shapefmu.cosim import Master  # noqa: E402
from shapefmu.fmi import build_fmu  # noqa: E402
from shapefmu.fmi.native import build_plant_fmu  # noqa: E402
from shapefmu.fmi.ssp import System  # noqa: E402
from shapefmu.plants.library import rigid_flexible  # noqa: E402
from shapefmu.shapers.window import hanning_filter, rectangle_filter  # noqa: E402

RESULTS = Path(__file__).resolve().parents[1] / "results"
OMEGA_MODEL = 1.0  # rad/s
DESIGNS = {"rectangle": rectangle_filter, "hanning": hanning_filter}
ZETAS = (0.0, 0.05, 0.2)
HEADLINE_ZETA, VTOL = 0.05, 0.05
CURVE_Q = np.linspace(0.05, 4.0, 40)
TAIL_Q = np.linspace(3.0, 10.0, 71)  # design example: max over q in [3, 10]
RECORD = ["plant.deflection_1", "plant.state.v_f1"]


def paper_ts(zeta: float) -> float:
    """Ts = pi / (100 omega_d) (paper 000, Sec. 2)."""
    return math.pi / (100.0 * OMEGA_MODEL * math.sqrt(1.0 - zeta * zeta))


def build(folder, have=None) -> dict[str, Path]:
    """The ShapeFilter FMU and the single-mode plant FMU (those not in ``have``), built into ``folder``.

    The ShapeFilter is built as a rectangle, whose y feeds through from u: built declaring that,
    it accepts every kind (a Hanning filter's first tap is 0, so it merely does not use it).
    """
    folder, fmus = Path(folder), dict(have or {})
    if "filter" not in fmus:
        fmus["filter"] = build_fmu("ShapeFilter", folder / "ShapeFilter.fmu", kind="rectangle")
    if "plant" not in fmus:
        mode = rigid_flexible(1.0, [(OMEGA_MODEL, 0.0, OMEGA_MODEL**2)], name="single_mode")
        fmus["plant"] = build_plant_fmu(mode, folder / "SingleMode.fmu")
    return fmus


class FilterOnMode:
    """One ShapeFilter -> single-mode plant system; ``residual(q)`` runs it once per frequency ratio."""

    def __init__(self, fmus, kind: str, zeta: float):
        self.zeta, self.ts = zeta, paper_ts(zeta)
        self.shaper = DESIGNS[kind](OMEGA_MODEL, zeta, self.ts)
        self.t_n = self.shaper.times[-1]
        filter_starts = {"kind": kind, "f": OMEGA_MODEL / (2 * math.pi), "zeta": zeta, "Ts": self.ts, "u": 1.0}
        system = (System(f"{kind}_on_mode")
                  .add("filter", fmus["filter"], filter_starts)
                  .add("plant", fmus["plant"], {"zeta[1]": zeta})
                  .connect("filter.y", "plant.u"))
        self.master = Master(system, self.ts, algorithm="jacobi", record=RECORD)
        self.runs = 0

    def envelope(self, q: float) -> float:
        """R(t_N) of the shaped step's residual oscillation on the mode omega = q omega_model."""
        omega = q * OMEGA_MODEL
        record = self.master.run(self.t_n + self.ts, parameters={"plant.omega[1]": omega, "plant.b4[1]": omega**2})
        self.runs += 1
        t, e, v = record["time"][-1], record["plant.deflection_1"][-1] - 1.0, record["plant.state.v_f1"][-1]
        damped = omega * math.sqrt(1.0 - self.zeta**2)
        # The envelope at t, carried back to t_N: it decays as e^{-zeta omega t}.
        return math.hypot(e, (v + self.zeta * omega * e) / damped) * math.exp(self.zeta * omega * (t - self.t_n))

    def residual(self, q: float) -> float:
        """V of eq. (5), a fraction."""
        return math.sqrt(1.0 - self.zeta**2) * self.envelope(q)

    def close(self):
        self.master.close()


def band_edges(run: FilterOnMode, q_max: float = 10.0) -> tuple[float, float]:
    """The band around q = 1 where V <= VTOL: edges bracketed on a grid, refined by Brent on FMU runs
    (``inf`` when V stays below VTOL up to ``q_max``)."""
    low_grid = np.linspace(0.5, 1.0, 11)
    low_v = [run.residual(q) for q in low_grid]
    k = max(i for i, v in enumerate(low_v) if v > VTOL)
    q_low = brentq(lambda q: run.residual(q) - VTOL, low_grid[k], low_grid[k + 1], xtol=1e-10)
    high_grid = np.linspace(1.0, q_max, 91)
    above = [i for i, q in enumerate(high_grid) if run.residual(q) > VTOL]
    if not above:
        return q_low, math.inf
    q_high = brentq(lambda q: run.residual(q) - VTOL, high_grid[above[0] - 1], high_grid[above[0]], xtol=1e-10)
    return q_low, q_high


def tail_maximum(run: FilterOnMode) -> float:
    """The largest V for q in [3, 10]: the best point of a grid, refined between its neighbours."""
    values = [run.residual(q) for q in TAIL_Q]
    k = int(np.argmax(values))
    lo, hi = TAIL_Q[max(k - 1, 0)], TAIL_Q[min(k + 1, TAIL_Q.size - 1)]
    best = minimize_scalar(lambda q: -run.residual(q), bounds=(lo, hi), method="bounded", options={"xatol": 1e-7})
    return max(values[k], -best.fun)


def run(fmus=None) -> dict:
    """Sensitivity curves and the zeta = 0.05 headline through the FMUs, beside the design layer."""
    with tempfile.TemporaryDirectory(prefix="paper000_") as folder:
        fmus = build(folder, fmus)
        curves, headline, runs = {}, {}, 0
        for kind in DESIGNS:
            for zeta in ZETAS:
                system = FilterOnMode(fmus, kind, zeta)
                try:
                    envelope = np.array([system.envelope(q) for q in CURVE_Q])
                    fmu = {"percent": math.sqrt(1.0 - zeta**2) * envelope, "absolute": CURVE_Q * OMEGA_MODEL * envelope}
                    design = {d: residual_vibration(system.shaper, CURVE_Q * OMEGA_MODEL, zeta, d)
                              for d in ("percent", "absolute")}
                    curves[kind, zeta] = {"fmu": fmu, "design": design}
                    if zeta == HEADLINE_ZETA:
                        band = insensitivity(system.shaper, OMEGA_MODEL, zeta, VTOL)
                        dense_tail = residual_vibration(system.shaper, np.linspace(3.0, 10.0, 1401), zeta)
                        headline[kind] = {"fmu_band": band_edges(system), "design_band": (band.q_low, band.q_high),
                                          "fmu_tail": tail_maximum(system), "design_tail": float(dense_tail.max())}
                finally:
                    runs += system.runs
                    system.close()
    return {"q": CURVE_Q, "curves": curves, "headline": headline, "runs": runs}


def main():
    result = run()
    print(f"ShapeFilter FMU -> single-mode plant FMU, {result['runs']} co-simulations; zeta = {HEADLINE_ZETA}, "
          f"Ts = pi/(100 omega_d)")
    print(f"{'filter':<10} {'path':<13} {'5 % band q_low':>14} {'q_high':>9} {'width':>8} {'max V, q >= 3':>14}")
    for kind, h in result["headline"].items():
        for path in ("fmu", "design"):
            low, high = h[f"{path}_band"]
            print(f"{kind:<10} {'FMUs' if path == 'fmu' else 'design layer':<13} {low:14.6f} {high:9.4f} "
                  f"{high - low:8.4f} {100 * h[f'{path}_tail']:13.4f} %")
    worst = max(np.max(np.abs(c["fmu"]["percent"] - c["design"]["percent"])) for c in result["curves"].values())
    print(f"largest |V_FMU - V_design| over {len(result['curves'])} curves x {CURVE_Q.size} frequencies: {worst:.2e}")
    print("paper: the Hanning filter's band is wider and its high-frequency residual lower (Fig. 2-3, no number given)")

    RESULTS.mkdir(exist_ok=True)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5), sharey=True)
    dense = np.linspace(0.0, 4.0, 801)
    for ax, (kind, title) in zip(axes, (("rectangle", "Fig. 2: rectangle"), ("hanning", "Fig. 3: Hanning"))):
        for zeta, color in zip(ZETAS, ("tab:blue", "tab:orange", "tab:green")):
            shaper = DESIGNS[kind](OMEGA_MODEL, zeta, paper_ts(zeta))
            ax.plot(dense, residual_vibration(shaper, dense, zeta, "absolute"), color=color, lw=1.0,
                    label=f"zeta = {zeta}, design layer")
            ax.plot(CURVE_Q, result["curves"][kind, zeta]["fmu"]["absolute"], "o", ms=3.5, color=color, mfc="none",
                    label=f"zeta = {zeta}, FMUs")
        ax.set(title=f"{title} shape filter f1[k]", xlabel="actual natural frequency [rad/s]")
        ax.legend(fontsize=7)
    axes[0].set_ylabel("residual vibration, eq. (4)")
    fig.suptitle("Paper 000: ShapeFilter FMU -> single-mode plant FMU through the master")
    fig.tight_layout()
    path = RESULTS / "paper000_window_filters_fmu.png"
    fig.savefig(path, dpi=120)
    print(f"figure: {path}")


if __name__ == "__main__":
    main()
