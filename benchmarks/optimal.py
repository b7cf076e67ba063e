"""Time-optimal move of the two-mode disk drive (paper 002): ours against a plain uniform-grid
transcription, in the same run.

Ours: ``time_optimal``'s pipeline, a uniform-grid LP transcription (bisection on T) for the bang-bang
structure, then the switch times refined on the exact (matrix-exponential) model; its T is exact
to ~1e-15. The peer is the free-final-time CasADi/IPOPT transcription alone on ever finer uniform
grids (doubling N from 100) while its total time stays within BUDGET. The comparison is at the
accuracy the peer actually reached within the budget: its solve time for that N against ours
(which is more accurate still). The extrapolated time the peer would need for T to 1e-9 is an extra
line, marked as such.

    .venv/bin/python benchmarks/optimal.py
"""

import math
import time

from shapefmu.optimal import lp_transcription, refine_transcription, transcribe
from shapefmu.plants import disk_drive

DISTANCE = 0.05  # rad: bang-bang pulses of 1.3 ms, longer than the 0.4 ms shapers
U_MAX = 11.0  # V, paper 002 Table I
BUDGET = 20.0  # s of peer solves
TARGET = 1e-9  # the acceptance tolerance, for the extrapolated line


def _timed(function, *args, **kwargs):
    start = time.perf_counter()
    result = function(*args, **kwargs)
    return result, time.perf_counter() - start


def main() -> None:
    plant = disk_drive()
    grid, t_transcription = _timed(lp_transcription, plant, DISTANCE, U_MAX)
    solution, t_refinement = _timed(refine_transcription, plant, grid, n_samples=2)
    T = solution.T
    ours = t_transcription + t_refinement
    print(f"disk drive, 2 modes, move {DISTANCE} rad, |u| <= {U_MAX} V: T = {T:.15g} s, "
          f"{len(solution.switch_times)} switches, final-state residual {solution.residual:.2e}")
    print(f"ours: LP transcription N={grid.n_intervals} ({grid.iterations} LPs) {t_transcription:.3f} s + refinement "
          f"{t_refinement:.3f} s = {ours:.3f} s")
    print(f"{'uniform N':>10} {'solve [s]':>10} {'|T_N - T| / T':>14}")
    history, spent, n = [], 0.0, 100
    while True:
        peer, seconds = _timed(transcribe, plant, DISTANCE, U_MAX, n)
        spent += seconds
        history.append((peer.n_intervals, seconds, abs(peer.T - T) / T))
        print(f"{peer.n_intervals:10d} {seconds:10.3f} {history[-1][2]:14.3e}")
        # Stop when the next doubling (cost grows ~N^2 here) would overrun the budget.
        if spent + 3.0 * seconds > BUDGET or history[-1][2] <= TARGET:
            break
        n = 2 * peer.n_intervals  # the transcription raises small N to resolve the fastest mode
    n_best, s_best, e_best = min(history, key=lambda row: row[2])
    print(f"equal accuracy {e_best:.2e} (the best the uniform grid reached within {BUDGET:g} s): uniform N = {n_best} "
          f"{s_best:.3f} s vs ours {ours:.3f} s (ours to ~1e-15): {s_best / ours:.1f}x ours")
    if e_best > TARGET and len(history) >= 2:
        (n1, s1, e1), (n2, s2, e2) = history[-2], history[-1]
        order = math.log(e1 / e2) / math.log(n2 / n1)
        cost = math.log(s2 / s1) / math.log(n2 / n1)
        needed = n2 * (e2 / TARGET) ** (1.0 / order)
        print(f"extrapolated, not measured: error ~ N^-{order:.2f}, time ~ N^{cost:.2f}; T to {TARGET:.0e} would need "
              f"N ~ {needed:.3g}, ~{s2 * (needed / n2) ** cost:.3g} s = ~{s2 * (needed / n2) ** cost / ours:.3g}x ours")


if __name__ == "__main__":
    main()
