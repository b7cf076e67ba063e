"""Sampled FMUs take the same samples at any start time (issue 34, item 1).

A host that starts at t0 = 1e6 or at a Unix-epoch 1.7e9 and keeps time as ``t += h`` gave other
outputs than one starting at 0: the FMUs compared its drifting time with t0 + k Ts to 1e-6 Ts, below
the spacing of doubles there (the native Shaper differed by 0.75 from step 70, the FMI 3.0 --clock
twins refused the tick "not at t = 1000000.021000001"). The rule now (runtime/sample_clock.py,
c/sample_clock.c): samples are counted from the steps.

Every sampled kind (Shaper of a closed-form and of a build-time-only kind, ShapeFilter, EKFTuner,
STOSController, ProfileGenerator), as a pythonfmu FMU and as its native twin in FMI 2.0, FMI 3.0
and FMI 3.0 with --clock, is run by a host written here (fmpy's bindings, time kept as ``t += h``,
inputs a function of the step's index) at t0 = 0, 1e3, 1e6 and 1.7e9, with steps of Ts, of 0.7 Ts
and of random sizes; a clocked host ends its steps at the ticks, which it counts down itself. Every
output at every communication point equals the t0 = 0 run's, bit for bit. The t0 = 0 run of the
Shaper equals the design's taps over the samples the spec takes (sampled_reference.py, numpy's
search on the grid of the steps' exact sums), so the runs compared are right, not only alike.

A host that aims its steps at absolute instants (h = t0 + m Ts - t, as fmi2_host's --random GRID
and a tick-aiming FMI 3.0 host do) has steps that differ from t0 to t0 by ulps of t0; its sampled
FMUs still take the same samples (its ticks are accepted), bit for bit.
"""

from __future__ import annotations

import math
import random
from concurrent.futures import ThreadPoolExecutor
from fractions import Fraction

import numpy as np
import pytest
from support.sampled_reference import SampledRun

from shapefmu.runtime import shaper_designs
from shapefmu.runtime.shaper_filter import grid_impulses

START_TIMES = (1e3, 1e6, 1.7e9)
STEPS = 300
SHAPER = {"n_modes": 1, "f[1]": 13.0, "zeta[1]": 0.05, "Ts": 1e-3}
# name -> (model name, start values, outputs compared)
KINDS = {
    "Shaper zvd": ("Shaper", {"kind": "zvd", **SHAPER}, ("y",)),
    "Shaper ei": ("Shaper", {"kind": "ei", "vtol": 0.05, **SHAPER}, ("y",)),
    # f_d = 10 Hz: the window is a whole 200 samples of Ts
    "ShapeFilter": ("ShapeFilter", {"kind": "hanning", "f": 10.0 / math.sqrt(1.0 - 0.05**2), "zeta": 0.05, "order": 2,
                                    "Ts": 1e-3}, ("y",)),
    "EKFTuner": ("EKFTuner", {"Ts": 1e-3}, ("y", "omega_est", "zeta_est")),
    "STOSController": ("STOSController", {}, ("u",)),  # its Ts = 10 us: 24 ulps of 1.7e9
    "ProfileGenerator": ("ProfileGenerator", {"t_start": -1.0, "Ts": 1e-3}, ("position", "velocity", "acceleration")),
}
BUILDS = ("pythonfmu", "native 2.0", "native 3.0", "native 3.0 clock")


