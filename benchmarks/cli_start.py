"""Start-up of the command line: ``shapefmu --help`` and ``shapefmu plant list`` against ``python -c
"import numpy"``, measured side by side in one run (issue 35: goal <= 2x).

Each command runs as a new process, as a user types it; the best of several runs stands for each
(the least disturbed by the other work on a shared machine), and the ratio to numpy's import is
printed beside the times. CPU time (user + system of the child) is printed too: on a loaded
machine it varies less than the wall clock.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import time

RUNS = 7
GOAL = 2.0

COMMANDS = {
    'python -c "import numpy"': [sys.executable, "-c", "import numpy"],
    "shapefmu --help": [sys.executable, "-m", "shapefmu", "--help"],
    "shapefmu plant list": [sys.executable, "-m", "shapefmu", "plant", "list"],
}


def _once(command: list[str]) -> tuple[float, float]:
    """(wall s, CPU s) of one run of ``command``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"})
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> int:
    for command in COMMANDS.values():  # warm the file cache and the bytecode once
        _once(command)
    best = {name: (float("inf"), float("inf")) for name in COMMANDS}
    for _ in range(RUNS):  # interleaved, so a slow spell of the machine hits every command alike
        for name, command in COMMANDS.items():
            wall, cpu = _once(command)
            best[name] = (min(best[name][0], wall), min(best[name][1], cpu))
    reference_wall, reference_cpu = best['python -c "import numpy"']
    print(f"best of {RUNS} runs each, interleaved; goal <= {GOAL:g}x the numpy import")
    print(f"{'command':<28} {'wall [s]':>9} {'ratio':>7} {'CPU [s]':>9} {'ratio':>7}")
    for name, (wall, cpu) in best.items():
        print(f"{name:<28} {wall:9.3f} {wall / reference_wall:6.2f}x {cpu:9.3f} {cpu / reference_cpu:6.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
