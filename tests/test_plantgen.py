"""The plant-FMU generator (shapefmu.fmi.native): native FMI 2.0 ME + CS FMUs from models/.

References: the exact solution of the LTI (scipy expm) for Model Exchange, the exact zero-order-hold
discretisation (scipy expm of the augmented matrix) for Co-Simulation, scipy's solve_ivp for the
nonlinear pendulum, finite differences for the directional derivatives, and the plant models of
shapefmu.plants loaded from the same files.
"""

import ctypes
import math
import re
import shutil

import numpy as np
import pytest
import scipy.linalg
from support.fixtures_plants import LINEAR_PLANTS, MODELS
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model, FMU2Slave, fmi2Error
from fmpy.validation import validate_fmu
from scipy.integrate import solve_ivp

from shapefmu.cosim.fmpy_log import listening
from shapefmu.plants import load, loads

# Horizons: a few periods of each plant's slowest flexible mode; CS step: well below its fastest.
STOP_TIME = {"disk_drive": 2e-3, "disk_drive_back_emf": 2e-3, "linear_synchronous_motor": 0.2,
             "ten_pendula": 5.0, "mass_spring_chain": 1.0, "printer_bed": 0.2, "gantry_crane": 5.0}
STEP = {"disk_drive": 1e-5, "disk_drive_back_emf": 1e-5, "linear_synchronous_motor": 1e-3,
        "ten_pendula": 1e-2, "mass_spring_chain": 5e-3, "printer_bed": 1e-3, "gantry_crane": 1e-2}
INPUT_SCALE = {"disk_drive": 11.0, "disk_drive_back_emf": 11.0, "linear_synchronous_motor": 1.0,
               "ten_pendula": 0.7, "mass_spring_chain": 10.0, "printer_bed": 1.0, "gantry_crane": 1.0}


def variables(fmu):
    return {v.name: v for v in read_model_description(str(fmu)).modelVariables}


def relative_error(actual: dict, reference: dict) -> float:
    """max over outputs of max_t |actual - reference| / max_t |reference|."""
    return max(np.max(np.abs(np.asarray(actual[k]) - reference[k])) / np.max(np.abs(reference[k])) for k in reference)


def zoh(plant, h):
    """Exact zero-order-hold discretisation: expm([[A, B], [0, 0]] h) = [[Phi, Gamma], [0, I]]."""
    n, m = plant.B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = plant.A * h, plant.B * h
    E = scipy.linalg.expm(M)
    return E[:n, :n], E[:n, n:]


def zoh_reference(plant, steps, inputs, x0=None):
    """Outputs after each step of x+ = Phi(h) x + Gamma(h) u, y = C x + D u."""
    x = np.zeros(plant.n_states) if x0 is None else np.array(x0, dtype=float)
    ys = []
    for h, u in zip(steps, inputs):
        Phi, Gamma = zoh(plant, h)
        x = Phi @ x + Gamma @ np.atleast_1d(u)
        ys.append(plant.C @ x + plant.D @ np.atleast_1d(u))
    return {name: np.array(ys)[:, i] for i, name in enumerate(plant.outputs)}, x


class Instance:
    """An fmpy instance of a plant FMU that records what the FMU logs."""

    def __init__(self, fmu, kind="CoSimulation", name="plant"):
        self.description = read_model_description(str(fmu))
        self.refs = {v.name: v.valueReference for v in self.description.modelVariables}
        self.messages = messages = []  # the sink holds the list, not the instance: it lives as long as the process
        cls = FMU2Slave if kind == "CoSimulation" else FMU2Model
        self.fmu = cls(guid=self.description.guid, unzipDirectory=extract(str(fmu)),
                       modelIdentifier=self.description.coSimulation.modelIdentifier, instanceName=name)
        self.callbacks = listening(lambda status, category, message: messages.append((status, category, message)))
        self.fmu.instantiate(callbacks=self.callbacks)

    def start(self, start_values=None):
        self.fmu.setupExperiment(startTime=0.0)
        self.set(start_values or {})
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        return self

    def set(self, values):
        for name, value in values.items():
            self.fmu.setReal([self.refs[name]], [value])

    def get(self, names):
        return self.fmu.getReal([self.refs[n] for n in names])

    def errors(self):
        return [m for status, _, m in self.messages if status == fmi2Error]

    def free(self):
        self.fmu.freeInstance()


