"""Paper 002 (La-orpacharapan & Pao) through FMUs: STOS seeks on the two-mode disk drive.

The STOSController FMU closes the loop on the disk-drive plant FMU of Table I (2.0 and 3.0 kHz
modes, zeta = 0.01, b2 = -b4i = 2.7e3, U = 11 V; generated with its rigid-body velocity as an
output, ``compare.measured_plant``, because the law measures x_r and x_r'): the system of
models/disk_drive_stos.ssd, run by the master (Gauss-Seidel, step = the law's Ts = 1 us) for a
0.1 rad seek with the convolution and the simultaneous shaper, the settle controller of
``stos.stos_law`` bound as parameters as in the .ssd. Printed beside examples/stos_disk_drive.py's
design-layer numbers (``stos.simulate_stos``, the same law on the exact sampled plant) and the
CasADi time-optimal move of the full plant (``optimal.time_optimal``): the move time (x_r within
1e-5 X from then on), its ratio to the time-optimal one, the largest modal deflection left from
the move time on (for both paths; examples/stos_disk_drive.py counts it from the settle
controller's hand-over, which the FMU does not output), and how far the two paths' trajectories
differ. The paper reports that the
simultaneous-shaper STOS is 12.08 us faster than the convolution one (with its shaper times).

By default the FMUs are built into fmus/ (``compare.FMUCache``: rebuilt when their sources
change) under the names the .ssd refers to. Writes results/paper002_stos_fmu.png (like Fig. 6).

    .venv/bin/python examples/paper002_stos_fmu.py
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from shapefmu.cosim import Master
from shapefmu.compare import FMUCache
from shapefmu.fmi.kinds.stos_controller import SETTLE_GAINS
from shapefmu.fmi.ssp import read_ssp
from shapefmu.optimal import time_optimal
from shapefmu.plants import library
from shapefmu.stos import STOSMetrics, STOSResult, plot_stos, rigid_bang_bang_residual, simulate_stos, stos_law

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results"
SYSTEM = ROOT / "models" / "disk_drive_stos.ssd"
X = 0.1  # rad
TS = 1e-6  # s, the law's sampling period and the master's step
BAND = 1e-5  # move time: |x_r - X| <= BAND X from then on (as examples/stos_disk_drive.py)
# The design layer's shaper names -> the FMU's kind: "zv" given two modes convolves one ZV per mode.
KINDS = {"convolution": "zv", "simultaneous": "simultaneous"}
PAPER_FASTER_US = 12.08
STATES = ["plant.position", "plant.velocity", "plant.deflection_1", "plant.state.v_f1", "plant.deflection_2",
          "plant.state.v_f2"]  # the order of the design layer's state vector
RECORD = ["controller.u", *STATES]


def default_system() -> Path:
    """models/disk_drive_stos.ssd with its FMUs built (or found up to date) in fmus/."""
    cache = FMUCache(ROOT / "fmus")
    cache.slave("STOSController")
    cache.plant(library.disk_drive())
    return SYSTEM


def move_time(t, x_r, distance) -> float:
    """First time after which |x_r - distance| <= BAND |distance| to the end of the record."""
    outside = np.flatnonzero(np.abs(x_r - distance) > BAND * abs(distance))
    return float(t[outside[-1] + 1]) if outside.size else float(t[0])


def residual_after(t, deflections, start) -> tuple[float, ...]:
    """Per mode, the largest |x_fi| from ``start`` on."""
    return tuple(float(np.max(np.abs(d[t >= start - 1e-12]))) for d in deflections)


def law_parameters(law, kind: str) -> dict:
    """The controller's run parameters: the shaper kind, the target and the settle controller."""
    settle = {f"controller.{k}": float(law.settle[k]) for k in SETTLE_GAINS}
    return {"controller.kind": KINDS[kind], "controller.target": X, "controller.Ts": TS, "controller.settle": True,
            **settle}


