"""The ImpulseTrain FMU (fmi/kinds/impulse_train.py) on the train ``recommend`` designs for a real
printer (the Switchwire's X recording of tests/data/recordings), written by ``recommend --build``
and by ``build shaper --impulses``.

The reference is the closed form of a shaper: y(t) = sum_i a_i u(t - t_i), evaluated by numpy on
the continuous command. The FMU samples u at k Ts and splits each impulse off the grid onto its two
neighbouring samples (linear interpolation of the samples); for a command that is linear between
samples (a trapezoidal move with its corners on the grid) that interpolation is exact, so the
sampled output must equal the closed form to rounding, whatever the impulses. The pythonfmu FMU, the
native FMI 2.0 and FMI 3.0 FMUs and libcosim's run are held to it and to each other (1e-12).
"""

import json
import math

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu
from hostile_support import guarded

from support import TESTS
from support.hosts import run_fmpy, run_libcosim

RECORDING = TESTS / "data" / "recordings" / "switchwire_resonances_x_20211024_204517.csv"
TS = 5e-5  # a whole number of nanoseconds, as libcosim's step must be


@pytest.fixture(scope="module")
def picked(tmp_path_factory):
    """(the JSON, the FMU it wrote) of ``recommend --json --build`` on the recording."""
    fmu = tmp_path_factory.mktemp("pick") / "Pick.fmu"
    code, out, err = guarded(["recommend", RECORDING, "--axis", "x", "--json", "--build", fmu], seconds=600)
    assert code == 0, err
    return json.loads(out), fmu


@pytest.fixture(scope="module")
def train(picked):
    """(times s, amplitudes) of the train recommend designed for the spectrum: its JSON row's impulses."""
    (row,) = [c for c in picked[0]["candidates"] if c["family"] == "train"]
    return row["impulse_times_s"], row["impulse_amplitudes"]


def trapezoid(t, ts):
    """A move's command, linear between corners on the grid k ts: up to 1 in 60 samples, held for 540
    (longer than the trains), down to -0.4 in 45, held (0 before t = 0)."""
    corners = np.array([0, 60, 600, 645]) * ts
    return np.interp(t, corners, [0.0, 1.0, 1.0, -0.4], left=0.0, right=-0.4)


def closed_form(times, amplitudes, t, ts):
    """sum_i a_i u(t - t_i) of the continuous command."""
    return sum(a * trapezoid(t - ti, ts) for ti, a in zip(times, amplitudes))


def shaped_in_fmpy(fmu, t):
    """y at the samples t = k Ts of the FMU (FMI 2.0 or 3.0) in fmpy: at each communication point
    t_k, u(t_k) set and y read (sample k, fed through), then a step of Ts."""
    md = read_model_description(str(fmu))
    three = md.fmiVersion.startswith("3")
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = (FMU3Slave if three else FMU2Slave)(guid=md.guid, unzipDirectory=extract(str(fmu)),
                                                modelIdentifier=md.coSimulation.modelIdentifier, instanceName="train")
    slave.instantiate()
    if three:
        slave.enterInitializationMode(startTime=0.0)
    else:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
    slave.exitInitializationMode()
    ts = float(t[1] - t[0])
    set_u, get_y = (slave.setFloat64, slave.getFloat64) if three else (slave.setReal, slave.getReal)
    rows = []
    for k, tk in enumerate(t):
        set_u([vr["u"]], [float(trapezoid(tk, ts))])
        rows.append(get_y([vr["y"]])[0])
        slave.doStep(k * ts, ts)
    slave.terminate()
    slave.freeInstance()
    return np.array(rows)


def _starts(times, amplitudes, ts):
    from shapefmu.fmi.kinds.impulse_train import train_start_values

    return {**train_start_values(times, amplitudes), "Ts": ts}


def test_recommend_build_writes_the_picked_train_as_an_impulse_train_that_shapes_as_its_closed_form(picked, train):
    advice, fmu = picked
    assert advice["pick"]["family"] == "train"  # the train is the pick on this machine (it dominates Klipper's)
    md = read_model_description(str(fmu))
    starts = {v.name: v.start for v in md.modelVariables if v.causality == "parameter"}
    times, amplitudes = train
    n = int(starts["n_impulses"])
    assert md.modelName == "ImpulseTrain" and n == len(times)
    assert [float(starts[f"impulse_time[{i}]"]) for i in range(1, n + 1)] == times
    np.testing.assert_allclose([float(starts[f"impulse_amplitude[{i}]"]) for i in range(1, n + 1)], amplitudes,
                               rtol=1e-15)  # the pick's own, normalised to sum to 1 (they do, within 1e-15)
    ts = float(starts["Ts"])
    t = ts * np.arange(1000)
    y = shaped_in_fmpy(fmu, t)
    np.testing.assert_allclose(y, closed_form(times, amplitudes, t, ts), rtol=0, atol=1e-12)
    assert max(y) == pytest.approx(1.0) and y[-1] == pytest.approx(-0.4)  # the whole move, shaped


