"""The core of the generic C FMI layer (src/shapefmu/fmi/native/c/layer_core.c): the rules every
native FMU shares behind both its FMI 2.0 and its FMI 3.0 API, tested through those APIs (fmpy) on
the generated disk-drive plant, and on a native Shaper for a fixed parameter and a string.

The second opinions: paper 002's eq. (1) for the disk drive (x_r'' = b2 u, x_fi'' = -omega_i^2 x_fi
- 2 zeta_i omega_i x_fi' + b4i u, the outputs x_r and the x_fi; models/disk_drive.toml's values), whose
Jacobian the directional derivatives must give; the FMI standards' state machines for which
variable a host may set in which state (FMI 2.0.5 tables of sec. 3.2.3 and 4.2.4, FMI 3.0 sec. 2.3:
the same for these causalities and variabilities) and for fmi2Reset after fmi2Error (FMI 2.0.5,
p. 18); a fresh instance for what a reset must restore.
"""

import math

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model, FMU2Slave
from fmpy.fmi3 import FMU3Model, FMU3Slave

from support import MODELS

B2, B4 = 2.7e3, -2.7e3
OMEGA = (2 * math.pi * 2.0e3, 2 * math.pi * 3.0e3)
ZETA = (0.01, 0.01)
STATES = ["state.x_r", "state.v_r", "state.x_f1", "state.v_f1", "state.x_f2", "state.v_f2"]


def eq_1():
    """(A, B, C) of paper 002's eq. (1) for the disk drive: the state [x_r, x_r', x_f1, x_f1', x_f2, x_f2']."""
    a = np.zeros((6, 6))
    b = np.zeros(6)
    a[0, 1], b[1] = 1.0, B2
    for i, (w, z) in enumerate(zip(OMEGA, ZETA)):
        k = 2 + 2 * i
        a[k, k + 1] = 1.0
        a[k + 1, k], a[k + 1, k + 1], b[k + 1] = -w * w, -2.0 * z * w, B4
    c = np.zeros((3, 6))
    c[0, 0], c[1, 2], c[2, 4] = 1.0, 1.0, 1.0
    return a, b, c


class Instance:
    """One instance of an FMU in fmpy, FMI 2.0 or 3.0, Co-Simulation or Model Exchange, with the few
    calls these tests make spelled once for both versions."""

    def __init__(self, fmu, model_exchange=False):
        md = read_model_description(str(fmu))
        self.fmi3 = md.fmiVersion.startswith("3")
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        classes = {(False, False): FMU2Slave, (False, True): FMU2Model, (True, False): FMU3Slave, (True, True): FMU3Model}
        interface = md.modelExchange if model_exchange else md.coSimulation
        token = md.instantiationToken if self.fmi3 else md.guid
        self.fmu = classes[self.fmi3, model_exchange](guid=token, unzipDirectory=extract(str(fmu)),
                                                      modelIdentifier=interface.modelIdentifier, instanceName="core")
        self.fmu.instantiate()
        self.model_exchange = model_exchange

    def setup(self, start=0.0, stop=None):
        if not self.fmi3:
            self.fmu.setupExperiment(startTime=start, stopTime=stop)
        self._start, self._stop = start, stop

    def initialise(self, values=None):
        if self.fmi3:
            self.fmu.enterInitializationMode(startTime=self._start, stopTime=self._stop)
        else:
            self.fmu.enterInitializationMode()
        for name, value in (values or {}).items():
            self.set(name, value)
        self.fmu.exitInitializationMode()
        if self.model_exchange:
            (self.fmu.updateDiscreteStates if self.fmi3 else self.fmu.newDiscreteStates)()
            self.fmu.enterContinuousTimeMode()

    def set(self, name, value):
        (self.fmu.setFloat64 if self.fmi3 else self.fmu.setReal)([self.vr[name]], [value])

    def get(self, names):
        return (self.fmu.getFloat64 if self.fmi3 else self.fmu.getReal)([self.vr[n] for n in names])

    def step(self, t, h):
        self.fmu.doStep(t, h)

    def derivatives(self, x):
        from ctypes import c_double

        states = (c_double * len(x))(*x)
        self.fmu.setContinuousStates(states, len(x))
        dx = (c_double * len(x))()
        (self.fmu.getContinuousStateDerivatives if self.fmi3 else self.fmu.getDerivatives)(dx, len(x))
        return np.array(dx)

    def directional(self, unknowns, known):
        return np.array(self.fmu.getDirectionalDerivative([self.vr[n] for n in unknowns], [self.vr[known]], [1.0]))

    def free(self):
        self.fmu.freeInstance()


