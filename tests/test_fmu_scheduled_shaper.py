"""The ScheduledShaper FMU (fmi/kinds/scheduled_shaper.py, issue 37): at every sample its output equals
the change-by-change sum of the closed-form shapers designed for the scheduling value in force when
each change was commanded (tests/test_scheduled_shaper.py's reference: Singer & Seering's ZV and ZVD,
split onto the grid by hand), in fmpy and in our master; no jump when the design changes. The tests
run in fmpy take the pythonfmu FMU and its native C twin (fmi/native/scheduled_shaper.py) alike.
"""

import json

import numpy as np
import pytest
from support.fixtures_fmi import SCHEDULED_STARTS
from support.fmpy_slaves import initialised, refused_start_values
from test_scheduled_shaper import BED, FS, change_by_change, closed_form_taps, schedule_mode

from shapefmu.fmi.kinds.scheduled_shaper import schedule_start_values

TS = 1.0 / FS


def test_the_fixtures_schedule_is_the_reference_bed():
    """SCHEDULED_STARTS (support/fixtures_fmi.py), the FMUs of bed() and scheduled_zv_fmu, holds BED's rows at FS."""
    assert SCHEDULED_STARTS["Ts"] == TS
    assert schedule_start_values(*BED).items() - {"extrapolate": False}.items() <= SCHEDULED_STARTS.items()


@pytest.fixture(params=["pythonfmu", "native"])
def bed(request, builds):
    """bed(kind, **changed): the ScheduledShaper of SCHEDULED_STARTS (the bed) for ``kind``, as the pythonfmu
    FMU or as its native C twin."""
    return lambda kind, **changed: getattr(builds, request.param)("ScheduledShaper",
                                                                  **{**SCHEDULED_STARTS, "kind": kind, **changed})


def moves_through_a_drift(n=600, seed=11):
    """Moves, holds and jumps of the command while the bed gains mass sample by sample, holds it, and
    loses some in one step: every kind of change of both inputs."""
    rng = np.random.default_rng(seed)
    u = np.cumsum(rng.normal(size=n)) * (rng.random(n) < 0.7)
    values = np.clip(np.linspace(0.0, 300.0, n) + rng.normal(0.0, 5.0, n), 0.0, 300.0)
    values[250:350] = 180.0
    values[350:] -= 60.0
    return u, np.clip(values, 0.0, 300.0)


def run_fmpy(fmu, u, values):
    """y at each sample instant k Ts: both inputs set there, y read (feed-through), then the step."""
    slave, vr = initialised(fmu, {"scheduling": float(values[0])})
    y = []
    for k, (a, s) in enumerate(zip(u, values)):
        slave.setReal([vr["u"], vr["scheduling"]], [float(a), float(s)])
        y.append(slave.getReal([vr["y"]])[0])
        slave.doStep(k * TS, TS)
    slave.terminate()
    slave.freeInstance()
    return np.array(y)


@pytest.mark.parametrize("kind", ["zv", "zvd"])
def test_output_is_at_every_sample_the_shaper_designed_for_the_value_in_force(bed, kind):
    u, values = moves_through_a_drift()
    y = run_fmpy(bed(kind), u, values)
    np.testing.assert_allclose(y, change_by_change(u, 0.0, values, kind), rtol=0, atol=1e-12)


def test_a_command_at_rest_does_not_move_when_the_design_changes(bed):
    values = np.tile([0.0, 300.0, 40.0, 220.0], 50)
    y = run_fmpy(bed("zv"), np.full(values.size, 0.0), values)
    assert np.all(y == 0.0)
    u = np.concatenate([np.linspace(0.0, 1.0, 40), np.ones(160)])  # a move, then rest through the changes
    y = run_fmpy(bed("zv"), u, values)
    assert np.all(y[120:] == y[-1]) and y[-1] == pytest.approx(1.0, abs=1e-15)


def player(tmp_path, name, samples, ts=TS):
    """A ReferencePlayer FMU holding samples[k] around k ts (each switch half a sample before)."""
    from shapefmu.fmi import build_fmu

    changes = np.flatnonzero(np.diff(samples)) + 1
    table = {"kind": "signal_table", "interpolation": "hold", "before": float(samples[0]),
             "time": [(k - 0.5) * ts for k in changes], "value": [float(samples[k]) for k in changes]}
    return build_fmu("ReferencePlayer", tmp_path / f"{name}.fmu", table=json.dumps(table))


def test_in_our_master_fed_by_two_players_the_output_is_the_same_sum(scheduled_zv_fmu, tmp_path):
    """Jacobi steps: the shaper takes the players' values at t_k for its sample k, and the master
    records its output after the step, before the values of t_(k+1) are set: sample k+1's output
    with the command held, the change-by-change sum less the first impulse of the change at k+1."""
    from shapefmu.cosim.master import simulate
    from shapefmu.fmi.ssp import System

    u, values = moves_through_a_drift(n=300, seed=5)
    # Both inputs start where the FMU starts: the master passes the players' outputs on from the first
    # step, and until then the shaper holds its start values (a pythonfmu output is computed at the
    # exit of initialisation, after the master has read it).
    u[0] = values[0] = 0.0
    system = (System("scheduled")
              .add("command", player(tmp_path, "command", u))
              .add("load", player(tmp_path, "load", values))
              .add("shaper", scheduled_zv_fmu)
              .connect("command.y", "shaper.u")
              .connect("load.y", "shaper.scheduling"))
    result = simulate(system, (u.size - 1) * TS, TS, record=["shaper.y"], algorithm="jacobi")
    y = np.asarray(result["shaper.y"], dtype=float)
    first = np.array([closed_form_taps("zv", *schedule_mode(value))[0] for value in values])
    held = change_by_change(u, 0.0, values, "zv") - first * np.diff(u, prepend=0.0)
    assert y.size == u.size
    np.testing.assert_allclose(y, held, rtol=0, atol=1e-12)