def run_steps(instance, outputs, steps, input_name=None, inputs=None, t0=0.0):
    t = t0
    ys = []
    for k, h in enumerate(steps):
        if input_name is not None:
            instance.set({input_name: float(inputs[k])})
        instance.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        t += h
        ys.append(instance.get(outputs))
    return {name: np.array(ys)[:, i] for i, name in enumerate(outputs)}


# ------------------------------------------------------------------------------------------ validity

def test_every_plant_of_models_is_built(plant_fmus):
    assert set(plant_fmus) == {*LINEAR_PLANTS, "pendulum"}


@pytest.mark.parametrize("name", [*LINEAR_PLANTS, "pendulum"])
def test_fmu_passes_fmpy_validation(plant_fmus, name):
    assert validate_fmu(str(plant_fmus[name])) == []


@pytest.mark.parametrize("name", LINEAR_PLANTS)
def test_fmu_variables_are_the_model_file_names(plant_fmus, name):
    plant = load(MODELS / f"{name}.toml")
    names = variables(plant_fmus[name])
    for signal in (*plant.inputs, *plant.outputs):
        assert signal in names
    for key, parameter in plant.parameters.items():
        values = parameter.value if isinstance(parameter.value, tuple) else (parameter.value,)
        for i, value in enumerate(values, 1):
            variable = names[f"{key}[{i}]" if isinstance(parameter.value, tuple) else key]
            assert float(variable.start) == value and variable.unit == parameter.unit


# ------------------------------------------------------------------------------------------ accuracy

@pytest.mark.parametrize("name", LINEAR_PLANTS)
def test_model_exchange_matches_exact_lti_solution(plant_fmus, name):
    """fmpy's CVode on the ME interface against x(t) = e^{At} x0 + int_0^t e^{As} ds B u."""
    plant = load(MODELS / f"{name}.toml")
    names = variables(plant_fmus[name])
    u = INPUT_SCALE[name]
    start = {plant.inputs[0]: u}
    x0 = np.zeros(plant.n_states)
    if all(f"state.{s}" in names for s in plant.states):  # physical coordinates: start off rest too
        nominal = np.array([float(names[f"state.{s}"].nominal) for s in plant.states])
        x0 = nominal * np.linspace(-1.0, 1.0, plant.n_states)
        start.update({f"state.{s}": v for s, v in zip(plant.states, x0)})
    stop = STOP_TIME[name]
    result = simulate_fmu(str(plant_fmus[name]), fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-12,
                          start_values=start, stop_time=stop, output_interval=stop / 200, output=list(plant.outputs))
    n = plant.n_states
    M = np.zeros((n + 1, n + 1))
    M[:n, :n], M[:n, n:] = plant.A, plant.B
    reference = {k: [] for k in plant.outputs}
    for t in result["time"]:
        x = scipy.linalg.expm(M * t) @ np.append(x0, u)
        for k, y in zip(plant.outputs, plant.C @ x[:n] + plant.D[:, 0] * u):
            reference[k].append(y)
    error = relative_error({k: result[k] for k in plant.outputs}, {k: np.array(v) for k, v in reference.items()})
    assert error < 1e-8, f"{name}: ME relative error {error:.2e}"


@pytest.mark.parametrize("name", LINEAR_PLANTS)
def test_cosimulation_is_the_exact_zero_order_hold_with_variable_steps(plant_fmus, name):
    plant = load(MODELS / f"{name}.toml")
    rng = np.random.default_rng(8)
    h = STEP[name]
    steps = h * rng.choice([0.5, 1.0, 1.0, 1.0, 2.5], size=int(STOP_TIME[name] / h))
    inputs = INPUT_SCALE[name] * rng.choice([-1.0, 0.0, 1.0], size=steps.size)
    instance = Instance(plant_fmus[name]).start()
    actual = run_steps(instance, plant.outputs, steps, plant.inputs[0], inputs)
    assert instance.errors() == []
    instance.free()
    reference, _ = zoh_reference(plant, steps, inputs)
    error = relative_error(actual, reference)
    assert error < 1e-12, f"{name}: CS relative error {error:.2e}"