@pytest.fixture(scope="module", params=["2.0", "3.0"])
def plant(request, builds):
    """The disk-drive plant FMU as FMI 2.0 and as FMI 3.0."""
    return builds.plant(MODELS / "disk_drive.toml", fmi_version=request.param)


def test_derivatives_and_outputs_are_those_of_paper_002_eq_1(plant):
    a, b, c = eq_1()
    rng = np.random.default_rng(1)
    x, u = rng.normal(size=6) * [1e-3, 1.0, 1e-6, 1e-2, 1e-6, 1e-2], 7.5
    instance = Instance(plant, model_exchange=True)
    instance.setup()
    instance.initialise()
    instance.set("voltage", u)
    dx = instance.derivatives(x)
    outputs = instance.get(["position", "deflection_1", "deflection_2"])
    instance.free()
    expected = a @ x + b * u
    np.testing.assert_allclose(dx, expected, rtol=1e-13, atol=1e-13 * np.max(np.abs(expected)))
    np.testing.assert_allclose(outputs, c @ x, rtol=1e-15, atol=0)


def test_directional_derivatives_are_the_jacobian_of_eq_1(plant):
    """Each column of A (d der(x) / d x_j) and B (d der(x) / d voltage), and of C (d y / d x_j)."""
    a, b, c = eq_1()
    instance = Instance(plant, model_exchange=True)
    instance.setup()
    instance.initialise()
    derivatives = [f"der({name})" for name in STATES]
    outputs = ["position", "deflection_1", "deflection_2"]
    for j, state in enumerate(STATES):
        np.testing.assert_allclose(instance.directional(derivatives, state), a[:, j], rtol=1e-15, atol=0, err_msg=state)
        np.testing.assert_allclose(instance.directional(outputs, state), c[:, j], rtol=0, atol=0, err_msg=state)
    np.testing.assert_allclose(instance.directional(derivatives, "voltage"), b, rtol=1e-15, atol=0)
    instance.free()


def _refused(call, capfd, words):
    """``call`` fails with an error status and logs a message holding ``words``."""
    with pytest.raises(FMICallException) as refused:
        call()
    assert refused.value.status == 3  # fmi2Error, fmi3Error
    assert words in capfd.readouterr().out


@pytest.mark.parametrize("model_exchange", [False, True], ids=["co-simulation", "model-exchange"])
def test_which_variable_may_be_set_when_follows_the_standards_tables(plant, capfd, model_exchange):
    """Before initialisation is complete: inputs, parameters and states with initial="exact"; then
    inputs always, tunable parameters between steps (Co-Simulation) or in Event Mode (Model Exchange,
    not in Continuous-Time Mode), states only through the state-vector calls; never what the FMU
    computes (outputs, derivatives) nor a value reference it does not have."""
    expected_before = {"voltage": True, "b2": True, "state.v_r": True, "position": False, "der(state.x_r)": False}
    expected_running = {"voltage": True, "b2": not model_exchange, "state.v_r": False, "position": False,
                        "der(state.x_r)": False}
    words = {"position": "position is computed by the FMU and cannot be set",
             "der(state.x_r)": "a state derivative is computed by the FMU and cannot be set",
             "state.v_r": "state v_r can be set only before initialisation is complete",
             "b2": "tunable parameter b2 can be set only in Event Mode or between steps, not in Continuous-Time Mode"}
    for running, expected in ((False, expected_before), (True, expected_running)):
        for name, allowed in expected.items():
            instance = Instance(plant, model_exchange)
            instance.setup()
            if running:
                instance.initialise()
            if allowed:
                instance.set(name, 0.5)
            else:
                _refused(lambda: instance.set(name, 0.5), capfd, words[name])
            instance.free()
    instance = Instance(plant, model_exchange)
    instance.vr["nothing"] = 999
    _refused(lambda: instance.set("nothing", 0.5), capfd, "variable has value reference 999")
    instance.free()


def test_a_fixed_parameter_is_refused_once_initialised(native_shapers, capfd):
    path, _ = native_shapers[("zvd", 2)]
    assert [v.variability for v in read_model_description(str(path)).modelVariables if v.name == "Ts"] == ["fixed"]
    instance = Instance(path)
    instance.setup()
    instance.initialise({"Ts": 1e-3})
    _refused(lambda: instance.set("Ts", 2e-3), capfd, "parameter Ts is fixed and cannot be set after initialisation")
    instance.free()


