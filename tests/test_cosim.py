"""The master algorithm against other hosts, closed forms and analytic fixed points."""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numpy as np
import pytest
from support.ssp_hosts import run_ecos, run_libcosim
from support.cosim_fmus import build_test_fmu

from shapefmu.cosim import AlgebraicLoopError, CosimError, Master, save_results, simulate
from shapefmu.fmi.ssp import System, read_ssp, write_ssv


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    directory = tmp_path_factory.mktemp("cosim_fmus")
    names = ("CosimRamp", "CosimGain", "CosimIntegrator", "CosimGainNoState", "CosimFailing")
    return {name: build_test_fmu(name, directory) for name in names}


def chain(fmus) -> System:
    """ramp -> (2y + 1) -> gain -> integrator -> negating gain, every parameter off its default."""
    return (System("chain")
            .add("ramp", fmus["CosimRamp"], {"slope": 3.0, "bias": 0.25})
            .add("gain", fmus["CosimGain"], {"k": 2.0, "c": 0.5})
            .add("integrator", fmus["CosimIntegrator"], {"x0": 1.5})
            .add("negate", fmus["CosimGain"], {"k": -1.0})
            .connect("ramp.y", "gain.u", factor=2.0, offset=1.0)
            .connect("gain.y", "integrator.u")
            .connect("integrator.y", "negate.u"))


def test_jacobi_equals_libcosim_and_ecos_on_the_same_ssp(fmus, tmp_path):
    ssp = chain(fmus).write_ssp(tmp_path / "chain.ssp")
    variables = ["ramp.y", "gain.y", "integrator.y", "negate.y"]
    h, n = 1e-3, 40
    ours = simulate(ssp, n * h, h, algorithm="jacobi", record=variables)
    ours = np.column_stack([ours[v] for v in variables])
    libcosim = run_libcosim(ssp, h, n, variables)
    ecos = run_ecos(ssp, h, n, variables)
    np.testing.assert_allclose(ours[1:], libcosim[1:], rtol=0, atol=1e-9)
    # ecos reads a feed-through output (gain.y = k*u computed when read) after setting the new
    # input; outputs computed in the step (ramp, integrator) are the same in all three hosts.
    np.testing.assert_allclose(ours[:, [0, 2]], ecos[:, [0, 2]], rtol=0, atol=1e-9)
    # and the result is the closed form of the Jacobi scheme, not three hosts agreeing on a bug
    t = h * np.arange(n + 1)
    ramp = 3.0 * t + 0.25
    u = 2.0 * ramp + 1.0
    gain_input = np.concatenate([[u[0]], u[:-1]])
    gain_y = 2.0 * gain_input + 0.5
    integrator = 1.5 + h * np.concatenate([[0.0], np.cumsum(gain_y[:-1])])
    np.testing.assert_allclose(ours[:, 0], ramp, atol=1e-12)
    np.testing.assert_allclose(ours[:, 1], gain_y, atol=1e-12)
    np.testing.assert_allclose(ours[:, 2], integrator, atol=1e-12)


def test_single_fmu_equals_fmpy_simulate_fmu(fmus):
    from fmpy import simulate_fmu

    h, stop = 0.01, 0.5
    want = simulate_fmu(str(fmus["CosimIntegrator"]), stop_time=stop, step_size=h, output_interval=h, output=["y"],
                        start_values={"x0": -0.75, "u": 1.25})
    got = simulate(System().add("i", fmus["CosimIntegrator"], {"x0": -0.75, "u": 1.25}), stop, h)
    np.testing.assert_allclose(got["time"], want["time"], atol=1e-12)
    np.testing.assert_allclose(got["i.y"], want["y"], atol=1e-12)
    np.testing.assert_allclose(got["i.y"][-1], -0.75 + 1.25 * stop, atol=1e-12)