@pytest.mark.parametrize("target", ["klipper", "rrf", "marlin"])
def test_recommend_build_writes_the_shaper_a_firmware_runs(tmp_path, target):
    """--build with --firmware klipper, rrf or marlin writes that firmware's pick (Klipper's: Klipper's own
    pick as its calibrate_shaper.py prints it for the file, tests/data/klipper/klipper_figures.json); the
    FMU shapes as the closed form of the pick's impulses, normalised to sum to 1."""
    fmu = tmp_path / "Pick.fmu"
    code, out, err = guarded(["recommend", RECORDING, "--axis", "x", "--firmware", target, "--json", "--build", fmu],
                             seconds=600)
    assert code == 0, err
    pick = json.loads(out)["pick"]
    assert pick["family"] in (target, "train") and pick["firmware_line"]
    if target == "klipper":
        figures = json.loads((TESTS / "data" / "klipper" / "klipper_figures.json").read_text())["files"]
        klippers = figures[RECORDING.name]["pick"]
        assert pick["shaper"] == klippers["name"] and pick["frequencies_hz"][0] == pytest.approx(klippers["freq"])
    md = read_model_description(str(fmu))
    assert md.modelName == pick["fmu_model"]
    total = math.fsum(pick["impulse_amplitudes"])
    ts = float(next(v.start for v in md.modelVariables if v.name == "Ts"))
    t = ts * np.arange(1200)
    np.testing.assert_allclose(shaped_in_fmpy(fmu, t), closed_form(pick["impulse_times_s"],
                                                                   [a / total for a in pick["impulse_amplitudes"]],
                                                                   t, ts), rtol=0, atol=1e-12)


@pytest.mark.parametrize("build", ["pythonfmu", "native 2.0", "native 3.0"])
def test_each_fmu_of_the_train_validates_and_shapes_as_the_closed_form(builds, train, build):
    times, amplitudes = train
    starts = _starts(times, amplitudes, TS)
    fmu = builds.pythonfmu("ImpulseTrain", **starts) if build == "pythonfmu" else \
        builds.native("ImpulseTrain", fmi_version=build.split()[1], **starts)
    assert validate_fmu(str(fmu)) == []
    t = TS * np.arange(1200)
    np.testing.assert_allclose(shaped_in_fmpy(fmu, t), closed_form(times, amplitudes, t, TS), rtol=0, atol=1e-12)


def test_pythonfmu_native_fmpy_and_libcosim_agree_to_1e_12(builds, quiet_libcosim, train):
    """Steps of 4 Ts and a command set at each communication point: the FMUs sample it on their own grid."""
    starts = _starts(*train, TS)
    python, native = builds.pythonfmu("ImpulseTrain", **starts), builds.native("ImpulseTrain", **starts)
    step = 4 * TS
    inputs = [{"u": float(trapezoid(k * step, TS))} for k in range(300)]
    reference = np.array(run_fmpy(python, inputs, step, ("y",)))
    assert max(reference) == pytest.approx(1.0) and reference[-1] == pytest.approx(-0.4)
    for fmu in (python, native):
        for host in (run_fmpy, run_libcosim):
            np.testing.assert_allclose(host(fmu, inputs, step, ("y",)), reference, rtol=0, atol=1e-12)


def test_build_shaper_impulses_normalises_what_the_user_types_and_says_so(tmp_path, train):
    """The pick's impulses typed with 4 decimals, as a person copies them: the FMU holds them divided
    by their sum, and shapes as the closed form of that train."""
    times = [round(t, 4) for t in train[0]]
    typed = [round(a, 4) for a in train[1]]
    out = tmp_path / "Typed.fmu"
    text = ",".join(f"{t}:{a}" for t, a in zip(times, typed))
    code, _, err = guarded(["build", "shaper", "--impulses", text, "--ts", str(TS), "-o", out], seconds=120)
    assert code == 0, err
    total = math.fsum(typed)
    assert (f"summed to {total!r}" in err) == (abs(total - 1) > 1e-9)
    amplitudes = [a / total for a in typed]
    t = TS * np.arange(1200)
    np.testing.assert_allclose(shaped_in_fmpy(out, t), closed_form(times, amplitudes, t, TS), rtol=0, atol=1e-12)


@pytest.mark.parametrize("argv,words", [
    (["--impulses", "0:0.5,0.01"], "item 2 is '0.01'"),
    (["--impulses", ",".join(["0:1"] * 33)], "at most 32 impulses, got 33"),
    (["--impulses", "0:0.5,0.01:0.5,0.005:0"], "impulse_time[3] must be > impulse_time[2] = 0.01 s"),
    (["--impulses=-0.001:1"], "impulse_time[1] must be >= 0 s"),
    (["--impulses", "0:1,0.01:-1"], "finite sum other than 0"),
    (["--impulses", "0:1", "--kind", "zv"], "--kind designs a shaper for --mode"),
    (["--impulses", "0:1", "--mode", "10"], "not allowed with argument --impulses"),
])
def test_bad_impulses_are_one_line_naming_them(tmp_path, argv, words):
    code, _, err = guarded(["build", "shaper", *argv, "-o", tmp_path / "X.fmu"])
    assert code == 2 and err.count("\n") == 1 and words in err, err


@pytest.mark.parametrize("changed,words", [
    ({"impulse_amplitude[2]": 0.4}, "must sum to 1 within 1e-09, got the sum 0.9"),
    ({"impulse_time[3]": 0.004}, "impulse_time[3] must be > impulse_time[2]"),
    ({"impulse_amplitude[6]": 0.1}, "must be 0 since n_impulses = 3"),
    ({"n_impulses": 2}, "must be 0 since n_impulses = 2"),
])
@pytest.mark.parametrize("build", ["pythonfmu", "native"])
def test_a_train_set_before_initialisation_is_checked_as_the_build_checks_it(builds, capfd, build, changed, words):
    """Hosts may set the impulses in initialisation: both FMUs refuse a bad train at its exit, with
    fmi2Error and a logged message naming it."""
    from support.fmpy_slaves import refused_initialisation

    starts = _starts([0.0, 0.0123, 0.0251], [0.3, 0.45, 0.25], 1e-3)
    fmu = builds.pythonfmu("ImpulseTrain", **starts) if build == "pythonfmu" else builds.native("ImpulseTrain", **starts)
    capfd.readouterr()
    assert refused_initialisation(fmu, changed).status == 3  # fmi2Error
    assert words in capfd.readouterr().out
