"""Every FMU answers any step a host chooses: sampled FMUs take their samples on t0 + k Ts.

Driven by our C host (hosts_c/fmi2_host.c, run by tests/support/c_hosts.py) the way the FMU compliance checker
(fmuCheck) and OMSimulator drive an FMU: time kept as ``t += h`` with the last step trimmed onto the
stop time (after 2000 steps of 1 ms towards 2 s the last step is 1.1e-13 s), steps of stop/500
(fmuCheck's default), random steps from 1e-9 Ts to 7.3 Ts. Every FMU that ``shapefmu build``
writes answers fmi2OK to every call and the process exits 0, whether the host terminates and frees
its instances from an exit handler registered before it loaded the FMU (as OMSimulator does) or
never. The outputs of the sampled FMUs equal, at every communication point, the design layer's
sampled response held between samples (sampled_reference.py), to 1e-12.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from support.c_hosts import fmu_arguments, host_rows, run_host
from support.sampled_reference import SampledRun

from shapefmu.fmi.kinds import KINDS as SLAVES
from shapefmu.runtime import shaper_designs
from shapefmu.runtime.ekf_tuner import EKFTunedShaperKernel
from shapefmu.runtime.stos import STOSKernel, stos_curves
from shapefmu.shapers import WINDOW_FILTERS, design

MODELS = Path(__file__).resolve().parent.parent / "models"
PLANTS = sorted(p.stem for p in [*MODELS.glob("*.toml"), *MODELS.glob("*.py")])
SAMPLED = ("Shaper", "ShapeFilter", "EKFTuner", "STOSController")
# Plants have no DefaultExperiment: OMSimulator's run of the issue, 2 s in steps of 1 ms.
PLANT_EXPERIMENT = (0.0, 2.0, 1e-3)


@pytest.fixture(scope="module")
def built(all_fmus, plant_fmus) -> dict:
    """{name: FMU path} of everything ``shapefmu build`` writes: the pythonfmu FMUs and the plants."""
    return {**{path.stem: path for path in all_fmus}, **plant_fmus}


def _experiment(fmu):
    from fmpy import read_model_description

    experiment = read_model_description(str(fmu)).defaultExperiment
    if experiment is None:
        return PLANT_EXPERIMENT
    return float(experiment.startTime), float(experiment.stopTime), float(experiment.stepSize)


def _host_times(start, stop, step):
    """The communication points of a host that keeps time as t += h and trims the last step."""
    times, t = [start], start
    while t < stop:
        h = stop - t if t + step > stop else step
        t += h
        times.append(t)
    return np.array(times)


def _signal(name, step):
    """Input amplitude and period: positions of millimetres for the STOS loop, a period of 50 steps."""
    return ["--amplitude", 1e-3 if name == "STOSController" else 1.0, "--period", 50 * step]


def test_the_runs_below_cover_every_fmu_shapefmu_build_writes(built):
    assert set(built) == set(SLAVES) | set(PLANTS)


@pytest.mark.parametrize("teardown", ["atexit", "never"])
@pytest.mark.parametrize("steps", ["2000 steps", "stop/500"])
@pytest.mark.parametrize("name", [*sorted(SLAVES), *PLANTS])
def test_every_call_is_ok_and_the_host_exits_0_with_drifting_time_and_a_trimmed_last_step(
    built, c_host, tmp_path, name, steps, teardown
):
    start, stop, step = _experiment(built[name])
    if steps == "2000 steps":
        stop = start + 2000 * step  # 2000 samples of a sampled FMU: its step is its Ts
        options = ["--stop", stop, "--step", step]
        times = _host_times(start, stop, step)
    else:
        options = ["--stop", stop, "--steps", 500]
        times = _host_times(start, stop, (stop - start) / 500)
    csv = tmp_path / "run.csv"
    result = run_host(c_host, [fmu_arguments(built[name], tmp_path / "fmu")], *options, "--teardown", teardown,
                      "--start", start, "--csv", csv, *_signal(name, step))
    assert result.returncode == 0, result.stderr[-3000:]
    assert result.stdout.splitlines()[-1] == "done"
    if teardown == "atexit":
        assert "exit handler: atexit done" in result.stderr  # it ran, and every fmi2Terminate was fmi2OK
    rows = host_rows(csv)[(0, 0, 0)]
    np.testing.assert_array_equal(rows[:, 0], times)  # every communication point, the trimmed last one too
    assert np.all(np.isfinite(rows))


def test_the_last_step_of_omsimulators_run_is_a_sample_reached_not_skipped(built, c_host, tmp_path):
    # 2000 steps of 1 ms towards 2 s leave t = 2 - 1.1e-13 s: that point counts as sample 2000,
    # and the trimmed step of 1.1e-13 s onto 2 s takes no sample of its own.
    times = _host_times(0.0, 2.0, 1e-3)
    assert 1e-13 < times[-1] - times[-2] < 1.2e-13
    csv = tmp_path / "run.csv"
    result = run_host(c_host, [fmu_arguments(built["Shaper"], tmp_path / "fmu")], "--stop", 2.0, "--step", 1e-3,
                      "--csv", csv, *_signal("Shaper", 1e-3))
    assert result.returncode == 0, result.stderr[-3000:]
    rows = host_rows(csv)[(0, 0, 0)]
    run = SampledRun(rows[:, 0], rows[:, 1], 1e-3)
    assert run.index[-3:].tolist() == [1999, 2000, 2000] and run.on_grid.all()
    np.testing.assert_allclose(rows[:, 2], run.fir(_shaper_taps()), rtol=0, atol=1e-12)


# --- random steps against the design layer ----------------------------------------------------------------

RANDOM_STEPS = 100_000


def _random_run(c_host, tmp_path, fmu, ts, steps, seed, *options):
    """``steps`` random steps in [1e-9 Ts, 7.3 Ts] (a third of them onto the grid): rows of the CSV."""
    csv = tmp_path / "random.csv"
    result = run_host(c_host, [fmu_arguments(fmu, tmp_path / "fmu")], "--random", seed, 1e-9 * ts, 7.3 * ts, steps, ts,
                      "--period", 50 * ts, *options, "--csv", csv)
    assert result.returncode == 0, result.stderr[-3000:]
    rows = host_rows(csv)[(0, 0, 0)]
    steps_taken = np.diff(rows[:, 0])
    assert steps_taken.min() < 1e-8 * ts and steps_taken.max() > 7 * ts  # the whole range was stepped
    return rows


def _shaper_taps():
    """The design layer's ZVD for 10 Hz on the 1 ms grid: the Shaper FMU's default parameters."""
    return design("zvd", [(2 * math.pi * 10.0, 0.0)]).on_grid(1e-3).taps


def _assert_fir_matches(rows, ts, taps, t0=0.0):
    run = SampledRun(rows[:, 0], rows[:, 1], ts, t0)
    assert 0.2 < run.on_grid.mean() < 0.8  # the run stood both on the grid and between samples
    np.testing.assert_allclose(rows[:, 2], run.fir(taps), rtol=0, atol=1e-12)


def test_shaper_output_at_random_steps_is_the_sampled_design_held_between_samples(built, c_host, tmp_path):
    rows = _random_run(c_host, tmp_path, built["Shaper"], 1e-3, RANDOM_STEPS, 1)
    _assert_fir_matches(rows, 1e-3, _shaper_taps())


def test_samples_are_counted_from_the_start_time_of_the_experiment(built, c_host, tmp_path):
    start = 0.3705  # not on the grid k Ts from 0: the grid is start + k Ts
    rows = _random_run(c_host, tmp_path, built["Shaper"], 1e-3, 5000, 5, "--start", start)
    assert rows[0, 0] == start
    _assert_fir_matches(rows, 1e-3, _shaper_taps(), t0=start)


def test_feed_through_shape_filter_at_random_steps_is_the_sampled_design_held(feedthrough_filter_fmu, c_host, tmp_path):
    from support.fixtures_fmi import FEEDTHROUGH_FILTER_STARTS as starts

    taps = WINDOW_FILTERS["rectangle"](2 * math.pi * starts["f"], starts["zeta"], starts["Ts"]).taps
    assert taps[0] != 0.0  # y feeds through: the latch between samples shows
    rows = _random_run(c_host, tmp_path, feedthrough_filter_fmu, starts["Ts"], RANDOM_STEPS, 2)
    _assert_fir_matches(rows, starts["Ts"], taps)


def test_ekf_tuner_at_random_steps_equals_the_kernel_run_once_per_sample(built, c_host, tmp_path):
    ts = 1e-3  # the EKFTuner's defaults: ZVD, 10 Hz guess, n = 1, retune 5 %, amplitude 1
    # Sines of 50 samples (20 Hz) without the square wave: a vibration the EKF locks on to.
    rows = _random_run(c_host, tmp_path, built["EKFTuner"], ts, 10_000, 3, "--square", 0.0)
    run = SampledRun(rows[:, 0], rows[:, 1:3], ts)
    kernel = EKFTunedShaperKernel(1.0 / ts, 2 * math.pi * 10.0, "zvd", 1, 0.05, amplitude=1.0)
    after = [[0.0, kernel.ekf.omega_n, kernel.ekf.zeta, 0.0]]  # outputs after samples 0..k-1
    for u, vibration in run.samples[:-1]:
        y = kernel.step(u, vibration)
        after.append([y, kernel.ekf.omega_n, kernel.ekf.zeta, 1.0 if kernel.ekf.converged else 0.0])
    assert kernel.designs >= 1 and kernel.ekf.omega_n == pytest.approx(2 * math.pi * 20.0, rel=1e-3)  # it tuned
    np.testing.assert_allclose(rows[:, 3:], np.array(after)[run.index], rtol=0, atol=1e-12)


def test_stos_controller_at_random_steps_equals_the_law_sampled_and_held(built, c_host, tmp_path):
    ts = 1e-5  # the STOSController's defaults: paper 002's disk drive, modes at 2 and 3 kHz
    rows = _random_run(c_host, tmp_path, built["STOSController"], ts, 20_000, 4, "--amplitude", 1e-3)
    run = SampledRun(rows[:, 0], rows[:, 1:4], ts)
    times, amplitudes = shaper_designs.design_impulses(
        "simultaneous", [(2 * math.pi * 2000.0, 0.01), (2 * math.pi * 3000.0, 0.01)], 1)
    kernel = STOSKernel(stos_curves(2.7e3, 11.0, times, amplitudes, 0.0))
    expected, point = np.empty(len(rows)), 0
    for k, sample in enumerate(run.samples):
        while point < len(rows) and run.index[point] == k:  # the law at the current inputs, committed state kept
            saved = kernel.get_state()
            expected[point] = kernel.control(*run.current[point])
            kernel.set_state(saved)
            point += 1
        kernel.control(*sample)
    assert expected.min() == -11.0 and expected.max() == 11.0 and np.any(np.abs(expected) < 11.0)  # bangs and between
    np.testing.assert_allclose(rows[:, 4], expected, rtol=0, atol=1e-12)


# --- steps of extreme sizes ---------------------------------------------------------------------------------


def test_a_step_spanning_more_than_the_bound_is_refused_at_once_naming_it_and_changes_nothing(built, c_host, tmp_path):
    fmus = [fmu_arguments(built[name], tmp_path / name) for name in SAMPLED]
    results, rows = {}, {}
    for probe in (None, 1e300):
        csv = tmp_path / f"{probe}.csv"
        options = ["--probe", probe] if probe else []
        results[probe] = run_host(c_host, fmus, "--stop", 0.02, "--step", 1e-3, "--csv", csv, *options)
        assert results[probe].returncode == 0, results[probe].stderr[-3000:]
        rows[probe] = host_rows(csv)
    probes = [line.split() for line in results[1e300].stdout.splitlines() if line.startswith("probe")]
    assert [int(status) for _, status, _ in probes] == [3] * len(SAMPLED)  # fmi2Error
    assert max(float(seconds) for _, _, seconds in probes) < 0.5  # at once, not after 1e303 samples
    # each at its own bound: the samples its Python kernel takes in about a second (limits.PYTHON_STEP_SECONDS)
    assert results[1e300].stderr.count("per step (about a second of this FMU's work") == len(SAMPLED)
    assert "h = 1e+300 s spans 1e+303 samples of Ts = 0.001 s" in results[1e300].stderr  # the Shaper's
    for key, unprobed in rows[None].items():
        np.testing.assert_array_equal(rows[1e300][key], unprobed)  # the refused step changed nothing


def test_a_step_of_1e_16_s_is_ok_for_every_fmu(built, c_host, tmp_path):
    names = [*sorted(SLAVES), *PLANTS]
    fmus = [fmu_arguments(built[name], tmp_path / name) for name in names]
    result = run_host(c_host, fmus, "--probe", 1e-16, "--stop", 0.01, "--step", 1e-3)
    assert result.returncode == 0, result.stderr[-3000:]
    statuses = [int(line.split()[1]) for line in result.stdout.splitlines() if line.startswith("probe")]
    assert statuses == [0] * len(names)