def test_parameter_change_between_runs_takes_effect(plant_fmus):
    """f[1] = 2.5 kHz set before initialisation gives the plant of the edited model file."""
    text = (MODELS / "disk_drive.toml").read_text().replace("[2.0e3, 3.0e3]", "[2.5e3, 3.0e3]")
    edited = loads(text)
    steps, inputs = np.full(200, 1e-5), np.full(200, 11.0)
    runs = []
    for start in ({}, {"f[1]": 2.5e3}):
        instance = Instance(plant_fmus["disk_drive"]).start(start)
        runs.append(run_steps(instance, edited.outputs, steps, "voltage", inputs))
        instance.free()
    reference, _ = zoh_reference(edited, steps, inputs)
    assert relative_error(runs[1], reference) < 1e-12
    assert relative_error(runs[0], reference) > 0.1  # the default 2 kHz mode is another plant


def test_tunable_parameter_set_between_steps_applies_from_the_next_step(plant_fmus):
    plant = load(MODELS / "disk_drive.toml")
    edited = loads((MODELS / "disk_drive.toml").read_text().replace("[0.01, 0.01]", "[0.2, 0.01]"))
    steps, inputs = np.full(100, 1e-5), np.full(100, 11.0)
    instance = Instance(plant_fmus["disk_drive"]).start()
    first = run_steps(instance, plant.outputs, steps, "voltage", inputs)
    instance.set({"zeta[1]": 0.2})
    second = run_steps(instance, plant.outputs, steps, "voltage", inputs, t0=steps.sum())
    instance.free()
    reference_first, x = zoh_reference(plant, steps, inputs)
    reference_second, _ = zoh_reference(edited, steps, inputs, x0=x)
    assert relative_error(first, reference_first) < 1e-12
    assert relative_error(second, reference_second) < 1e-12


def pendulum_reference(parameters, x0, steps, inputs):
    """solve_ivp (rtol 1e-10) of L theta'' = -g sin(theta) - a cos(theta) - c L theta', step by step."""
    L, g, c = parameters

    def rhs(t, s, a):
        x, v, theta, omega = s
        return [v, a, omega, -(g * math.sin(theta) + a * math.cos(theta)) / L - c * omega]

    state, t, ys = np.array(x0, dtype=float), 0.0, []
    for h, a in zip(steps, inputs):
        state = solve_ivp(rhs, (t, t + h), state, args=(a,), method="DOP853", rtol=1e-10, atol=1e-12).y[:, -1]
        t += h
        ys.append([state[0], state[2], state[0] + L * math.sin(state[2])])
    ys = np.array(ys)
    return {"cart_position": ys[:, 0], "theta": ys[:, 1], "bob_position": ys[:, 2]}


def test_nonlinear_pendulum_cosimulation_matches_solve_ivp_at_large_angles(plant_fmus):
    steps = np.full(300, 0.01)
    inputs = np.where(np.arange(300) < 50, 3.0, np.where(np.arange(300) < 100, -3.0, 0.0))
    start = {"state.theta": 1.2, "c": 0.05, "L": 0.8}
    instance = Instance(plant_fmus["pendulum"]).start(start)
    actual = run_steps(instance, ["cart_position", "theta", "bob_position"], steps, "acceleration", inputs)
    instance.free()
    reference = pendulum_reference((0.8, 9.80665, 0.05), [0.0, 0.0, 1.2, 0.0], steps, inputs)
    assert max(np.max(np.abs(actual[k] - reference[k])) for k in reference) < 1e-6
    assert np.max(np.abs(reference["theta"])) > 1.0  # far outside the small-angle range


