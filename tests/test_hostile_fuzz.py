"""Fixed-seed fuzzers over the surfaces of issue 34: forged FMU states, clock abuse, the master's arrays,
reference tables and files written beside links. Each finds 0 crash, hang, traceback, silent NaN or
file written through a link, in a bounded number of cases (not a time budget: the same cases on any
machine).

- states and clocks: tests/state_clock_fuzzer.py, in a process of its own (a crash fails the test,
  not the suite), against native twins (FMI 2.0, 3.0, 3.0 --clock) and a pythonfmu Shaper;
- arrays: ArrayGain3 (tests/fmus_c/array_gain3.c) declaring random sizes, set and recorded whole,
  by element and out of range, in both step loops: a run or a one-line ValueError, nothing else;
- tables: random JSON objects for the ReferencePlayer, typed and sized at random: a ValueError, or a
  table whose value and step means are finite at any finite time, from the first row to 1e300;
- links: output files of the commands planted as links, FIFOs, folders or others' files at random:
  the target keeps its bytes, and the command writes or refuses in one line.
"""

from __future__ import annotations

import json
import math
import os
import random
import subprocess
import sys
from pathlib import Path

import pytest
from support.c_fmus import build_array_gain3
from support.fixtures_fmi import TRAIN_STARTS
from hostile_support import guarded
from test_hostile_arrays import declared

FUZZER = Path(__file__).resolve().parent / "state_clock_fuzzer.py"
SHAPER = {"kind": "zvd", "n_modes": 1, "f[1]": 13.0, "zeta[1]": 0.05, "Ts": 1e-3}
# (model, FMI version, --clock, start values), for the state and clock fuzzer
TWINS = {
    "Shaper 2.0": ("Shaper", "2.0", False, SHAPER),
    "Shaper 3.0 clock": ("Shaper", "3.0", True, SHAPER),
    "ImpulseTrain 3.0 clock": ("ImpulseTrain", "3.0", True, TRAIN_STARTS),
    "ShapeFilter 3.0": ("ShapeFilter", "3.0", False, {"kind": "hanning", "f": 10.0 / math.sqrt(1 - 0.05**2),
                                                       "zeta": 0.05, "Ts": 1e-3}),
    "EKFTuner 3.0 clock": ("EKFTuner", "3.0", True, {}),
    "TrackedShaper 3.0 clock": ("TrackedShaper", "3.0", True, {}),
    "STOSController 2.0": ("STOSController", "2.0", False, {}),
    "ProfileGenerator 3.0 clock": ("ProfileGenerator", "3.0", True, {"t_start": -1.0}),
    "ReferencePlayer 2.0": ("ReferencePlayer", "2.0", False, {}),
    "ScheduledShaper 3.0 clock": ("ScheduledShaper", "3.0", True, {}),
    "Shaper pythonfmu": ("Shaper", "pythonfmu", False, SHAPER),
}


@pytest.fixture(scope="module")
def extracted(tmp_path_factory):
    from fmpy import extract

    from shapefmu.fmi.native.twins import build_native
    from shapefmu.fmi.python.builder import build_fmu

    folder = tmp_path_factory.mktemp("fuzz")
    found = {}
    for name, (model, version, clock, values) in TWINS.items():
        path = folder / f"{name.replace(' ', '_')}.fmu"
        if version == "pythonfmu":
            build_fmu(model, path, **values)
        else:
            build_native(model, path, fmi_version=version, clock=clock, **values)
        found[name] = (Path(extract(str(path), str(folder / path.stem))), "3" if version == "3.0" else "2")
    return found


@pytest.mark.parametrize("name", TWINS)
def test_forged_states_and_clock_abuse_find_no_crash_and_no_silent_nan(extracted, name):
    directory, version = extracted[name]
    done = subprocess.run([sys.executable, str(FUZZER), str(directory), version, "34", "150"], capture_output=True,
                          text=True, timeout=3000)
    assert done.returncode == 0, done.stderr[-3000:]
    word, cases, calls, refused, silent_nan = done.stdout.split()
    assert word == "ok" and cases == "150" and silent_nan == "0", done.stderr[-3000:]
    assert int(refused) > 0  # the forged states and abuses met refusals: the fuzzer reached the checks


# --- the master's arrays ----------------------------------------------------------------------------

def test_random_array_declarations_settings_and_records_run_or_refuse_in_one_line(tmp_path):
    from shapefmu.cosim import CosimError, Master
    from shapefmu.fmi.ssp import System

    rng = random.Random(34)
    gain = build_array_gain3(tmp_path / "gain")
    sizes = [0, 1, 2, 3, 3, 3, 4, 1000, 10**6 + 1, 10**9, 10**18]
    values = ["[1,2,3]", "[1,2]", "[", "[1e400,0,0]", "[nan,1,2]", "[1,2,3,4]", "[" + ",".join("1" * 5000) + "]", "5",
              "[true,1,2]", "[1 2 3]"]
    outcomes = {"ran": 0, "refused": 0}
    for case in range(60):
        sizes_of = {v: rng.choice(sizes) for v in ("u", "k", "y", "x") if rng.random() < 0.5}
        fmu = declared(gain, tmp_path, sizes_of, f"g{case}")
        parameters = {f"g.{rng.choice(['k', 'u', 'k[1]', 'k[3]', 'k[4]', 'k[0]', 'u[2]'])}": rng.choice(values)
                      for _ in range(rng.randrange(0, 3))}
        record = rng.sample(["g.y", "g.x", "g.total", "g.y[1]", "g.y[3]", "g.y[4]", "g.m2", "g.k[0]"], rng.randrange(1, 4))
        try:
            with Master(System("s").add("g", fmu), 0.25, native=rng.random() < 0.5, record=record) as master:
                result = master.run(0.5, parameters=parameters)
            assert all(math.isfinite(v) for name in result.dtype.names for v in result[name] if isinstance(v, float))
            outcomes["ran"] += 1
        except (ValueError, CosimError) as error:
            assert len(str(error).splitlines()) == 1, str(error)
            outcomes["refused"] += 1
    assert outcomes["ran"] > 0 and outcomes["refused"] > 0, outcomes


