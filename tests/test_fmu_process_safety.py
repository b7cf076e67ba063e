"""Many instances of several FMU builds in one process: no crash, no cross-talk, no reference drift.

Two hazards live in every process that hosts our pythonfmu-based FMUs (fmpy, the master, libcosim):

- pythonfmu 0.7.0's export library re-executes the FMU's entry module at every fmi2Instantiate and
  then releases the module's globals once more than it took; the entry module written by
  ``shapefmu.fmi.python.builder`` takes one reference back per execution
  (``slave_base.ENTRY_MODULE_REFERENCES``). Counted wrong, the globals are freed while the module
  still uses them, and a later FMU in the process crashes.
- fmpy's logger proxy (``fmpy.logging.addLoggerProxy``) formats the C message and then calls ONE
  process-wide Python callback, the last one registered. A host that registers a callback per
  instance and lets it die leaves every later FMU that logs through fmpy calling freed memory; the
  master and the test hosts register one router that lives as long as the process (``shapefmu.cosim.fmpy_log``).
- pythonfmu 0.7.0 answers a Python exception escaping the slave with fmi2Fatal and releases the
  instance's Python objects then and again at fmi2FreeInstance; and its library destructor writes
  into a std::shared_ptr that the C++ exit handlers have already freed. The FMUs' C front end
  stops forwarding to a fatal instance (``shim/fmi2_shim.c``, point 5) and resets the pointer
  first (``shim/python_runtime.c``).

Each scenario runs in a subprocess (this file run as a script), so a crash fails the test instead of
killing pytest. The reference is a fresh process that instantiates each FMU once, alone.
"""

from __future__ import annotations

import gc
import json
import math
import os
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from support import CTYPES_HOST
from support.valgrind import requires_valgrind

H = 1e-3  # every FMU below samples at 1 ms
STEPS = 240
NAN_AT = 170  # the step at which our FMUs get a NaN input (fmi2Error), then the step is redone
CHURN_ROUNDS = 25  # instantiate / reset / free cycles per build, three instances each


# --- the driver, run in a subprocess -------------------------------------------------------------


def _inputs(description):
    return [v for v in description.modelVariables if v.causality == "input" and v.type == "Real"]


def _outputs(description):
    return [v for v in description.modelVariables if v.causality == "output" and v.type == "Real"]