def test_parameter_bindings_from_ssv_and_inline_and_linear_transformation_take_effect(fmus, tmp_path):
    ssv = write_ssv(tmp_path / "ramp.ssv", {"slope": -4.0, "bias": 0.5})
    system = (System("bound")
              .add("ramp", fmus["CosimRamp"], ssv=ssv)
              .add("gain", fmus["CosimGain"], {"k": 3.0, "c": -0.25})
              .connect("ramp.y", "gain.u", factor=0.5, offset=2.0))
    for path in (system.write_ssp(tmp_path / "bound.ssp"), system.write_ssd(tmp_path / "bound.ssd")):
        result = simulate(read_ssp(path), 1.0, 0.125)
        t = result["time"]
        ramp = -4.0 * t + 0.5  # defaults would give y = t
        np.testing.assert_allclose(result["ramp.y"], ramp, atol=1e-12)
        # Gauss-Seidel: the gain steps after the ramp and sees its value at the end of the step
        np.testing.assert_allclose(result["gain.y"][1:], 3.0 * (0.5 * ramp[1:] + 2.0) - 0.25, atol=1e-12)


def test_inline_value_overrides_the_ssv_value(fmus, tmp_path):
    ssv = write_ssv(tmp_path / "ramp.ssv", {"slope": -4.0, "bias": 0.5})
    system = System().add("ramp", fmus["CosimRamp"], {"bias": 7.0}, ssv=ssv)
    result = simulate(read_ssp(system.write_ssp(tmp_path / "s.ssp")), 1.0, 0.5)
    np.testing.assert_allclose(result["ramp.y"], -4.0 * result["time"] + 7.0, atol=1e-12)


def test_run_parameters_apply_to_that_run_only(fmus):
    with Master(System().add("ramp", fmus["CosimRamp"], {"slope": 2.0}), 0.1) as master:
        first = master.run(1.0, parameters={"ramp.slope": 5.0})
        second = master.run(1.0)
    np.testing.assert_allclose(first["ramp.y"][-1], 5.0, atol=1e-12)
    np.testing.assert_allclose(second["ramp.y"][-1], 2.0, atol=1e-12)


def test_reset_returns_to_the_initial_state(fmus):
    with Master(chain(fmus), 0.01) as master:
        first = master.run(0.3)
        master.reset()
        again = master.run(0.3)
    for name in first.dtype.names:
        np.testing.assert_array_equal(first[name], again[name])


def test_a_master_left_open_is_released_at_exit_without_an_error(fmus, tmp_path):
    # Not closed, the master is released at interpreter exit: FMUs freed, extracted files removed,
    # nothing printed (a __del__ used to fail there with "sys.meta_path is None").
    ssp = chain(fmus).write_ssp(tmp_path / "chain.ssp")
    extracted = tmp_path / "extracted"
    extracted.mkdir()
    script = "import sys\nfrom shapefmu.cosim import Master\nmaster = Master(sys.argv[1], 0.01)\nmaster.run(0.1)\n"
    result = subprocess.run([sys.executable, "-c", script, str(ssp)], capture_output=True, text=True, timeout=120,
                            env={**os.environ, "TMPDIR": str(extracted)})
    assert result.returncode == 0 and result.stderr == "", result.stderr
    assert list(extracted.iterdir()) == []


def test_stop_time_is_exact_with_a_shortened_last_step(fmus):
    result = simulate(System().add("i", fmus["CosimIntegrator"], {"u": 2.0}), 0.35, 0.1)
    np.testing.assert_allclose(result["time"], [0, 0.1, 0.2, 0.3, 0.35], atol=1e-15)
    assert result["i.y"][-1] == pytest.approx(0.7, abs=1e-12)


def test_output_interval_records_every_nth_step(fmus):
    result = simulate(System().add("r", fmus["CosimRamp"]), 1.0, 0.01, output_interval=0.25)
    np.testing.assert_allclose(result["time"], [0, 0.25, 0.5, 0.75, 1.0], atol=1e-12)
    np.testing.assert_allclose(result["r.y"], result["time"], atol=1e-12)


def test_step_multiple_steps_a_component_less_often(fmus):
    system = (System().add("ramp", fmus["CosimRamp"]).add("i", fmus["CosimIntegrator"])
              .connect("ramp.y", "i.u"))
    h, m = 0.1, 3
    result = simulate(system, 1.2, h, algorithm="jacobi", step_multiples={"i": m})
    # The integrator steps by 3h from t = 0, 0.3, 0.6, 0.9 with the ramp value at those instants,
    # and its output is passed on when its step has ended.
    expected_at = {round(0.3 * j, 9): sum(3 * h * 0.3 * i for i in range(j)) for j in range(5)}
    for t, y in zip(result["time"], result["i.y"]):
        held = max(v for v in expected_at if v <= t + 1e-12)
        assert y == pytest.approx(expected_at[held], abs=1e-12), t