def directional_vs_finite_differences(fmu, start, eps=1e-6):
    """(max |analytic - central difference|, max |analytic|) over every d(derivative or output) /
    d(state or input), at the state and input given by ``start``."""
    description = read_model_description(str(fmu))
    states = [v for v in description.modelVariables if v.name.startswith("state.")]
    unknowns = [v.valueReference for v in description.modelVariables
                if v.name.startswith("der(") or v.causality == "output"]
    inputs = [v for v in description.modelVariables if v.causality == "input"]
    instance = Instance(fmu, kind="ModelExchange").start(start)
    model = instance.fmu
    model.enterContinuousTimeMode()
    x = np.array(instance.get([v.name for v in states]))
    worst, scale = 0.0, 0.0
    for known in states + inputs:
        analytic = np.array(model.getDirectionalDerivative(unknowns, [known.valueReference], [1.0]))
        base = instance.get([known.name])[0]

        def evaluate(delta):
            if known in states:
                shifted = x.copy()
                shifted[states.index(known)] += delta
                model.setContinuousStates(shifted.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), len(shifted))
            else:
                model.setReal([known.valueReference], [base + delta])
            return np.array(model.getReal(unknowns))

        numeric = (evaluate(eps) - evaluate(-eps)) / (2 * eps)
        evaluate(0.0)
        worst = max(worst, np.max(np.abs(analytic - numeric)))
        scale = max(scale, np.max(np.abs(analytic)))
    instance.free()
    return worst, scale


def test_pendulum_directional_derivatives_match_finite_differences(plant_fmus):
    worst, scale = directional_vs_finite_differences(
        plant_fmus["pendulum"], {"state.theta": 1.1, "state.omega": -0.7, "acceleration": 2.0, "c": 0.1})
    assert worst < 1e-6 and scale > 1.0


def test_linear_directional_derivatives_are_the_state_space_matrices(plant_fmus):
    plant = load(MODELS / "mass_spring_chain.toml")
    instance = Instance(plant_fmus["mass_spring_chain"], kind="ModelExchange").start()
    refs = instance.refs
    der = [refs[f"der(state.{s})"] for s in plant.states]
    out = [refs[k] for k in plant.outputs]
    for j, s in enumerate(plant.states):
        column = instance.fmu.getDirectionalDerivative(der + out, [refs[f"state.{s}"]], [1.0])
        np.testing.assert_allclose(column, np.concatenate([plant.A[:, j], plant.C[:, j]]), rtol=1e-14, atol=1e-14)
    column = instance.fmu.getDirectionalDerivative(der + out, [refs["force"]], [1.0])
    np.testing.assert_allclose(column, np.concatenate([plant.B[:, 0], plant.D[:, 0]]), rtol=1e-14, atol=1e-14)
    instance.free()


def test_sprung_mass_is_a_tunable_parameter_that_moves_the_mode_as_sqrt_k_over_m(plant_fmus):
    """The printer bed gaining 300 g: masses[1] = 1.3 kg set in the FMU gives, in the state matrix it
    reports (directional derivatives), the mode omega = sqrt(k / m), zeta = c / (2 sqrt(k m)) of the
    spring and damper written in models/printer_bed.toml (Marlin #26655: 30 Hz -> 26.3 Hz)."""
    import tomllib

    written = tomllib.loads((MODELS / "printer_bed.toml").read_text())["parameters"]
    k, c = written["stiffnesses"]["value"][0], written["dampers"]["value"][0]
    names = variables(plant_fmus["printer_bed"])
    assert names["masses[1]"].causality == "parameter" and names["masses[1]"].variability == "tunable"
    instance = Instance(plant_fmus["printer_bed"], kind="ModelExchange").start({"masses[1]": 1.3})
    refs, states = instance.refs, ("x", "v", "e_1", "de_1")
    der = [refs[f"der(state.{s})"] for s in states]
    A = np.array([instance.fmu.getDirectionalDerivative(der, [refs[f"state.{s}"]], [1.0]) for s in states]).T
    instance.free()
    poles = [p for p in np.linalg.eigvals(A) if p.imag > 0]
    omega, zeta = abs(poles[0]), -poles[0].real / abs(poles[0])
    assert omega == pytest.approx(math.sqrt(k / 1.3), rel=1e-12)
    assert zeta == pytest.approx(c / (2.0 * math.sqrt(k * 1.3)), rel=1e-12)
    assert omega / (2.0 * math.pi) == pytest.approx(30.0 / math.sqrt(1.3), rel=1e-9)


