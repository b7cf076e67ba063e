"""FMI 3.0 components: the plant generator's FMI 3.0 target, and the master running it beside FMI 2.0
FMUs -- against the all-FMI 2.0 system, fmpy, and the exact solution."""

from __future__ import annotations

import re

import numpy as np
import pytest
import scipy.linalg

from shapefmu.cosim import Master, simulate
from shapefmu.fmi.ssp import System, read_ssp
from shapefmu.plants import load

MODEL = "models/disk_drive.toml"
PLANT_OUTPUTS = ["plant.position", "plant.deflection_1", "plant.deflection_2"]


@pytest.fixture(scope="module")
def fmus(builds):
    return {"plant2": builds.plant(MODEL), "plant3": builds.plant(MODEL, fmi_version="3.0"),
            "shaper": builds.pythonfmu("Shaper")}


def test_the_fmi3_plant_passes_fmpy_validation(fmus):
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(fmus["plant3"])) == []
    description = read_model_description(str(fmus["plant3"]))
    assert description.fmiVersion == "3.0"
    assert {v.type for v in description.modelVariables} == {"Float64"}


def test_the_fmi3_plant_steps_as_the_fmi2_plant_in_fmpy(fmus):
    from fmpy import simulate_fmu

    options = dict(stop_time=1e-3, step_size=1e-5, output_interval=1e-5, output=["position", "deflection_1"])
    two = simulate_fmu(str(fmus["plant2"]), start_values={"voltage": 11.0, "f[1]": 2100.0}, **options)
    # FMI 3.0: the mode frequencies are the array parameter f (its one element here)
    three = simulate_fmu(str(fmus["plant3"]), start_values={"voltage": 11.0, "f": [2100.0, fmi2_start(fmus, "f[2]")]},
                         **options)
    assert np.ptp(two["position"]) > 1e-3
    for name in ("time", "position", "deflection_1"):
        np.testing.assert_array_equal(three[name], two[name])


def fmi2_start(fmus, name: str) -> float:
    from fmpy import read_model_description

    return next(float(v.start) for v in read_model_description(str(fmus["plant2"])).modelVariables if v.name == name)


def shaped_seek(fmus, plant: str) -> System:
    return (System("shaped_seek")
            .add("shaper", fmus["shaper"], {"kind": "zvd", "f[1]": 2000.0, "zeta[1]": 0.01, "Ts": 1e-6, "u": 1.0})
            .add("plant", fmus[plant], {"f[1]": 2100.0})
            .connect("shaper.y", "plant.voltage", factor=11.0))


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
@pytest.mark.parametrize("native", [True, False], ids=["C", "Python"])
def test_an_fmi3_plant_beside_an_fmi2_shaper_equals_the_all_fmi2_system(fmus, tmp_path, algorithm, native):
    results = {}
    for plant in ("plant2", "plant3"):
        ssp = shaped_seek(fmus, plant).write_ssp(tmp_path / f"{plant}.ssp")
        with Master(read_ssp(ssp), 1e-6, algorithm=algorithm, native=native, record=["shaper.y", *PLANT_OUTPUTS]) as master:
            assert master.loop_kind == ("C" if native else "Python")
            assert [u.prefix for u in master.units] == ["fmi2", "fmi3" if plant == "plant3" else "fmi2"]
            results[plant] = master.run(8e-4)
    assert np.ptp(results["plant2"]["plant.deflection_1"]) > 1e-6  # the move and the vibration happen
    for name in results["plant2"].dtype.names:
        np.testing.assert_allclose(results["plant3"][name], results["plant2"][name], rtol=0, atol=1e-12, err_msg=name)


def test_an_fmi3_model_exchange_plant_matches_the_exact_solution(fmus):
    volts = 11.0
    with Master(System().add("plant", fmus["plant3"], {"voltage": volts}), 1e-5, model_exchange=["plant"],
                tolerance=1e-10, record=PLANT_OUTPUTS) as master:
        assert master.units[0].interface == "ModelExchange" and master.units[0].prefix == "fmi3"
        result = master.run(2e-3)
    system = load(MODEL).to_statespace()
    A, B, C, D = (np.asarray(m, dtype=float) for m in (system.A, system.B, system.C, system.D))
    n = A.shape[0]
    augmented = np.zeros((n + 1, n + 1))
    augmented[:n, :n], augmented[:n, n:] = A, B
    want = np.array([C @ scipy.linalg.expm(augmented * t)[:n, n:] @ [volts] + D @ [volts] for t in result["time"]])
    for j, name in enumerate(PLANT_OUTPUTS):
        scale = np.max(np.abs(want[:, j]))
        np.testing.assert_allclose(result[name], want[:, j], rtol=0, atol=1e-6 * scale, err_msg=name)


def test_an_fmi3_parameter_error_names_the_component_and_the_call(fmus):
    from shapefmu.cosim import CosimError

    # f is an FMI 3.0 array: its element is set with the whole array, the other element at its start
    with pytest.raises(CosimError, match=rf"component 'plant' \({re.escape(fmus['plant3'].name)}\): fmi3SetFloat64\(f=\[-1.0, "
                                         r"3000.0\]\) returned fmi3Error.*parameter f\[1\] must be > 0, got -1"):
        simulate(System().add("plant", fmus["plant3"], {"f[1]": -1.0}), 1e-4, 1e-5)