def test_a_scheduling_value_where_the_law_fails_is_an_error_naming_it(bed, capfd):
    from fmpy.fmi1 import FMICallException

    law = schedule_start_values([0.0, 1.0], [30.0, 20.0], [0.05, 0.05], extrapolate=True)  # 0 Hz at value 3
    slave, vr = initialised(bed("zv", **law))
    with pytest.raises(FMICallException):
        slave.setReal([vr["scheduling"]], [3.5])
    slave.freeInstance()
    assert "scheduling value 3.5 lies where the schedule gives f = -5 Hz" in capfd.readouterr().out


def test_a_bad_table_fails_the_build_naming_the_row(tmp_path):
    from shapefmu.fmi import build_fmu

    with pytest.raises(ValueError, match=r"values must be strictly increasing"):
        build_fmu("ScheduledShaper", tmp_path / "bad.fmu", **schedule_start_values([0.0, 0.0], [30.0, 26.0],
                                                                                   [0.05, 0.05]))
    with pytest.raises(ValueError, match=r"zetas\[1\]"):
        build_fmu("ScheduledShaper", tmp_path / "bad.fmu", **schedule_start_values([0.0, 1.0], [30.0, 26.0],
                                                                                   [0.05, 1.2]))


@pytest.mark.parametrize(("parameters", "named"), [
    ({"values[2]": -1.0}, "values"),  # the rows' values not increasing: at the exit of initialisation
    ({"zeta[1]": 1.0}, "zeta"),
    ({"Ts": 0.0}, "Ts"),
    ({"resolution": -1e-3}, "resolution"),
    ({"n_rows": 9}, "n_rows must be in [1, 8]"),
    ({"extrapolate": True, "scheduling": 1e6}, "scheduling value"),  # the law continued to f < 0
])
def test_a_bad_parameter_is_refused_with_a_message_naming_it(bed, capfd, parameters, named):
    refused_start_values(bed("zv"), parameters)
    assert named in capfd.readouterr().out


def test_the_native_twin_refuses_what_it_cannot_design_in_c(builds, tmp_path, capfd):
    """The closed-form kinds only (the C re-designs them at every sample where the mode moved), zv_dn up to
    n = 62: refused by the builder (and ``shapefmu build scheduled-shaper --native``) and when set."""
    from shapefmu.fmi.native.twins import build_native

    from shapefmu.cli import main

    with pytest.raises(ValueError, match=r"kind must be one of zv, zvd, zvdd, zv_dn, mzv for the native ScheduledShaper"):
        build_native("ScheduledShaper", tmp_path / "ei.fmu", kind="ei")
    with pytest.raises(SystemExit) as refused:
        main(["build", "scheduled-shaper", "--native", "--param", "kind=ei3", "-o", str(tmp_path / "ei3.fmu")])
    assert refused.value.code == 2
    assert "for the native ScheduledShaper" in capfd.readouterr().err and not (tmp_path / "ei3.fmu").exists()
    native = builds.native("ScheduledShaper", **SCHEDULED_STARTS, kind="zv")
    refused_start_values(native, {"kind": "ei2"}, when_set=True)
    refused_start_values(native, {"n": 63}, when_set=True)
    printed = capfd.readouterr().out
    assert "kind must be one of zv, zvd, zvdd, zv_dn, mzv" in printed and "n must be an integer in [0, 62]" in printed


def test_the_native_twin_keeps_thousands_of_designs_in_flight(builds):
    """A slow mode (ZV at 0.2 to 0.25 Hz: 5000 samples long at 2 kHz) re-designed at every sample of a
    ramp keeps a design per sample in flight: 5000 at the end, past the 4096 a fixed-size C store once
    held; still the change-by-change sum (only the native twin: the pythonfmu FMU's sum is Python)."""
    law = schedule_start_values([0.0, 1.0], [0.2, 0.25], [0.0, 0.0])
    fmu = builds.native("ScheduledShaper", **{**SCHEDULED_STARTS, **law, "kind": "zv", "resolution": 0.0})
    n = 6000
    u, values = np.arange(n) * 1e-3, np.linspace(0.0, 1.0, n)
    reference = np.zeros(n)
    for j, value in enumerate(values):
        for d, w in closed_form_taps("zv", 0.2 + 0.05 * value, 0.0).items():
            reference[j + d:] += w * (1e-3 if j else 0.0)
    np.testing.assert_allclose(run_fmpy(fmu, u, values), reference, rtol=0, atol=1e-12)