# ------------------------------------------------------------------------------------------ FMU state

@pytest.mark.parametrize("name", ["disk_drive", "pendulum"])
def test_fmu_state_get_set_and_serialise_round_trip_exactly(plant_fmus, name):
    fmu = plant_fmus[name]
    names = variables(fmu)
    outputs = [k for k, v in names.items() if v.causality == "output"]
    input_name = next(k for k, v in names.items() if v.causality == "input")
    h = 1e-5 if name == "disk_drive" else 1e-2
    inputs = np.sin(np.arange(100))
    instance = Instance(fmu).start()
    run_steps(instance, outputs, np.full(50, h), input_name, inputs[:50])
    state = instance.fmu.getFMUstate()
    serialised = instance.fmu.serializeFMUstate(state)
    after = run_steps(instance, outputs, np.full(50, h), input_name, inputs[50:], t0=50 * h)
    instance.fmu.setFMUstate(state)
    again = run_steps(instance, outputs, np.full(50, h), input_name, inputs[50:], t0=50 * h)
    instance.fmu.freeFMUstate(state)
    instance.free()
    fresh = Instance(fmu, name="fresh").start()
    restored = fresh.fmu.deSerializeFMUstate(serialised)
    fresh.fmu.setFMUstate(restored)
    resumed = run_steps(fresh, outputs, np.full(50, h), input_name, inputs[50:], t0=50 * h)
    fresh.fmu.freeFMUstate(restored)
    fresh.free()
    for k in outputs:
        assert np.array_equal(after[k], again[k]) and np.array_equal(after[k], resumed[k])


# ------------------------------------------------------------------------------------------ bad input

def refused(instance, call, pattern):
    """The call returns fmi2Error and the FMU logs a message matching ``pattern``."""
    with pytest.raises(FMICallException) as raised:
        call()
    assert raised.value.status == fmi2Error
    assert any(re.search(pattern, m) for m in instance.errors()), instance.errors()


def test_nan_input_is_refused_with_a_logged_error(plant_fmus):
    instance = Instance(plant_fmus["disk_drive"]).start()
    refused(instance, lambda: instance.set({"voltage": float("nan")}), r"voltage must be finite, got nan")
    instance.free()


def test_negative_step_is_refused_with_a_logged_error(plant_fmus):
    instance = Instance(plant_fmus["disk_drive"]).start()
    refused(instance, lambda: instance.fmu.doStep(0.0, -1e-5), r"communicationStepSize must be finite and >= 0, got -1e-05")
    instance.free()


def test_fixed_parameter_after_initialisation_is_refused(plant_fmus):
    instance = Instance(plant_fmus["linear_synchronous_motor"]).start()
    refused(instance, lambda: instance.set({"den[2]": 80.0}), r"parameter den\[2\] is fixed")
    instance.free()


def test_parameter_out_of_range_is_refused(plant_fmus):
    instance = Instance(plant_fmus["ten_pendula"]).start()
    refused(instance, lambda: instance.set({"lengths[3]": -0.5}), r"lengths\[3\] must be > 0, got -0.5")
    instance.free()


def test_calls_out_of_order_are_refused_until_reset(plant_fmus):
    instance = Instance(plant_fmus["disk_drive"])
    refused(instance, lambda: instance.fmu.doStep(0.0, 1e-5), r"fmi2DoStep: not allowed in Instantiated")
    refused(instance, lambda: instance.fmu.enterInitializationMode(), r"not allowed in Error")
    instance.fmu.reset()
    instance.start()
    refused(instance, lambda: instance.fmu.setupExperiment(startTime=0.0), r"fmi2SetupExperiment: not allowed in Step Complete")
    instance.free()