def test_calls_on_a_freed_fmi3_plant_are_refused_and_a_second_free_does_nothing(fmus, capfd):
    # What OMSimulator does to FMI 2.0 instances after a failed initialisation (README, OMSimulator):
    # the FMI 3.0 wrapper keeps the same registry of live instances as the generic FMI 2.0 layer.
    from fmpy import extract, read_model_description
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi3 import FMU3Slave

    md = read_model_description(str(fmus["plant3"]))
    slave = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(fmus["plant3"])),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="freed")
    slave.instantiate()
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    slave.doStep(0.0, 1e-4)
    slave.fmi3FreeInstance(slave.component)
    for call in (slave.terminate, lambda: slave.doStep(1e-4, 1e-4), lambda: slave.getFloat64([0])):
        with pytest.raises(FMICallException) as refused:
            call()
        assert refused.value.status == 3  # fmi3Error
    slave.fmi3FreeInstance(slave.component)  # a second free does nothing
    slave.freeLibrary()
    stderr = capfd.readouterr().err
    for function in ("fmi3Terminate", "fmi3DoStep", "fmi3GetFloat64"):
        assert stderr.count(f"shapefmu FMU: {function} called on an instance that is not live (already freed?)") == 1


# ---------------------------------------------------------------------------------------------
# every type across versions: TypedStair (FMI 2.0) and TypedStair3 (FMI 3.0), one model

TYPED_RECORD = ["a.counter", "a.n_out", "a.e_out", "a.b_out", "a.s_out", "a.x_out", "a.level",
                "b.counter", "b.n_out", "b.e_out", "b.b_out", "b.s_out", "b.x_out", "b.level"]


@pytest.fixture(scope="module")
def stairs(tmp_path_factory):
    from support.c_fmus import build_typed_stair, build_typed_stair3

    folder = tmp_path_factory.mktemp("stairs")
    return {"2": build_typed_stair(folder), "3": build_typed_stair3(folder)}


def typed_pair(stairs, a: str, b: str, strings: bool = True) -> System:
    system = (System("typed").add("a", stairs[a], {"increment": 3, "mode": "down", "negate": True, "label": "A",
                                                   "x_in": 0.5, "period": 0.25})
              .add("b", stairs[b], {"label": "B"})
              .connect("a.counter", "b.n_in").connect("a.e_out", "b.e_in").connect("a.b_out", "b.b_in")
              .connect("a.x_out", "b.x_in"))
    return system.connect("a.s_out", "b.s_in") if strings else system


@pytest.mark.parametrize("versions", ["23", "32", "33"])
def test_every_type_crosses_between_fmi2_and_fmi3_components_unchanged(stairs, versions):
    want = simulate(typed_pair(stairs, "2", "2"), 2.0, 0.125, record=TYPED_RECORD)
    got = simulate(typed_pair(stairs, *versions), 2.0, 0.125, record=TYPED_RECORD)
    assert got["a.b_out"].dtype == np.bool_ and got["a.s_out"].tolist()[-1] == "A:"
    assert np.ptp(want["b.n_out"]) > 0 and want["b.s_out"].tolist()[-1] == "B:A:"
    for name in TYPED_RECORD:
        assert got[name].tolist() == want[name].tolist(), name


@pytest.mark.parametrize("versions", ["23", "32"])
def test_numeric_fmi3_connections_run_in_the_compiled_loop_bit_for_bit(stairs, versions):
    record = [r for r in TYPED_RECORD if "s_out" not in r]
    results = {}
    for native in (True, False):
        with Master(typed_pair(stairs, *versions, strings=False), 0.1, native=native, record=record) as master:
            assert master.loop_kind == ("C" if native else "Python"), master.loop_reason
            results[native] = master.run(2.35)
    assert results[True].tobytes() == results[False].tobytes()
    want = simulate(typed_pair(stairs, "2", "2", strings=False), 2.35, 0.1, record=record)
    for name in record:
        assert results[True][name].tolist() == want[name].tolist(), name


@pytest.mark.parametrize("interface", ["CoSimulation", "ModelExchange"])
@pytest.mark.parametrize("native", [True, False], ids=["C", "Python"])
def test_an_fmi3_fmu_ending_the_simulation_ends_the_run_as_the_fmi2_one_does(stairs, interface, native):
    results = {}
    for version in ("2", "3"):
        system = System().add("s", stairs[version], {"stop_at": 2.3, "period": 0.5, "x_in": -1.5, "increment": 2})
        with Master(system, 0.25, native=native, record=["s.counter", "s.level"],
                    model_exchange=["s"] if interface == "ModelExchange" else None) as master:
            results[version] = master.run(5.0)
            termination = master.termination
        assert termination.component == "s" and termination.time == pytest.approx(2.3, abs=1e-12)
        assert termination.call.startswith(f"fmi{version}")
    assert results["3"]["time"][-1] == pytest.approx(2.3, abs=1e-12)
    for name in ("time", "s.counter", "s.level"):
        np.testing.assert_allclose(results["3"][name], results["2"][name], rtol=0, atol=1e-12, err_msg=name)