# --- reference tables -----------------------------------------------------------------------------

def _random_json(rng, depth=0):
    kinds = ["number", "huge", "string", "bool", "null", "list", "object"] if depth < 2 else ["number", "string", "null"]
    kind = rng.choice(kinds)
    if kind == "number":
        return rng.choice([0, 1, -1, 0.5, rng.uniform(-10, 10), rng.randint(-5, 5)])
    if kind == "huge":
        return rng.choice([1e308, -1e308, 5e-324, 1e154, 1e200, 2**1023])
    if kind == "string":
        return rng.choice(["012", "1", "", "nan", "inf", "x" * 100])
    if kind == "bool":
        return rng.random() < 0.5
    if kind == "null":
        return None
    if kind == "list":
        return [_random_json(rng, depth + 1) for _ in range(rng.randrange(0, 6))]
    return {"a": _random_json(rng, depth + 1)}


def _random_table(rng):
    if rng.random() < 0.5:
        n = rng.randrange(0, 8)
        scale = rng.choice([1.0, 1e3, 1e150, 1e300])
        times = sorted(rng.uniform(-scale, scale) for _ in range(n))
        table = {"kind": "signal_table", "time": times, "value": [rng.uniform(-scale, scale) for _ in range(n)],
                 "interpolation": rng.choice(["hold", "linear", "cubic", 3]), "before": rng.uniform(-1, 1)}
    else:
        switches = sorted(rng.uniform(0, 1) for _ in range(rng.randrange(0, 4)))
        table = {"kind": "time_optimal", "switch_times": switches, "levels": [rng.uniform(-1, 1) for _ in range(len(switches) + 1)],
                 "T": rng.uniform(1, 2), "u_final": 0.0}
    for _ in range(rng.randrange(0, 3)):  # then make it hostile: a field's value replaced by anything
        table[rng.choice(list(table))] = _random_json(rng)
    return table


def test_random_tables_are_refused_or_played_finite_at_any_finite_time():
    from shapefmu.runtime.reference_player import from_dict

    rng = random.Random(34)
    outcomes = {"played": 0, "refused": 0}
    for _ in range(2000):
        table = json.loads(json.dumps(_random_table(rng)))  # as the file holds it
        try:
            played = from_dict(table)
        except ValueError as error:
            assert len(str(error).splitlines()) == 1
            outcomes["refused"] += 1
            continue
        outcomes["played"] += 1
        for _ in range(20):
            a = rng.choice([rng.uniform(-1e300, 1e300), rng.uniform(-2, 2), played.times[0], played.times[-1]])
            b = a + rng.choice([0.0, 1e-16, rng.uniform(0, 1), 1e300, abs(a)])
            if not math.isfinite(b):
                continue
            assert math.isfinite(played.value(a)) and math.isfinite(played.average(a, b)), (table, a, b)
    assert outcomes["played"] > 100 and outcomes["refused"] > 100, outcomes


# --- files beside links ---------------------------------------------------------------------------

VICTIM = b"the user's own file\n"
# (argv with OUT where the output goes, the output's name, the other files it writes, unnamed)
COMMANDS = [
    (["design", "zvd", "--mode", "40:0.05"], None, ()),
    (["sensitivity", "zvd", "--mode", "40:0.05", "--plot", "OUT"], "out.png", ()),
    (["profile", "hanning", "--mode", "40:0.05", "--distance", "0.01", "--plot", "OUT"], "out.png", ()),
    (["recommend", "--mode", "40:0.05", "--build", "OUT"], "out.fmu", ("out.ssv",)),
]


def test_outputs_planted_as_links_fifos_folders_or_others_files_are_never_written_through(tmp_path, monkeypatch):
    rng = random.Random(34)
    monkeypatch.chdir(tmp_path)
    victim = tmp_path / "victim.txt"
    for case in range(12):
        argv, output, beside = rng.choice(COMMANDS[1:])
        folder = tmp_path / f"c{case}"
        folder.mkdir()
        victim.write_bytes(VICTIM)
        planted = {}
        for name in (output, *beside):
            kind = rng.choice(["link", "link", "fifo", "folder", "file", "none"])
            path = folder / name
            if kind == "link":
                os.symlink(victim, path)
            elif kind == "fifo":
                os.mkfifo(path)
            elif kind == "folder":
                path.mkdir()
            elif kind == "file":
                path.write_bytes(VICTIM)
            planted[name] = kind
        code, out, err = guarded([a if a != "OUT" else str(folder / output) for a in argv], seconds=600)
        assert victim.read_bytes() == VICTIM, (argv, planted)
        if any(kind in ("link", "fifo", "folder") for kind in planted.values()) or planted.get("out.ssv") == "file":
            assert code == 2 and len(err.strip().splitlines()) == 1, (argv, planted, err)
        else:
            assert code == 0, (argv, planted, err)
            assert Path(folder / output).is_file() and not Path(folder / output).is_symlink()