def test_model_exchange_call_on_a_cosimulation_instance_is_refused(plant_fmus):
    instance = Instance(plant_fmus["disk_drive"]).start()
    get_derivatives = instance.fmu.dll.fmi2GetDerivatives  # fmpy's FMU2Slave does not bind it
    get_derivatives.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_double), ctypes.c_size_t]
    derivatives = (ctypes.c_double * 6)()
    assert get_derivatives(instance.fmu.component, derivatives, 6) == fmi2Error
    assert any("fmi2GetDerivatives: only for Model Exchange" in m for m in instance.errors())
    instance.free()


# ------------------------------------------------------------------------------------------ sources

@pytest.mark.skipif(shutil.which("cmake") is None, reason="fmpy rebuilds FMUs from their sources with CMake")
def test_fmpy_rebuild_from_the_shipped_sources_gives_the_same_results(plant_fmus, tmp_path):
    from fmpy.build import build_platform_binary

    fmu = plant_fmus["mass_spring_chain"]
    unzipped = tmp_path / "unzipped"
    extract(str(fmu), str(unzipped))
    for binary in (unzipped / "binaries").rglob("*.so"):
        binary.unlink()
    build_platform_binary(str(unzipped))
    assert list((unzipped / "binaries").rglob("*.so"))
    rebuilt = tmp_path / "Rebuilt.fmu"
    shutil.make_archive(str(rebuilt.with_suffix("")), "zip", unzipped)
    rebuilt.with_suffix(".zip").rename(rebuilt)
    plant = load(MODELS / "mass_spring_chain.toml")
    steps, inputs = np.full(100, 5e-3), 10.0 * np.sign(np.sin(np.arange(100) / 7))
    results = []
    for path in (fmu, rebuilt):
        instance = Instance(path).start({"springs[2]": 350.0})
        results.append(run_steps(instance, plant.outputs, steps, "force", inputs))
        instance.free()
    assert relative_error(results[1], results[0]) < 1e-12


# ------------------------------------------------------------------------------------------ other inputs

def test_python_control_lti_becomes_a_state_space_fmu_with_tunable_matrices(tmp_path):
    import control

    from shapefmu.fmi.native import build_plant_fmu
    from shapefmu.plants import as_plant

    system = control.ss(control.tf([400.0], [1.0, 4.0, 400.0]), name="resonator")
    fmu = build_plant_fmu(system, tmp_path / "Resonator.fmu")
    assert validate_fmu(str(fmu)) == []
    assert "A[2,1]" in variables(fmu)
    plant = as_plant(system)
    steps, inputs = np.full(300, 1e-3), np.sign(np.sin(np.arange(300) / 20))
    instance = Instance(fmu).start()
    actual = run_steps(instance, plant.outputs, steps, plant.inputs[0], inputs)
    instance.free()
    assert relative_error(actual, zoh_reference(plant, steps, inputs)[0]) < 1e-12


def test_library_plant_keeps_its_physical_parameters(tmp_path):
    from shapefmu.fmi.native import build_plant_fmu
    from shapefmu.plants import disk_drive

    fmu = build_plant_fmu(disk_drive(back_emf=True), tmp_path / "Library.fmu", name="library_disk_drive")
    names = variables(fmu)
    assert names["omega[2]"].unit == "rad/s" and float(names["omega[2]"].start) == pytest.approx(2 * math.pi * 3e3)
    assert float(names["rigid_damping"].start) == pytest.approx(9.8e-2**2 / (7.25 * 5e-6))


def test_cli_plant_build_writes_a_valid_fmu_and_refuses_a_missing_model(tmp_path, capsys):
    from shapefmu.cli import main

    out = tmp_path / "DiskDrive.fmu"
    assert main(["plant", "build", str(MODELS / "disk_drive.toml"), "-o", str(out)]) == 0
    assert validate_fmu(str(out)) == []
    with pytest.raises(SystemExit) as exit_:
        main(["plant", "build", str(tmp_path / "missing.toml"), "-o", str(out)])
    assert exit_.value.code == 2
    assert "missing.toml" in capsys.readouterr().err