def test_a_string_longer_than_the_fmu_holds_is_refused_naming_both_lengths(native_shapers, capfd):
    path, _ = native_shapers[("zvd", 2)]
    slave = FMU2Slave(guid=read_model_description(str(path)).guid, unzipDirectory=extract(str(path)),
                      modelIdentifier="Shaper", instanceName="core")
    slave.instantiate()
    vr = {v.name: v.valueReference for v in read_model_description(str(path)).modelVariables}
    _refused(lambda: slave.setString([vr["kind"]], ["z" * 100000]), capfd, "a value of 100000 characters is longer than the")
    slave.freeInstance()


def test_a_step_starts_at_the_fmus_time_within_a_hosts_rounding_and_an_empty_step_changes_nothing(plant, capfd):
    """FMI 2.0 sec. 4.2.2: a step starts at the previous communication point; a host's t += h may
    drift by rounding (DESIGN.md: never a failure), a step from elsewhere is an error."""
    instance = Instance(plant)
    instance.setup()
    instance.initialise({"voltage": 2.0})
    instance.step(0.0, 1e-3)
    before = instance.get(["position"])
    instance.step(1e-3, 0.0)  # an empty step: nothing moves, the time stays
    assert instance.get(["position"]) == before
    instance.step(1e-3 + 5e-13, 1e-3)  # rounding drift
    assert instance.get(["position"])[0] > before[0]
    _refused(lambda: instance.step(3e-3, 1e-3), capfd, "is not the FMU's time")
    instance.free()
    for h, shown in ((-1e-3, "-0.001"), (math.inf, "inf"), (math.nan, "nan")):
        instance = Instance(plant)
        instance.setup()
        instance.initialise()
        _refused(lambda: instance.step(0.0, h), capfd, f"communicationStepSize must be finite and >= 0, got {shown}")
        instance.free()


def test_after_an_error_only_a_reset_helps_and_the_reset_instance_runs_as_a_fresh_one(plant, capfd):
    def run(instance):
        instance.setup()
        instance.initialise({"voltage": 3.0, "b2": 2.5e3})
        rows = []
        for k in range(50):
            instance.step(k * 1e-4, 1e-4)
            rows.append(instance.get(["position", "deflection_1"]))
        return rows

    fresh = Instance(plant)
    expected = run(fresh)
    fresh.free()
    instance = Instance(plant)
    instance.setup()
    instance.initialise({"voltage": -1.0})
    instance.step(0.0, 1e-4)
    _refused(lambda: instance.step(0.0, -1.0), capfd, "communicationStepSize must be finite")
    _refused(lambda: instance.step(1e-4, 1e-4), capfd, "not allowed in Error")
    instance.fmu.reset()
    assert run(instance) == expected
    instance.free()


def test_the_experiment_must_start_at_a_finite_time_and_stop_after_it(plant, capfd):
    for start, stop, words in ((math.nan, None, "startTime must be finite, got nan"),
                               (1.0, 0.5, "stopTime must be >= startTime = 1, got 0.5")):
        instance = Instance(plant)

        def start_the_experiment():
            instance.setup(start, stop)  # FMI 2.0: fmi2SetupExperiment; FMI 3.0: at fmi3EnterInitializationMode
            instance.initialise()

        _refused(start_the_experiment, capfd, words)
        instance.free()


def test_debug_logging_takes_the_standards_categories_and_refuses_others(plant, capfd):
    instance = Instance(plant)
    instance.fmu.setDebugLogging(True, ["logAll", "logStatusError"])
    instance.fmu.setDebugLogging(False, [])
    _refused(lambda: instance.fmu.setDebugLogging(True, ["logEvents"]), capfd,
             "unknown log category logEvents (known: logAll, logStatusError)")
    instance.free()


def test_the_state_vector_calls_check_its_length_and_its_values(plant, capfd):
    instance = Instance(plant, model_exchange=True)
    instance.setup()
    instance.initialise()
    _refused(lambda: instance.derivatives(np.zeros(5)), capfd, "nx must be 6, got 5")
    instance.free()
    instance = Instance(plant, model_exchange=True)
    instance.setup()
    instance.initialise()
    _refused(lambda: instance.derivatives([0.0, math.nan, 0, 0, 0, 0]), capfd, "state v_r must be finite, got nan")
    instance.free()