def test_gauss_seidel_steps_the_plant_before_the_controller_in_a_feedback_loop(fmus):
    # integrator (no feed-through) <-> gain (feed-through): not an algebraic loop. x' = -2 x by
    # forward Euler, with the gain reading x at the end of each step: x_{k+1} = x_k (1 - 2h).
    system = (System().add("gain", fmus["CosimGain"], {"k": -2.0}).add("plant", fmus["CosimIntegrator"], {"x0": 1.0})
              .connect("plant.y", "gain.u").connect("gain.y", "plant.u"))
    with Master(system, 0.05) as master:
        assert [s.components for s in master.stages] == [["plant"], ["gain"]]
        result = master.run(1.0)
    k = np.arange(len(result))
    np.testing.assert_allclose(result["plant.y"], (1 - 2 * 0.05) ** k, rtol=1e-12)


def ring(fmus, a, c1, b, c2, gain="CosimGain"):
    return (System("ring").add("g1", fmus[gain], {"k": a, "c": c1}).add("g2", fmus["CosimGain"], {"k": b, "c": c2})
            .connect("g1.y", "g2.u").connect("g2.y", "g1.u"))


@pytest.mark.parametrize("solver, a, b", [("newton", 0.5, -0.8), ("fixed-point", 0.5, -0.8), ("newton", 3.0, 2.0)])
def test_algebraic_loop_converges_to_the_analytic_fixed_point(fmus, solver, a, b):
    # y1 = a*y2 + c1, y2 = b*y1 + c2  =>  y1 = (a*c2 + c1) / (1 - a*b); |ab| > 1 needs Newton.
    c1, c2 = 1.0, 2.0
    with Master(ring(fmus, a, c1, b, c2), 0.1, loop_solver=solver) as master:
        assert master.stages[0].is_loop
        result = master.run(0.5)
    y1 = (a * c2 + c1) / (1 - a * b)
    np.testing.assert_allclose(result["g1.y"], y1, rtol=0, atol=1e-10)
    np.testing.assert_allclose(result["g2.y"], b * y1 + c2, rtol=0, atol=1e-10)


def test_algebraic_loop_without_rollback_names_the_loop(fmus):
    with pytest.raises(AlgebraicLoopError) as error:
        Master(ring(fmus, 0.5, 1.0, -0.8, 2.0, gain="CosimGainNoState"), 0.1)
    message = str(error.value)
    for variable in ("g1.u", "g1.y", "g2.u", "g2.y"):
        assert variable in message
    assert "g1 cannot get/set its FMU state" in message


def test_fmu_error_names_component_call_and_time_and_keeps_partial_results(fmus):
    system = System().add("ramp", fmus["CosimRamp"]).add("failing", fmus["CosimFailing"], {"fail_at": 0.35})
    with pytest.raises(CosimError) as error:
        simulate(system, 1.0, 0.1)
    failure = error.value
    assert (failure.component, failure.call) == ("failing", "fmi2DoStep")
    assert failure.time == pytest.approx(0.3)
    assert "'failing'" in str(failure) and "fmi2DoStep" in str(failure) and "t = 0.3" in str(failure)
    np.testing.assert_allclose(failure.partial["time"], [0, 0.1, 0.2, 0.3], atol=1e-12)
    np.testing.assert_allclose(failure.partial["ramp.y"], failure.partial["time"], atol=1e-12)


def test_results_save_as_csv_and_parquet(fmus, tmp_path):
    result = simulate(chain(fmus), 0.1, 0.01)
    csv = np.genfromtxt(save_results(result, tmp_path / "r.csv"), delimiter=",", names=True)
    for name in result.dtype.names:
        np.testing.assert_array_equal(csv[name.replace(".", "")], result[name])
    import pyarrow.parquet as pq

    table = pq.read_table(save_results(result, tmp_path / "r.parquet"))
    for name in result.dtype.names:
        np.testing.assert_array_equal(table[name].to_numpy(), result[name])


