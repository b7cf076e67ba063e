"""Time-optimal move of the two-mode disk drive (paper 002): transcription + switching-time
refinement, against a plain uniform-grid transcription, in the same run.

Ours: a 100-interval CasADi/IPOPT transcription finds the bang-bang structure, then the switch
times are refined on the exact (matrix-exponential) model. The peer is the same transcription
alone on ever finer uniform grids (doubling N) until its move time T is as accurate as the refined
one (T to 1e-9 relative, the acceptance tolerance; the refined T is good to ~1e-15), or until
N_MAX, where its accuracy, and the N and solve time that equal accuracy would need (extrapolated
from the observed orders of convergence and of cost), are printed instead.

    .venv/bin/python benchmarks/optimal.py
"""

import math
import time

from shapefmu.optimal import refine_transcription, transcribe
from shapefmu.plants import disk_drive

DISTANCE = 0.05  # rad: bang-bang pulses of 1.3 ms, longer than the 0.4 ms shapers
U_MAX = 11.0  # V, paper 002 Table I
N_OURS = 100
N_MAX = 1800
TARGET = 1e-9


def _timed(function, *args, **kwargs):
    start = time.perf_counter()
    result = function(*args, **kwargs)
    return result, time.perf_counter() - start


def main() -> None:
    plant = disk_drive()
    grid, t_transcription = _timed(transcribe, plant, DISTANCE, U_MAX, N_OURS)
    solution, t_refinement = _timed(refine_transcription, plant, grid, n_samples=2)
    T = solution.T
    target = TARGET
    ours = t_transcription + t_refinement
    print(f"disk drive, 2 modes, move {DISTANCE} rad, |u| <= {U_MAX} V: T = {T:.15g} s, "
          f"{len(solution.switch_times)} switches, final-state residual {solution.residual:.2e}")
    print(f"ours: transcription N={grid.n_intervals} {t_transcription:.3f} s + refinement {t_refinement:.3f} s "
          f"= {ours:.3f} s")
    print(f"{'uniform N':>10} {'solve [s]':>10} {'|T_N - T| / T':>14}")
    history = []
    n = grid.n_intervals  # the first row is our own transcription without the refinement
    while n <= N_MAX:
        peer, seconds = _timed(transcribe, plant, DISTANCE, U_MAX, n)
        error = abs(peer.T - T) / T
        history.append((peer.n_intervals, seconds, error))
        print(f"{peer.n_intervals:10d} {seconds:10.3f} {error:14.3e}")
        if error <= target:
            print(f"uniform grid reaches T to {target:g} at N = {peer.n_intervals}: {seconds:.3f} s, "
                  f"{seconds / ours:.1f}x ours")
            return
        n *= 2
    (n1, s1, e1), (n2, s2, e2) = history[-2], history[-1]
    order = math.log(e1 / e2) / math.log(n2 / n1)
    cost = math.log(s2 / s1) / math.log(n2 / n1)
    needed = n2 * (e2 / target) ** (1.0 / order)
    print(f"uniform grid at N = {n2}: relative error of T {e2:.2e} (> {target:.0e}) after {s2:.3f} s "
          f"= {s2 / ours:.1f}x ours; error ~ N^-{order:.2f}, time ~ N^{cost:.2f}: T to {target:.0e} would need "
          f"N ~ {needed:.3g}, ~{s2 * (needed / n2) ** cost:.3g} s = ~{s2 * (needed / n2) ** cost / ours:.3g}x ours")


if __name__ == "__main__":
    main()
