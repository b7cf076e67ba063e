"""From a raw recording to a recommendation (issue 32, item 5: no slower than Klipper's
calibrate_shaper.py on the same file), on two 130 s, 3.2 kHz, three-axis Klipper raw recordings:
(a) a three-mode machine of ``synthetic`` and (b) the second generator's first chain
(``synthetic_chain``, seed 1000, as benchmarks/modes_chain.py draws it: 31.6 and 89.2 Hz).

1. In this process: identify + recommend (the default fmu target, with its designed train) of (a)
   against the floor measured beside it: reading the same file and one Welch spectrum of its three
   axes (what any recommender must at least do). Imports are not counted here.
2. With ``--klipper PATH`` (a Klipper checkout; its GPL code is run, never imported or copied), as a
   user runs them, each a new process: Klipper's ``scripts/calibrate_shaper.py FILE``, ``shapefmu
   recommend FILE`` and ``shapefmu identify FILE`` on (a) and (b), alternating, ``RUNS`` times each
   after one warm-up run, CPU (user + system of the process) and wall seconds, and ours over
   Klipper's. Every process gets the same interpreter and compiled bytecode cached (in a temporary
   folder, as an installed package has it), so that neither compiles its sources on each run.

    python benchmarks/recommend.py [--klipper /work/klipper]
"""

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from scipy.signal import welch

from shapefmu.identification import identify, klipper
from shapefmu.identification import synthetic as syn
from shapefmu.identification import synthetic_chain as sc
from shapefmu.identification.recommend import recommend, usable_modes
from shapefmu.identification.recordings import read_recording

MACHINE = [syn.SyntheticMode(38.0, 0.06, 0.5), syn.SyntheticMode(61.0, 0.08, 0.3), syn.SyntheticMode(95.0, 0.05, 0.2)]
CHAIN_SEED = 1000
RUNS = 3


def clocks() -> tuple[float, float]:
    """(wall, CPU) seconds: on a shared machine the CPU time is the steadier of the two."""
    return time.perf_counter(), time.process_time()


def since(start) -> tuple[float, float]:
    return tuple(now - then for now, then in zip(clocks(), start))


def floor(path) -> tuple[float, float]:
    """(wall, CPU) seconds to read the recording and take one Welch spectrum of each axis."""
    start = clocks()
    recording = read_recording(path)
    for samples in recording.channels.values():
        welch(samples, recording.fs, nperseg=2048)
    return since(start)


def in_process(path) -> None:
    least = floor(path)
    start = clocks()
    found = identify(path, axis="xyz")
    spectra = klipper.judged_spectra(found.recording, path)
    modes, _ = usable_modes(found.modes.modes)
    identified = since(start)
    advice = recommend(spectra, modes)
    ours = since(start)
    again = floor(path)
    print(f"(a) modes: {', '.join(f'{m.frequency:.2f} Hz / {m.zeta:.3f}' for m in found.modes.modes)}")
    k, pick = advice.klipper_pick, advice.pick
    print(f"(a) Klipper's pick: {k.kind} at {k.frequencies[0]:.1f} Hz, {100 * k.vibration:.2f} %, {k.max_accel:.0f} "
          f"mm/s^2; pick: {pick.label}, {100 * pick.vibration:.2f} %, {pick.max_accel:.0f} mm/s^2 ({advice.verdict})")
    for i, clock in enumerate(("wall", "CPU")):
        print(f"(a) in this process, {clock}: identify {identified[i]:.2f} s + recommend {ours[i] - identified[i]:.2f} s "
              f"= {ours[i]:.2f} s; floor (read + one Welch spectrum): {least[i]:.2f} s before, {again[i]:.2f} s after; "
              f"ratio ours / floor {ours[i] / min(least[i], again[i]):.1f}")


def run_once(command, cwd, env) -> tuple[float, float]:
    """(CPU, wall) seconds of one run of ``command`` as a new process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(command, cwd=cwd, env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), wall


def side_by_side(files: dict[str, Path], klipper_path: Path, cache: str) -> None:
    env = {key: value for key, value in os.environ.items() if key != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = cache
    shapefmu = [sys.executable, "-m", "shapefmu"]
    for label, path in files.items():
        commands = {
            "Klipper calibrate_shaper.py": ([sys.executable, "scripts/calibrate_shaper.py", str(path)], klipper_path),
            "shapefmu recommend": ([*shapefmu, "recommend", str(path)], None),
            "shapefmu identify": ([*shapefmu, "identify", str(path)], None),
        }
        for command, cwd in commands.values():  # the file cache and the bytecode, once
            run_once(command, cwd, env)
        times = {name: [] for name in commands}
        for _ in range(RUNS):  # alternating, so that a slow spell of the machine hits each alike
            for name, (command, cwd) in commands.items():
                times[name].append(run_once(command, cwd, env))
        reference = times["Klipper calibrate_shaper.py"]
        print(f"{label}: {RUNS} alternating runs each, CPU s (user + system) and wall s; ours / Klipper's by the "
              f"median CPU")
        for name, runs in times.items():
            cpu = sorted(c for c, _ in runs)
            wall = sorted(w for _, w in runs)
            ratio = cpu[RUNS // 2] / sorted(c for c, _ in reference)[RUNS // 2]
            print(f"  {name:<28} CPU {cpu[0]:.2f}-{cpu[-1]:.2f} (median {cpu[RUNS // 2]:.2f}, {ratio:.2f}x)   "
                  f"wall {wall[0]:.2f}-{wall[-1]:.2f}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--klipper", type=Path, help="a Klipper checkout, to run its calibrate_shaper.py beside ours")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        files = {"(a) three modes": Path(folder) / "a" / "resonances_x.csv",
                 "(b) chain": Path(folder) / "b" / "resonances_x.csv"}
        for path in files.values():
            path.parent.mkdir()
        t, xyz = syn.record(MACHINE, f_min=5.0, f_max=135.0, hz_per_sec=1.0, seed=5)
        syn.write_klipper_raw(files["(a) three modes"], t, xyz)
        sc.write_klipper_raw(files["(b) chain"], *sc.record(sc.Chain.random(CHAIN_SEED), seed=CHAIN_SEED))
        for label, path in files.items():
            recording = read_recording(path)
            rows = len(recording.channels["x"])
            print(f"{label}: {rows} rows x 3 axes, {rows / recording.fs:.1f} s at {recording.fs:.0f} Hz, "
                  f"{path.stat().st_size / 1e6:.1f} MB")
        in_process(files["(a) three modes"])
        if args.klipper is None:
            print("Klipper not measured (--klipper PATH runs its calibrate_shaper.py beside ours)")
        else:
            side_by_side(files, args.klipper, str(Path(folder) / "bytecode"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