@pytest.mark.parametrize("kwargs, message", [
    ({"step": 0.0}, "step must be a finite number > 0"),
    ({"step": 0.1, "algorithm": "newton"}, "algorithm must be one of"),
    ({"step": 0.1, "output_interval": 0.15}, "output_interval must be a whole multiple"),
    ({"step": 0.1, "step_multiples": {"nope": 2}}, "step_multiples names unknown component 'nope'"),
    ({"step": 0.1, "record": ["ramp.nope"]}, "has no variable 'nope'"),
])
def test_bad_master_arguments_are_refused(fmus, kwargs, message):
    with pytest.raises(ValueError, match=message):
        Master(System().add("ramp", fmus["CosimRamp"]), **kwargs)


def test_a_long_run_keeps_memory_flat_apart_from_the_results(fmus):
    import tracemalloc

    with Master(System().add("ramp", fmus["CosimRamp"]), 1e-3, output_interval=10.0) as master:
        master.run(1.0)  # warm up caches
        tracemalloc.start()
        master.run(10.0)
        _, small = tracemalloc.get_traced_memory()
        tracemalloc.reset_peak()
        master.run(50.0)
        current, large = tracemalloc.get_traced_memory()
        tracemalloc.stop()
    # 5x the steps: the peak may differ by the larger result array (11 rows) and nothing that grows
    assert large - small < 16 * 1024
    assert not math.isnan(current)


def test_cli_simulate_writes_the_master_results(fmus, tmp_path, capsys):
    from shapefmu.cli import main

    ssp = chain(fmus).write_ssp(tmp_path / "chain.ssp")
    out = tmp_path / "r.csv"
    assert main(["simulate", str(ssp), "--stop", "0.2", "--step", "0.01", "--record", "integrator.y",
                 "--set", "gain.k=4", "--out", str(out), "--plot", str(tmp_path / "r.png")]) == 0
    saved = np.genfromtxt(out, delimiter=",", names=True)
    want = simulate(ssp, 0.2, 0.01, record=["integrator.y"], parameters={"gain.k": 4.0})
    np.testing.assert_array_equal(saved["integratory"], want["integrator.y"])
    assert (tmp_path / "r.png").read_bytes()[:4] == b"\x89PNG"
    assert "integrator.y" in capsys.readouterr().out


def test_cli_simulate_refuses_a_bad_step(fmus, tmp_path, capsys):
    from shapefmu.cli import main

    ssp = chain(fmus).write_ssp(tmp_path / "chain.ssp")
    with pytest.raises(SystemExit) as exit_:
        main(["simulate", str(ssp), "--stop", "0.2", "--step", "-1"])
    assert exit_.value.code == 2
    assert "step must be a finite number > 0 s, got -1.0" in capsys.readouterr().err


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
@pytest.mark.parametrize("options", [{}, {"step_multiples": {"integrator": 3}, "output_interval": 0.04}],
                         ids=["every-step", "multirate"])
def test_compiled_loop_equals_the_python_loop_bit_for_bit(fmus, algorithm, options):
    # Feed-through gains (read before their step in Gauss-Seidel), a linear transformation, a
    # multirate component and a shortened last step: everything the generated step does.
    results = {}
    for native in (True, False):
        with Master(chain(fmus), 0.01, algorithm=algorithm, native=native, **options) as master:
            assert master.loop_kind == ("C" if native else "Python")
            results[native] = master.run(0.537)
    assert results[True].tobytes() == results[False].tobytes()


def test_an_fmu_error_inside_the_compiled_loop_names_component_call_and_time(fmus):
    system = System().add("ramp", fmus["CosimRamp"]).add("failing", fmus["CosimFailing"], {"fail_at": 0.35})
    with Master(system, 0.1) as master:
        assert master.loop_kind == "C"
        with pytest.raises(CosimError) as error:
            master.run(1.0)
    assert (error.value.component, error.value.call) == ("failing", "fmi2DoStep")
    assert error.value.time == pytest.approx(0.3)
    np.testing.assert_allclose(error.value.partial["time"], [0, 0.1, 0.2, 0.3], atol=1e-12)