def _signal(k, j):
    """Input j at step k: a slow sine per input plus a pulse train, so every output moves."""
    return math.sin(0.05 * k + j) + (1.0 if (k // 40) % 2 else 0.0)


class _Instance:
    """One fmpy instance of one FMU build, initialised, stepped one communication step at a time."""

    def __init__(self, build, unzip_directory, name):
        from fmpy.fmi2 import FMU2Slave

        self.build = build
        md = build["description"]
        self.inputs = [v.valueReference for v in _inputs(md)]
        self.outputs = [v.valueReference for v in _outputs(md)]
        self.slave = FMU2Slave(guid=md.guid, unzipDirectory=unzip_directory,
                               modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        self.slave.instantiate()  # fmpy's default callbacks: messages go through its logger proxy
        self.rows = []

    def initialise(self):
        self.slave.setupExperiment(startTime=0.0)
        self.slave.enterInitializationMode()
        self.slave.exitInitializationMode()
        return self

    def step(self, k):
        from fmpy.fmi1 import FMICallException

        if k == NAN_AT and self.build["rejects_nan"]:
            self.slave.setReal(self.inputs[:1], [float("nan")])
            try:
                self.slave.doStep(k * H, H)
            except FMICallException as failure:
                self.build["nan_statuses"].append(failure.status)
        self.slave.setReal(self.inputs, [_signal(k, j) for j in range(len(self.inputs))])
        self.slave.doStep(k * H, H)
        self.rows.append(self.slave.getReal(self.outputs))

    def free(self):
        self.slave.freeInstance()


def _builds(paths):
    from fmpy import extract, read_model_description

    builds = {}
    for label, spec in paths.items():
        with zipfile.ZipFile(spec["path"]) as fmu:
            entry = fmu.read("resources/slavemodule.txt").decode().strip()
        builds[label] = {
            "description": read_model_description(spec["path"]),
            "directories": [extract(spec["path"]), extract(spec["path"])],  # two copies on disk
            "entry": entry,
            "rejects_nan": spec["ours"],
            "nan_statuses": [],
        }
    return builds


def _entry_globals_references(builds):
    gc.collect()
    return {label: sys.getrefcount(sys.modules[build["entry"]].__dict__) for label, build in builds.items()}


def _churn(build, label, rounds):
    """Instances of one build made, stepped, reset and freed in mixed order, side by side."""
    for r in range(rounds):
        directories = build["directories"]
        a = _Instance(build, directories[r % 2], f"{label}_a{r}").initialise()
        b = _Instance(build, directories[(r + 1) % 2], f"{label}_b{r}").initialise()
        c = _Instance(build, directories[r % 2], f"{label}_c{r}")  # never initialised
        for k in range(3):
            a.step(k)
            b.step(k)
        b.slave.reset()
        b.initialise()
        b.step(0)
        for instance in (b, a, c) if r % 2 else (c, a, b):
            instance.free()


def _class_references_per_cycle(build, label, raising, cycles=4):
    """How the slave class's reference count moves per instantiate / call / free cycle.

    ``raising``: the slave's ``get_real`` raises (a bug in a slave, simulated by patching the class
    in this process), which pythonfmu answers with fmi2Fatal after releasing the instance's Python
    objects; the front end must then refuse further calls and not free them a second time.
    """
    from fmpy.fmi1 import FMICallException

    directories = build["directories"]
    probe = _Instance(build, directories[0], f"{label}_probe")
    slave_class = getattr(sys.modules[build["entry"]], build["description"].coSimulation.modelIdentifier)
    probe.free()
    original = slave_class.get_real
    statuses = []
    gc.collect()
    before = sys.getrefcount(slave_class)
    for r in range(cycles):
        instance = _Instance(build, directories[r % 2], f"{label}_fatal{r}").initialise()
        if raising:
            slave_class.get_real = lambda self, vrs: 1 / 0
        for call in (lambda: instance.slave.getReal(instance.outputs), lambda: instance.slave.doStep(0.0, H)):
            try:
                call()
                statuses.append(0)
            except FMICallException as failure:
                statuses.append(failure.status)
        slave_class.get_real = original
        instance.free()
    gc.collect()
    return (sys.getrefcount(slave_class) - before) / cycles, statuses


def _run_master(paths):
    """A co-simulation by shapefmu's master, closed before the FMUs below log anything."""
    from shapefmu.cosim import simulate
    from shapefmu.fmi.ssp import System

    system = System("churn").add("shaper", paths["shaper_a"]["path"]).add("integrator", paths["plain"]["path"])
    system.connect("shaper.y", "integrator.u")
    result = simulate(system, 0.02, H, record=["integrator.y"])
    return [float(v) for v in result["integrator.y"]]


def _drive(paths, mode):
    builds = _builds(paths)
    report = {"outputs": {}, "master": None, "references": None}
    if mode == "reference":  # each build alone: one instance, start to end, then freed
        for label, build in builds.items():
            instance = _Instance(build, build["directories"][0], label).initialise()
            for k in range(STEPS):
                instance.step(k)
            instance.free()
            report["outputs"][label] = instance.rows
    else:  # every build side by side, with churn and a master run between the two halves
        live = {label: _Instance(build, build["directories"][1], label).initialise() for label, build in builds.items()}
        for k in range(STEPS // 2):
            for instance in live.values():
                instance.step(k)
        for label, build in builds.items():
            _churn(build, label, 1)
        before = _entry_globals_references(builds)
        for label, build in builds.items():
            _churn(build, label, CHURN_ROUNDS)
        after = _entry_globals_references(builds)
        report["references"] = {label: [before[label], after[label]] for label in builds}
        report["fatal"] = {label: [_class_references_per_cycle(build, label, False),
                                   _class_references_per_cycle(build, label, True)]
                           for label, build in builds.items() if build["rejects_nan"]}
        report["master"] = _run_master(paths)
        gc.collect()  # frees whatever the master left behind, its logger callback included
        for k in range(STEPS // 2, STEPS):
            for instance in live.values():
                instance.step(k)
        for label, instance in live.items():
            instance.free()
            report["outputs"][label] = instance.rows
    report["nan_statuses"] = {label: build["nan_statuses"] for label, build in builds.items()}
    return report


# --- the tests ------------------------------------------------------------------------------------


def _build_all(directory: Path) -> dict:
    from support.cosim_fmus import build_test_fmu
    from support.fixtures_fmi import EKF_STARTS, SHAPER_STARTS

    from shapefmu.fmi import build_fmu

    return {
        # Two builds of one slave share one bundled package and one entry module in the process.
        "shaper_a": {"path": str(build_fmu("Shaper", directory / "ShaperA.fmu", **SHAPER_STARTS)), "ours": True},
        "shaper_b": {"path": str(build_fmu("Shaper", directory / "ShaperB.fmu", **{**SHAPER_STARTS, "f[1]": 12.5})),
                     "ours": True},
        "ekf": {"path": str(build_fmu("EKFTuner", directory / "EKFTuner.fmu", **EKF_STARTS)), "ours": True},
        # A plain pythonfmu FMU, as the master's tests build them (tests/support/cosim_fmus.py).
        "plain": {"path": str(build_test_fmu("CosimIntegrator", directory / "plain")), "ours": False},
    }


def _run(paths, mode, directory: Path):
    out = directory / f"{mode}.json"
    spec = directory / f"{mode}_paths.json"
    spec.write_text(json.dumps(paths))
    result = subprocess.run([sys.executable, "-X", "faulthandler", __file__, mode, str(spec), str(out)],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, f"{mode} run died with {result.returncode}:\n{result.stderr[-4000:]}"
    return json.loads(out.read_text()), result.stdout


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The builds, the reference process and the churned process (run once for this module)."""
    directory = tmp_path_factory.mktemp("process_safety")
    paths = _build_all(directory)
    reference, _ = _run(paths, "reference", directory)
    churned, printed = _run(paths, "churn", directory)
    return paths, reference, churned, printed


def test_many_instances_of_several_builds_side_by_side_match_each_fmu_run_alone(runs):
    paths, reference, churned, printed = runs
    for label in paths:
        rows = reference["outputs"][label]
        assert len(rows) == STEPS and max(map(max, rows)) > min(map(min, rows)), label  # the outputs move
        assert churned["outputs"][label] == rows, label  # bit for bit: no cross-talk, nothing corrupted
    assert len(churned["master"]) == 21  # the master ran (0 to 20 ms) between the two halves
    # Each of our FMUs refused its NaN input with fmi2Error, alone and side by side...
    ours = [label for label, spec in paths.items() if spec["ours"]]
    assert {label: churned["nan_statuses"][label] for label in ours} == {label: [3] for label in ours}
    assert reference["nan_statuses"] == churned["nan_statuses"]
    # ...and its message reached fmpy's own printer after the master had come and gone.
    assert printed.count("[ERROR] input ") == len(ours), printed


def test_entry_module_globals_are_referenced_as_often_after_many_instantiations(runs):
    paths, _, churned, _ = runs
    for label, spec in paths.items():
        before, after = churned["references"][label]
        if spec["ours"]:
            # 25 rounds of 3 instantiations: the workaround takes back exactly what pythonfmu releases.
            assert after == before, (label, before, after)
        else:
            # A plain pythonfmu module is never over-released: pythonfmu also leaks the class it
            # re-creates at each instantiation, whose methods hold the module's globals.
            assert after >= before, (label, before, after)


def test_an_exception_escaping_a_slave_is_fatal_for_that_instance_only_and_released_once(runs):
    _, _, churned, printed = runs
    for label, (normal, raising) in churned["fatal"].items():
        # fmi2Fatal for the raising call, then every call refused with fmi2Fatal until freed.
        assert normal[1] == [0, 0] * 4 and raising[1] == [4, 4] * 4, (label, normal, raising)
        # pythonfmu keeps one reference to the class per instantiation either way; a second
        # release at fmi2FreeInstance would show here as one reference fewer per cycle.
        assert raising[0] == normal[0], (label, normal, raising)
    assert "only fmi2FreeInstance is allowed" in printed
    # ...and the side-by-side instances above, stepped after all this, still matched (first test).


@pytest.mark.foreign
@requires_valgrind
def test_valgrind_sees_no_invalid_access_in_the_fmu_binaries_of_a_python_host(tmp_path):
    """pythonfmu's library destructor resets a std::shared_ptr the C++ exit handlers have freed;
    the front end's own exit handler resets it first (shim/python_runtime.c)."""
    from support.fixtures_fmi import EKF_STARTS, SHAPER_STARTS

    from shapefmu.fmi import build_fmu

    directories = []
    for name, starts in (("Shaper", SHAPER_STARTS), ("EKFTuner", EKF_STARTS)):
        with zipfile.ZipFile(build_fmu(name, tmp_path / f"{name}.fmu", **starts)) as fmu:
            fmu.extractall(tmp_path / name)
        directories.append(str(tmp_path / name))
    log = tmp_path / "valgrind.log"
    driver = CTYPES_HOST
    result = subprocess.run(
        ["valgrind", "--error-limit=no", "--num-callers=20", f"--log-file={log}",
         sys.executable, "-I", "-S", str(driver), ",".join(directories), "50", str(H)],
        capture_output=True, text=True, timeout=300, env={**os.environ, "PYTHONMALLOC": "malloc"})
    assert result.returncode == 0, result.stderr[-3000:]
    assert len(result.stdout.splitlines()) == 2  # both FMUs ran their 50 steps
    # memcheck separates its reports by an empty "==pid==" line; keep those in the FMUs' binaries
    # (the interpreter's own start-up has reports of its own that are none of the FMUs' business).
    reports = re.split(r"^==\d+== ?$", log.read_text(), flags=re.M)
    invalid = [r for r in reports if "Invalid " in r and "binaries/linux64/" in r]
    assert invalid == [], "\n".join(invalid)[:4000]


if __name__ == "__main__":
    _mode, _spec, _out = sys.argv[1:]
    Path(_out).write_text(json.dumps(_drive(json.loads(Path(_spec).read_text()), _mode)))