def run(system_file=None) -> dict:
    """Both STOS seeks through the FMUs (``system_file``: an .ssd whose FMUs exist; default the
    project's, built into fmus/), beside the design layer and the time-optimal move."""
    plant = library.disk_drive()
    optimal = time_optimal(plant, X)
    rigid_T, _ = rigid_bang_bang_residual(plant, X, TS)
    stop = TS * math.ceil((2 * rigid_T + 2e-3) / TS)  # whole samples: every step is one of the law's
    system = read_ssp(system_file or default_system())
    runs = {}
    with Master(system, TS, record=RECORD) as master:
        for kind in KINDS:
            law = stos_law(plant, kind, Ts=TS)
            record = master.run(stop, parameters=law_parameters(law, kind))
            t = record["time"]
            fmu_deflections = [record["plant.deflection_1"], record["plant.deflection_2"]]
            fmu_T = move_time(t, record["plant.position"], X)
            design = simulate_stos(plant, law, X, TS, stop, tolerance=BAND)
            design_T = design.metrics.move_time
            runs[kind] = {
                "fmu_move_time": fmu_T, "design_move_time": design_T,
                "fmu_residual": residual_after(t, fmu_deflections, fmu_T),
                "design_residual": residual_after(design.t, [design.x[:, 2], design.x[:, 4]], design_T),
                "largest_state_difference": float(np.max(np.abs(
                    np.column_stack([record[name] for name in STATES]) - design.x[: t.size]), axis=0)[0]),
                "largest_u_difference": float(np.max(np.abs(record["controller.u"][:-1] - design.u[: t.size - 1]))),
                "record": record,
            }
    return {"optimal_T": optimal.T, "rigid_T": rigid_T, "runs": runs}


def as_stos_result(record) -> STOSResult:
    """The FMU run in the design layer's result type, for ``stos.plot_stos``."""
    n = record.size
    return STOSResult(record["time"], np.column_stack([record[name] for name in STATES]), record["controller.u"],
                      np.full(n, X), np.zeros(n), np.zeros(n, dtype=bool),
                      TS, X, STOSMetrics(*(np.nan,) * 6, BAND))


def main():
    result = run()
    T_opt = result["optimal_T"]
    print(f"disk drive (Table I), seek of {X} rad, |u| <= {library.DISK_DRIVE_U} V, Ts = {TS:g} s; "
          f"STOSController FMU <-> plant FMU ({SYSTEM.name}) by the master")
    print(f"CasADi time-optimal move of the full plant: {1e3 * T_opt:.5f} ms; "
          f"rigid bang-bang {1e3 * result['rigid_T']:.5f} ms")
    print(f"{'STOS shaper':<14} {'path':<13} {'move [ms]':>10} {'/ optimal':>10} {'x_f1 left':>10} {'x_f2 left':>10}")
    for kind, r in result["runs"].items():
        for path in ("fmu", "design"):
            T = r[f"{path}_move_time"]
            left = r[f"{path}_residual"]
            print(f"{kind:<14} {'FMUs' if path == 'fmu' else 'design layer':<13} {1e3 * T:10.5f} {T / T_opt:10.5f} "
                  f"{left[0]:10.3e} {left[1]:10.3e}")
        print(f"{'':<14} largest |x_r(FMUs) - x_r(design layer)| = {r['largest_state_difference']:.2e} rad, "
              f"|u(FMUs) - u(design layer)| = {r['largest_u_difference']:.2e} V")
    runs = result["runs"]
    for path in ("fmu", "design"):
        faster = runs["convolution"][f"{path}_move_time"] - runs["simultaneous"][f"{path}_move_time"]
        print(f"simultaneous STOS faster by {1e6 * faster:.1f} us ({'FMUs' if path == 'fmu' else 'design layer'}; "
              f"paper {PAPER_FASTER_US} us with its shaper times)")
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / "paper002_stos_fmu.png"
    plot_stos({f"STOS, {kind} (FMUs)": as_stos_result(r["record"]) for kind, r in runs.items()}, path)
    print(f"plot: {path}")


if __name__ == "__main__":
    main()
