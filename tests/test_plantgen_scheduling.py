"""Plant FMUs whose modes move (issue 37): the scheduling input of models/printer_bed.toml and
models/gantry_crane.toml is an input of their native FMUs.

References: the design layer's plant at each value of the input (``ScheduledPlant.at``, the plant
library's numpy matrices, not the FMU generator's CasADi mapping) discretised exactly with scipy's
expm, and the closed forms omega = sqrt(k / m) (bed) and omega = sqrt(g / L) (crane).
"""

import math

import numpy as np
import pytest
from support.fixtures_plants import MODELS
from test_plantgen import Instance, variables, zoh

from shapefmu.plants import load_scheduled

G = 9.80665
# Per plant: the communication step, the steps, the command's amplitude, and the scheduling input's
# values, one per segment of equal length (the bed gains 300 g in steps, the rope pays out and back).
CASES = {
    "printer_bed": (1e-3, 240, 1.0, [0.0, 100.0, 300.0, 150.0]),
    "gantry_crane": (1e-2, 400, 1.0, [1.0, 2.0, 0.5, 1.4]),
}


def schedule_of(values, steps):
    return np.repeat(values, steps // len(values))


@pytest.mark.parametrize("name", list(CASES))
def test_scheduling_input_is_an_fmu_input_with_its_range_and_start(plant_fmus, name):
    scheduling = load_scheduled(MODELS / f"{name}.toml").scheduling
    variable = variables(plant_fmus[name])[scheduling.name]
    assert variable.causality == "input" and variable.unit == scheduling.unit
    assert (float(variable.start), float(variable.min), float(variable.max)) == \
        (scheduling.start, scheduling.minimum, scheduling.maximum)


@pytest.mark.parametrize("name", list(CASES))
def test_cosimulation_is_the_exact_hold_of_the_plant_at_the_input_in_force(plant_fmus, name):
    """Command and scheduling input held over each step: every step is the exact zero-order hold of
    the design layer's plant at that step's value, the state carried across each change."""
    h, steps, amplitude, values = CASES[name]
    scheduled = load_scheduled(MODELS / f"{name}.toml")
    commands = amplitude * np.sign(np.sin(np.arange(steps) / 7.0))
    schedule = schedule_of(values, steps)
    instance = Instance(plant_fmus[name]).start()
    outputs = scheduled.plant.outputs
    actual = []
    for k in range(steps):
        instance.set({scheduled.plant.inputs[0]: float(commands[k]), scheduled.scheduling.name: float(schedule[k])})
        instance.fmu.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
        actual.append(instance.get(outputs))
    assert instance.errors() == []
    instance.free()
    x = np.zeros(scheduled.plant.n_states)
    reference = []
    for u, s in zip(commands, schedule):
        plant = scheduled.at(s)
        Phi, Gamma = zoh(plant, h)
        x = Phi @ x + Gamma[:, 0] * u
        reference.append(plant.C @ x + plant.D[:, 0] * u)
    actual, reference = np.array(actual), np.array(reference)
    scale = np.abs(reference).max(axis=0)
    assert np.all(scale > 0)
    assert (np.abs(actual - reference).max(axis=0) / scale).max() < 1e-12


def lowest_mode(instance, states):
    """(omega, zeta) of the lowest oscillatory pole of the state matrix the ME FMU reports."""
    refs = instance.refs
    der = [refs[f"der(state.{s})"] for s in states]
    A = np.array([instance.fmu.getDirectionalDerivative(der, [refs[f"state.{s}"]], [1.0]) for s in states]).T
    pole = min((p for p in np.linalg.eigvals(A) if p.imag > 0), key=abs)
    return abs(pole), -pole.real / abs(pole)


def test_bed_mode_follows_the_added_mass_as_sqrt_k_over_m(plant_fmus):
    """30 Hz with the bed alone, 30 / sqrt(1.3) = 26.3 Hz with 300 g on it (Marlin #26655)."""
    import tomllib

    written = tomllib.loads((MODELS / "printer_bed.toml").read_text())["parameters"]
    k, c, m = written["stiffnesses"]["value"][0], written["dampers"]["value"][0], written["masses"]["value"][0]
    instance = Instance(plant_fmus["printer_bed"], kind="ModelExchange").start()
    for grams in (0.0, 120.0, 300.0):
        instance.set({"added_mass": grams})
        omega, zeta = lowest_mode(instance, ("x", "v", "e_1", "de_1"))
        mass = m + grams / 1000.0
        assert omega == pytest.approx(math.sqrt(k / mass), rel=1e-12)
        assert zeta == pytest.approx(c / (2.0 * math.sqrt(k * mass)), rel=1e-12)
    assert omega / (2.0 * math.pi) == pytest.approx(30.0 / math.sqrt(1.3), rel=1e-9)
    instance.free()


def test_crane_swing_follows_the_rope_length_as_sqrt_g_over_l(plant_fmus):
    instance = Instance(plant_fmus["gantry_crane"], kind="ModelExchange").start()
    states = [v.name[len("state."):] for v in instance.description.modelVariables if v.name.startswith("state.")]
    for length in (0.5, 1.3, 2.0):
        instance.set({"rope_length": length})
        omega, zeta = lowest_mode(instance, states)
        assert omega == pytest.approx(math.sqrt(G / length), rel=1e-12)
        assert zeta == pytest.approx(0.01, rel=1e-9)
    instance.free()


@pytest.mark.parametrize("name, value", [("printer_bed", 300.5), ("printer_bed", -1.0), ("gantry_crane", 0.4),
                                         ("gantry_crane", float("nan"))])
def test_scheduling_input_outside_its_range_is_refused_with_a_logged_error(plant_fmus, name, value):
    from fmpy.fmi1 import FMICallException

    scheduling = load_scheduled(MODELS / f"{name}.toml").scheduling
    instance = Instance(plant_fmus[name]).start()
    with pytest.raises(FMICallException):
        instance.set({scheduling.name: value})
    assert any(f"scheduling input {scheduling.name} must be in [{scheduling.minimum:g}, {scheduling.maximum:g}]" in m
               for m in instance.errors())
    instance.free()


@pytest.mark.parametrize("name", list(CASES))
def test_moving_mode_runs_identically_in_fmpy_libcosim_and_ecos(plant_fmus, quiet_libcosim, name):
    from support.hosts import HOSTS

    h, steps, amplitude, values = CASES[name]
    scheduled = load_scheduled(MODELS / f"{name}.toml")
    command, scheduling = scheduled.plant.inputs[0], scheduled.scheduling.name
    inputs = [{command: amplitude * math.copysign(1.0, math.sin(k / 7.0)), scheduling: float(s)}
              for k, s in enumerate(schedule_of(values, steps))]
    runs = {host: np.array(run(plant_fmus[name], inputs, h)) for host, run in HOSTS.items()}
    scale = np.abs(runs["fmpy"]).max(axis=0)
    for host in ("libcosim", "ecos"):
        assert runs[host].shape == runs["fmpy"].shape
        assert np.all(np.abs(runs[host] - runs["fmpy"]).max(axis=0) <= 1e-12 * scale), host
