"""The TrackedShaper FMU (fmi/kinds/tracked_shaper.py) in fmpy: its FMU state restores the run exactly,
and a measurement that is not a number is refused naming it; the pythonfmu FMU and its native C twin
(fmi/native/tracked_shaper.py) alike. The native FMU refuses bad parameters with a logged message (a
shaper or an EKF window longer than it holds at the exit of initialisation), and what it cannot design
in C (another kind, n > 62) when it is built.
Its closed loop is tests/test_tracked_cosim.py; the twin contract tests/test_native_twin_contract.py."""

import math
import re

import numpy as np
import pytest
from support.fmpy_slaves import initialised, refused_start_values

TS = 5e-4
STARTS = {"f0": 33.0, "Ts": TS}  # as support/fixtures_fmi.py's tracked_fmu: the bed's guess 10 % off, at 2 kHz


@pytest.fixture(params=["pythonfmu", "native"])
def tracked(request, builds):
    """The TrackedShaper of STARTS as the pythonfmu FMU or as its native C twin."""
    return getattr(builds, request.param)("TrackedShaper", **STARTS)


@pytest.fixture
def native_tracked(builds):
    return builds.native("TrackedShaper", **STARTS)


def feed(slave, vr, k0, commands, measurements):
    """y at each sample k0, k0 + 1, ...: both inputs set, y read, the step taken."""
    y = []
    for k, (u, m) in enumerate(zip(commands, measurements), start=k0):
        slave.setReal([vr["u"], vr["measurement"]], [float(u), float(m)])
        y.append(slave.getReal([vr["y"]])[0])
        slave.doStep(k * TS, TS)
    return y


def test_a_restored_state_gives_the_same_run_again(tracked):
    """The command rests before the first sample (the kernel counts that as rested for ever): the state
    holds no inf, and restoring it replays the moves and the rings the EKF watches bit for bit."""
    t = np.arange(1200) * TS
    commands = np.where((t > 0.01) & (t < 0.03) | (t > 0.3) & (t < 0.32), 5.0, 0.0)
    measurements = 0.3 * np.exp(-5.0 * t) * np.sin(2.0 * math.pi * 30.0 * t)
    slave, vr = initialised(tracked)
    feed(slave, vr, 0, commands[:10], measurements[:10])  # taken while the command still rests since before t0
    state = slave.deSerializeFMUstate(slave.serializeFMUstate(slave.getFMUstate()))
    first = feed(slave, vr, 10, commands[10:], measurements[10:])
    slave.setFMUstate(state)
    again = feed(slave, vr, 10, commands[10:], measurements[10:])
    slave.freeInstance()
    assert again == first and np.ptp(first) > 0


def test_a_measurement_that_is_not_a_number_is_refused(tracked):
    from fmpy.fmi1 import FMICallException

    slave, vr = initialised(tracked)
    with pytest.raises(FMICallException):
        slave.setReal([vr["measurement"]], [float("nan")])
    slave.freeInstance()


@pytest.mark.parametrize(("starts", "words"), [
    ({"f0": -1.0}, "f0 must be > 0, got -1"),
    ({"kind": "ei"}, "kind must be one of zv, zvd, zvdd, zv_dn, mzv (the kinds this FMU designs in C), got ei"),
    ({"n": 63}, "n must be an integer in [0, 62], got 63"),
    ({"band_low": 1.2}, "band_low must be in (0, 1), got 1.2"),
    ({"zeta_max": 1.0}, "zeta_max must be in [0, 1), got 1"),
    ({"noise": 0.0}, "noise must be > 0, got 0"),
    # at the exit of initialisation: pi fs = 6283.19 rad/s, 1100 Hz is 6911.5 rad/s
    ({"f0": 1100.0}, "lies at or above the Nyquist frequency pi*fs = 6283.19 rad/s"),
    # a ZV shaper for 1 mHz at 2 kHz is half a period long: 1e6 samples (+ 2), past the limit
    ({"f0": 1e-3}, "samples long, more than the limit of 1,000,000 (shapefmu.runtime.limits.MAX_SAMPLED_LENGTH)"),
    # a 2 mHz mode at 3.2 kHz: its ZV shaper (8e5 samples) fits, the EKF's window (a period, 1.6e6) does not
    ({"f0": 2e-3, "Ts": 5e-4 / 1.6}, "the EKF's convergence window; at most 1000000"),
])
def test_bad_parameters_are_refused_by_the_native_fmu_with_a_logged_message(native_tracked, capfd, starts, words):
    """Refused when set if the value alone is out of range, else at the exit of initialisation."""
    assert refused_start_values(native_tracked, starts).status == 3  # fmi2Error
    assert words in capfd.readouterr().out


@pytest.mark.parametrize(("starts", "words"), [
    ({"kind": "ei"}, "kind must be one of zv, zvd, zvdd, zv_dn, mzv for the native TrackedShaper"),
    ({"kind": "zv_dn", "n": 63}, "n must be an integer in [0, 62] for the native TrackedShaper, got 63"),
])
def test_what_c_cannot_design_is_refused_when_the_native_fmu_is_built(tmp_path, starts, words):
    from shapefmu.fmi.native.tracked_shaper import build_native_tracked_shaper

    with pytest.raises(ValueError, match=re.escape(words)):
        build_native_tracked_shaper(tmp_path / "refused.fmu", **starts)
    assert not (tmp_path / "refused.fmu").exists()


def test_the_command_line_builds_the_native_fmu_and_refuses_a_kind_c_cannot_design(tmp_path):
    import zipfile

    from fmpy import read_model_description
    from hostile_support import guarded

    out = tmp_path / "Tracked.fmu"
    code, _, err = guarded(["build", "tracked-shaper", "--native", "--param", "kind=zvd", "--param", "f0=27",
                            "-o", out], seconds=120)
    assert code == 0, err
    starts = {v.name: v.start for v in read_model_description(str(out)).modelVariables}
    assert (starts["kind"], float(starts["f0"])) == ("zvd", 27.0)
    assert "sources/tracked_shaper_part.c" in zipfile.ZipFile(out).namelist()
    code, _, err = guarded(["build", "tracked-shaper", "--native", "--param", "kind=ei", "-o", tmp_path / "ei.fmu"])
    assert code == 2 and err.count("\n") == 1 and "kind must be one of zv, zvd, zvdd, zv_dn, mzv" in err, err