def _inputs(model, n):
    """The inputs at the n-th communication point (the same whatever t0)."""
    wave = (1.0 if (n // 37) % 2 == 0 else -0.5) + 0.3 * math.sin(0.37 * n)
    if model == "EKFTuner":
        return {"u": wave, "vibration": math.exp(-0.004 * n) * math.sin(0.08 * n)}
    if model == "STOSController":
        return {"target": 1e-3, "x_r": 1e-3 * (1.0 - math.exp(-0.02 * n)), "x_r_dot": 2e-5 * math.exp(-0.02 * n)}
    if model == "ProfileGenerator":
        return {"start": 1.0 if n >= 5 else 0.0}
    return {"u": wave}


def _steps(pattern, ts):
    """The host's step sizes: Ts, 0.7 Ts, or random (log-uniform over 1e-3..3 Ts, or 1..3 whole Ts)."""
    if pattern == "Ts":
        return [ts] * STEPS
    if pattern == "0.7 Ts":
        return [0.7 * ts] * STEPS
    rng = random.Random(34)
    return [ts * (rng.randint(1, 3) if rng.random() < 0.3 else 10.0 ** rng.uniform(-3.0, math.log10(3.0)))
            for _ in range(STEPS)]


def _period(model, values):
    return values.get("Ts", 1e-5 if model == "STOSController" else 1e-3)


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    """{(kind, build): FMU path} for every kind and build."""
    from shapefmu.fmi.native.twins import build_native
    from shapefmu.fmi.python.builder import build_fmu

    folder = tmp_path_factory.mktemp("start_times")

    def build(kind, variant):
        model, values, _ = KINDS[kind]
        path = folder / f"{kind.replace(' ', '_')}_{variant.replace(' ', '_')}.fmu"
        if variant == "pythonfmu":
            return build_fmu(model, path, **values)
        return build_native(model, path, fmi_version="2.0" if "2.0" in variant else "3.0", clock="clock" in variant,
                            **values)

    with ThreadPoolExecutor(2) as pool:
        jobs = {(kind, variant): pool.submit(build, kind, variant) for kind in KINDS for variant in BUILDS}
        return {key: job.result() for key, job in jobs.items()}


class _Host:
    """One instance of an FMU at start time t0, stepped by a host that keeps its time as t += h."""

    def __init__(self, path, t0, clocked):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave
        from fmpy.fmi3 import FMU3Slave

        md = read_model_description(str(path))
        self.fmi3 = md.fmiVersion.startswith("3")
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.clock_vr = [v.valueReference for v in md.modelVariables if v.type == "Clock"]
        self.slave = (FMU3Slave if self.fmi3 else FMU2Slave)(
            guid=md.guid, unzipDirectory=extract(str(path)), modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName="host")
        if self.fmi3:
            self.slave.instantiate(eventModeUsed=clocked)
            self.slave.enterInitializationMode(startTime=t0)
        else:
            self.slave.instantiate()
            self.slave.setupExperiment(startTime=t0)
            self.slave.enterInitializationMode()
        self.slave.exitInitializationMode()  # a clocked FMU is now in Event Mode, at its first tick
        self.clocked = clocked

    def set(self, values):
        vrs, numbers = [self.vr[name] for name in values], list(values.values())
        (self.slave.setFloat64 if self.fmi3 else self.slave.setReal)(vrs, numbers)

    def get(self, names):
        return (self.slave.getFloat64 if self.fmi3 else self.slave.getReal)([self.vr[name] for name in names])

    def tick(self, values):
        """In Event Mode at a tick: the inputs, the clock, back to Step Mode."""
        self.set(values)
        self.slave.setClock(self.clock_vr, [True])
        self.slave.updateDiscreteStates()
        self.slave.enterStepMode()

    def free(self):
        self.slave.terminate()
        self.slave.freeInstance()


def _run(path, model, outputs, t0, steps, ts, clocked=False, aimed=False):
    """Outputs at every communication point (after its inputs are set), for the steps ``steps`` from t0.

    A clocked host ends a step at the next tick, counting down the time to it from its own steps
    (``aimed``: at t0 + m Ts, computed from its absolute time as a tick-aiming host does). An unclocked
    ``aimed`` host makes every third step end at the grid point t0 + m Ts 1 or 2 Ts after the nearest one."""
    host = _Host(path, t0, clocked)
    rows, t, to_tick, tick = [], t0, ts, 1
    n, at_tick, drift = 0, clocked, 0.0
    for h in steps:
        values = _inputs(model, n)
        if at_tick:
            host.tick(values)
        elif not clocked:
            host.set(values)
        rows.append(host.get(outputs))
        if clocked:
            target = t0 + tick * ts
            # As fmi3_host.c, a step that would end within 1e-6 Ts of the tick is one to it; a host
            # aiming from its absolute time adds what it cannot resolve: an ulp of t, and the rounding
            # its t += h has had since its last tick.
            slack = 1e-6 * ts + (math.ulp(t) + drift if aimed else 0.0)
            at_tick = (target - t <= h + slack) if aimed else (to_tick <= h + slack)
            h = (target - t) if aimed and at_tick else to_tick if at_tick else h
            to_tick = ts if at_tick else to_tick - h
            drift = 0.0 if at_tick else drift + math.ulp(t + h)
            tick += at_tick
        elif aimed and n % 3 == 2:
            h = t0 + (round((t - t0) / ts) + 1 + n % 2) * ts - t
        host.slave.doStep(t, h)
        t += h
        n += 1
        if at_tick:
            host.slave.enterEventMode()
    host.free()
    return np.array(rows)


def _kind_runs(fmus, kind, build, pattern, aimed=False):
    model, values, outputs = KINDS[kind]
    ts = _period(model, values)
    steps = _steps(pattern, ts)
    clocked = "clock" in build
    return {t0: _run(fmus[kind, build], model, outputs, t0, steps, ts, clocked, aimed) for t0 in (0.0, *START_TIMES)}


@pytest.mark.parametrize("pattern", ["Ts", "0.7 Ts", "random"])
@pytest.mark.parametrize("build", BUILDS)
@pytest.mark.parametrize("kind", KINDS)
def test_every_start_time_takes_the_samples_of_t0_0_bit_for_bit(fmus, kind, build, pattern):
    runs = _kind_runs(fmus, kind, build, pattern)
    for t0 in START_TIMES:
        differ = np.nonzero(np.any(runs[t0] != runs[0.0], axis=1))[0]
        assert differ.size == 0, (f"t0 = {t0}: first differs at step {differ[0]}: {runs[t0][differ[0]]} "
                                  f"instead of {runs[0.0][differ[0]]}")


@pytest.mark.parametrize("build", BUILDS)
@pytest.mark.parametrize("kind", [k for k in KINDS if k != "ProfileGenerator"])
def test_a_host_aiming_at_absolute_instants_takes_the_same_samples_at_every_start_time(fmus, kind, build):
    # The profile generator plays a function of the time, which such a host's steps change by ulps of t0.
    runs = _kind_runs(fmus, kind, build, "random", aimed=True)
    for t0 in START_TIMES:
        differ = np.nonzero(np.any(runs[t0] != runs[0.0], axis=1))[0]
        assert differ.size == 0, f"t0 = {t0}: first differs at step {differ[0]}"


@pytest.mark.parametrize("pattern", ["Ts", "0.7 Ts", "random"])
@pytest.mark.parametrize("build", ["pythonfmu", "native 2.0", "native 3.0"])
def test_the_shaper_run_from_t0_0_is_the_designs_taps_over_the_specs_samples(fmus, build, pattern):
    model, values, outputs = KINDS["Shaper zvd"]
    ts = values["Ts"]
    steps = _steps(pattern, ts)
    y = _run(fmus["Shaper zvd", build], model, outputs, 0.0, steps, ts)[:, 0]
    times, inputs = [0.0], []
    exact = Fraction(0)
    for n, h in enumerate(steps):
        inputs.append(_inputs(model, n)["u"])
        exact += Fraction(h)
        times.append(float(exact))
    modes = shaper_designs.parameter_modes(values, 4)
    delays, weights = grid_impulses(*shaper_designs.design_impulses("zvd", modes, 1, 0.05), ts)
    taps = np.zeros(max(delays) + 1)
    np.add.at(taps, delays, weights)
    reference = SampledRun(times[:-1], inputs, ts).fir(taps)
    np.testing.assert_allclose(y, reference, rtol=0, atol=1e-12)


@pytest.mark.parametrize("kind", ["Shaper zvd", "EKFTuner"])
def test_the_master_ticks_a_clocked_fmu_at_any_start_time_as_at_0(fmus, kind):
    """shapefmu's own master is such a host: its ticks are counted by its steps, not by t - t0 (off by
    ulps of t0 at 1.7e9, it found no tick to set and the FMU refused the step)."""
    from shapefmu.cosim import Master
    from shapefmu.fmi.ssp import System

    model, values, outputs = KINDS[kind]
    ts = _period(model, values)
    rows = {}
    for t0 in (0.0, *START_TIMES):
        system = System("s").add("fmu", fmus[kind, "native 3.0 clock"])
        system.start_time = t0
        inputs = {f"fmu.{name}": value for name, value in _inputs(model, 3).items()}
        with Master(system, ts, record=[f"fmu.{name}" for name in outputs]) as master:
            result = master.run(t0 + STEPS * ts, parameters=inputs)
        # at 1.7e9 the stop time t0 + 0.3 s is itself rounded: compare the first STEPS + 1 rows
        rows[t0] = np.column_stack([result[f"fmu.{name}"] for name in outputs])[: STEPS + 1]
    for t0 in START_TIMES:
        assert np.array_equal(rows[t0], rows[0.0]), t0
