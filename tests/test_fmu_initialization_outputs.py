"""Outputs got in Initialization Mode (FMI 2.0 section 2.2.7, initial="calculated"): every kind, as a
pythonfmu FMU and as a native FMU for FMI 2.0 and 3.0, gives a host that gets an output after setting
its inputs in Initialization Mode what the output will be once initialisation is over.

The references: the FMU's own value got right after the exit of initialisation, before any step (a
second method); the closed forms where one exists (a shaper's first impulse, Singer and Seering's ZVD
amplitude; a signal table's value at t0); fmpy's simulate_fmu, which sets the input before the exit.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException

from support import MODELS
from support.fixtures_fmi import TRAIN_STARTS
from support.fixtures_native import FILTERS, TWO_MODES, shaper_starts
from support.valgrind import requires_valgrind, run_driver_under_valgrind

# A hold table whose value at t0 = 0 is its "before" value.
TABLE = json.dumps({"kind": "signal_table", "interpolation": "hold", "before": 5.0, "time": [0.0005], "value": [0.0]})
# name -> (model, start values): every kind with a native twin; "plant" is the disk drive (native only).
CASES = {
    "shaper zvd": ("Shaper", shaper_starts("zvd", TWO_MODES)),
    "impulse train": ("ImpulseTrain", TRAIN_STARTS),
    "filter hanning2": ("ShapeFilter", FILTERS["hanning2"]),
    "ekf tuner": ("EKFTuner", {}),
    "tracked shaper": ("TrackedShaper", {}),
    "stos controller": ("STOSController", {}),
    "reference player": ("ReferencePlayer", {"table": TABLE}),
    "profile generator": ("ProfileGenerator", {}),
    "scheduled shaper": ("ScheduledShaper", {}),
}
FLAVOURS = ("pythonfmu", "native 2.0", "native 3.0")
INPUT = 0.75  # every input, set in Initialization Mode (inside every kind's valid range)


@pytest.fixture(scope="module")
def fmus(builds):
    """{(case, flavour): FMU} of every case and the disk-drive plant."""
    jobs = {}
    for name, (model, starts) in CASES.items():
        jobs[(name, "pythonfmu")] = ("pythonfmu", (model,), starts)
        for version in ("2.0", "3.0"):
            jobs[(name, f"native {version}")] = ("native", (model,), {"fmi_version": version, **starts})
    for version in ("2.0", "3.0"):
        jobs[("plant", f"native {version}")] = ("plant", (MODELS / "disk_drive.toml",), {"fmi_version": version})
    return builds.many(jobs)


class Initializing:
    """One instance of an FMU in Initialization Mode, FMI 2.0 or 3.0 (fmpy), got and set by name."""

    def __init__(self, fmu):
        md = read_model_description(str(fmu))
        self.fmi3 = md.fmiVersion.startswith("3")
        self.variables = {v.name: v for v in md.modelVariables if v.name != "time"}
        if self.fmi3:
            from fmpy.fmi3 import FMU3Slave

            self.slave = FMU3Slave(guid=md.instantiationToken, unzipDirectory=extract(str(fmu)),
                                   modelIdentifier=md.coSimulation.modelIdentifier, instanceName="initializing")
            self.slave.instantiate()
            self.slave.enterInitializationMode(startTime=0.0)
        else:
            from fmpy.fmi2 import FMU2Slave

            self.slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)),
                                   modelIdentifier=md.coSimulation.modelIdentifier, instanceName="initializing")
            self.slave.instantiate()
            self.slave.setupExperiment(startTime=0.0)
            self.slave.enterInitializationMode()

    def get(self, name):
        v = self.variables[name]  # fmpy's getter of the type: getReal / getFloat64, getInteger / getInt32, ...
        return getattr(self.slave, f"get{v.type}")([v.valueReference])[0]

    def set(self, name, value):
        v = self.variables[name]
        getattr(self.slave, f"set{v.type}")([v.valueReference], [value])

    def names(self, causality):
        return [n for n, v in self.variables.items() if v.causality == causality and v.type != "String"]

    def outputs(self):
        return {name: self.get(name) for name in self.names("output")}

    def exit(self):
        self.slave.exitInitializationMode()

    def free(self):
        self.slave.freeInstance()


def _set_inputs(fmu):
    """An instance in Initialization Mode with every input (all are Real) at INPUT."""
    instance = Initializing(fmu)
    for name in instance.names("input"):
        instance.set(name, INPUT)
    return instance


def _zvd_first_amplitude(starts) -> float:
    """The first impulse of the modes' ZVD shapers convolved: prod 1 / (1 + K_i)^2, K_i = exp(-zeta_i pi /
    sqrt(1 - zeta_i^2)) (Singer and Seering's ZVD; the convolution's first impulse is the product of
    the firsts)."""
    first = 1.0
    for i in range(1, starts["n_modes"] + 1):
        zeta = starts[f"zeta[{i}]"]
        first /= (1.0 + math.exp(-zeta * math.pi / math.sqrt(1.0 - zeta**2))) ** 2
    return first


@pytest.mark.parametrize(("name", "flavour"), [(n, f) for n in [*CASES, "plant"] for f in FLAVOURS
                                               if n != "plant" or f != "pythonfmu"])  # plants are native only
def test_every_output_got_in_initialization_mode_is_the_one_after_the_exit(fmus, name, flavour):
    instance = _set_inputs(fmus[(name, flavour)])
    in_initialization = instance.outputs()
    instance.exit()
    after_exit = instance.outputs()
    instance.free()
    assert in_initialization == after_exit


@pytest.mark.parametrize("flavour", FLAVOURS)
def test_a_shaper_gives_its_first_impulse_times_the_input_in_initialization_mode(fmus, flavour):
    """y(0) = a_1 u(0) + (1 - a_1) u0: the impulses after the first still see u0, the command before the start."""
    starts = CASES["shaper zvd"][1]
    instance = _set_inputs(fmus[("shaper zvd", flavour)])
    first, u0 = _zvd_first_amplitude(starts), starts["u0"]
    assert instance.get("y") == pytest.approx(first * INPUT + (1.0 - first) * u0, rel=1e-12)
    instance.set("u", 2.0 * INPUT)  # a later set changes the next get, and the exit takes it
    assert instance.get("y") == pytest.approx(first * 2.0 * INPUT + (1.0 - first) * u0, rel=1e-12)
    instance.exit()
    assert instance.get("y") == pytest.approx(first * 2.0 * INPUT + (1.0 - first) * u0, rel=1e-12)
    instance.free()


@pytest.mark.parametrize("flavour", FLAVOURS)
def test_a_player_gives_its_table_value_at_t0_in_initialization_mode(fmus, flavour):
    instance = Initializing(fmus[("reference player", flavour)])
    assert instance.get("y") == 5.0  # the table's "before" value
    instance.free()


@pytest.mark.parametrize("flavour", FLAVOURS)
def test_parameters_the_exit_would_refuse_are_refused_at_the_exit_not_by_a_get(fmus, flavour, capfd):
    """Ts = 1e-9 s makes the ZVD's delay line longer than any FMU holds: a get in Initialization Mode
    answers (the outputs' start values) without an error and leaves the instance usable -- Ts set back,
    the next get is the closed form -- and the exit with Ts = 1e-9 refuses with a message naming Ts."""
    starts = CASES["shaper zvd"][1]
    first, u0 = _zvd_first_amplitude(starts), starts["u0"]
    instance = _set_inputs(fmus[("shaper zvd", flavour)])
    instance.set("Ts", 1e-9)
    assert math.isfinite(instance.get("y"))
    assert "error" not in capfd.readouterr().out.lower()
    instance.set("Ts", starts["Ts"])
    assert instance.get("y") == pytest.approx(first * INPUT + (1.0 - first) * u0, rel=1e-12)
    instance.set("Ts", 1e-9)
    with pytest.raises(FMICallException):
        instance.exit()
    instance.free()
    assert "Ts = 1e-09" in capfd.readouterr().out


def test_player_to_shaper_gives_the_first_impulse_of_the_player_at_t0_in_our_master_and_in_fmpy(builds):
    """Our master propagates values in Initialization Mode: the shaper's output recorded at t = 0 is a_1
    times the player's value there, as fmpy's simulate_fmu gives with the player's value as input."""
    from fmpy import simulate_fmu

    from shapefmu.cosim.master import simulate
    from shapefmu.fmi.ssp import System

    starts = {"kind": "zvd", **TWO_MODES, "Ts": 1e-3}
    expected = _zvd_first_amplitude(starts) * 5.0
    player_fmus = (builds.pythonfmu("ReferencePlayer", table=TABLE), builds.native("ReferencePlayer", table=TABLE))
    shaper_fmus = (builds.pythonfmu("Shaper", **starts), builds.native("Shaper", **starts))
    for player, shaper in zip(player_fmus, shaper_fmus):
        system = System("player_to_shaper").add("player", player).add("shaper", shaper)
        system.connect("player.y", "shaper.u")
        for algorithm in ("gauss-seidel", "jacobi"):
            result = simulate(system, 0.01, 1e-3, record=["shaper.y"], algorithm=algorithm)
            assert result["shaper.y"][0] == pytest.approx(expected, rel=1e-12), (shaper.name, algorithm)
        signal = np.array([(0.0, 5.0), (0.01, 5.0)], dtype=[("time", float), ("u", float)])
        fmpy_result = simulate_fmu(str(shaper), stop_time=0.01, output_interval=1e-3, input=signal, output=["y"])
        assert fmpy_result["y"][0] == pytest.approx(expected, rel=1e-12)


@requires_valgrind
@pytest.mark.parametrize("name", [*CASES, "plant"])
def test_outputs_got_in_initialization_mode_leave_no_error_and_no_leak_under_valgrind(fmus, name, tmp_path):
    run_driver_under_valgrind(fmus[(name, "native 2.0")], "valgrind_initialization", tmp_path)
