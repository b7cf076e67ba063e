"""Forged FMU states are refused on restore (issue 34, item 11).

fmi2SetReal(u, NaN) is refused, but a serialised state with NaN or inf in a Shaper's or
ShapeFilter's latched input, start time or delay line was accepted and made NaN outputs. Now a
restore checks what a set call checks: the native twins (FMI 2.0 and 3.0) refuse a state with a
non-finite latched input, history, start time, or a position off their sample grid; the pythonfmu
FMUs refuse a state holding any non-finite number or a sample clock no run reaches.

The states are forged the way an attacker would: a run leaves distinctive numbers in the state
(u0 = pi/10 fills the delay line, u = 1/sqrt(2) is latched half a sample after t0 = 123.456), and
every copy of one of them is overwritten in the serialised bytes. The unforged bytes restore the
same outputs (the check is no blanket refusal).
"""

from __future__ import annotations

import math
import struct

import numpy as np
import pytest

TS = 1e-3
T0 = 123.456
U0 = math.pi / 10
LATCHED = 1.0 / math.sqrt(2.0)
KINDS = {
    "Shaper": {"kind": "zvd", "n_modes": 1, "f[1]": 13.0, "zeta[1]": 0.05, "Ts": TS, "u0": U0},
    "ShapeFilter": {"kind": "hanning", "f": 10.0 / math.sqrt(1.0 - 0.05**2), "zeta": 0.05, "Ts": TS, "u0": U0},
}
BUILDS = ("pythonfmu", "native 2.0", "native 3.0")
BAD = (float("nan"), float("inf"), -float("inf"))
# What is forged: the model's copies of the latched input and of the delay line's values, and the time.
FORGED = {"latched input": LATCHED, "delay line": U0, "time": T0 + 0.5 * TS}


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    from shapefmu.fmi.native.twins import build_native
    from shapefmu.fmi.python.builder import build_fmu

    folder = tmp_path_factory.mktemp("forged_states")
    built = {}
    for name, values in KINDS.items():
        built[name, "pythonfmu"] = build_fmu(name, folder / f"{name}.fmu", **values)
        for version in ("2.0", "3.0"):
            built[name, f"native {version}"] = build_native(name, folder / f"{name}_{version}.fmu", fmi_version=version,
                                                            **values)
    return built


class _Instance:
    """An FMU instance half a sample after T0, its input latched; its state serialised."""

    def __init__(self, path):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave
        from fmpy.fmi3 import FMU3Slave

        md = read_model_description(str(path))
        self.fmi3 = md.fmiVersion.startswith("3")
        vr = {v.name: v.valueReference for v in md.modelVariables}
        self.u, self.y = vr["u"], vr["y"]
        self.slave = (FMU3Slave if self.fmi3 else FMU2Slave)(
            guid=md.guid, unzipDirectory=extract(str(path)), modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName="forged")
        self.slave.instantiate()
        if self.fmi3:
            self.slave.enterInitializationMode(startTime=T0)
        else:
            self.slave.setupExperiment(startTime=T0)
            self.slave.enterInitializationMode()
        self.slave.exitInitializationMode()
        self.set(LATCHED)
        self.slave.doStep(T0, 0.5 * TS)
        state = self.slave.getFMUState() if self.fmi3 else self.slave.getFMUstate()
        self.serial = bytes(self.slave.serializeFMUState(state) if self.fmi3 else self.slave.serializeFMUstate(state))

    def set(self, u):
        (self.slave.setFloat64 if self.fmi3 else self.slave.setReal)([self.u], [u])

    def y_after(self, steps):
        """y after each of ``steps`` steps of Ts from where the state left it, u = 0."""
        t, ys = T0 + 0.5 * TS, []
        for _ in range(steps):
            self.set(0.0)
            self.slave.doStep(t, TS)
            t += TS
            ys.append((self.slave.getFloat64 if self.fmi3 else self.slave.getReal)([self.y])[0])
        return ys

    def restore(self, serial):
        """Restore ``serial``; raises fmpy's FMICallException if the FMU refuses it."""
        if self.fmi3:
            self.slave.setFMUState(self.slave.deserializeFMUState(serial))
        else:
            self.slave.setFMUstate(self.slave.deSerializeFMUstate(serial))


def _forge(serial, value, bad, text, first=False):
    """``serial`` with the copies of ``value`` after the first replaced by ``bad`` (``first``: every
    copy), as a double or as JSON text. The first copy is the variable's (the values come before the
    model's own data in both kinds of state), the later ones the model's: what fmi2SetReal never sees."""
    if text:
        old, new = repr(value).encode(), {"nan": "NaN", "inf": "Infinity", "-inf": "-Infinity"}[repr(bad)].encode()
    else:
        old, new = struct.pack("<d", value), struct.pack("<d", bad)
    head, found, tail = serial.partition(old)
    assert found and (first or old in tail), f"{value!r} is not in the state {'at all' if not found else 'twice'}"
    return serial.replace(old, new) if first else head + found + tail.replace(old, new)


@pytest.mark.parametrize("build", BUILDS)
@pytest.mark.parametrize("name", KINDS)
def test_the_unforged_state_restores_the_same_outputs(fmus, name, build):
    instance = _Instance(fmus[name, build])
    expected = instance.y_after(100)
    instance.restore(instance.serial)
    assert instance.y_after(100) == expected and all(map(math.isfinite, expected))
    assert np.ptp(expected) > 0


@pytest.mark.parametrize("bad", BAD, ids=repr)
@pytest.mark.parametrize("what", FORGED)
@pytest.mark.parametrize("build", BUILDS)
@pytest.mark.parametrize("name", KINDS)
def test_a_state_with_a_non_finite_number_is_refused_with_a_message(fmus, name, build, what, bad, capfd):
    from fmpy.fmi1 import FMICallException

    instance = _Instance(fmus[name, build])
    capfd.readouterr()
    forged = _forge(instance.serial, FORGED[what], bad, text=build == "pythonfmu", first=what == "time")
    with pytest.raises(FMICallException):
        instance.restore(forged)
    out = capfd.readouterr().out
    assert "state" in out.lower(), out


@pytest.mark.parametrize("build", ["native 2.0", "native 3.0"])
@pytest.mark.parametrize("name", KINDS)
@pytest.mark.parametrize("since", [-0.25 * TS, TS, 1e300], ids=["-Ts/4", "Ts", "1e300"])
def test_a_native_state_off_its_sample_grid_is_refused(fmus, name, build, since):
    from fmpy.fmi1 import FMICallException

    instance = _Instance(fmus[name, build])
    forged = _forge(instance.serial, 0.5 * TS, since, text=False, first=True)  # the time since the current sample
    with pytest.raises(FMICallException):
        instance.restore(forged)


@pytest.mark.parametrize("build", ["native 2.0", "native 3.0"])
@pytest.mark.parametrize("name", KINDS)
def test_a_native_state_holds_the_start_time_once_where_a_restore_checks_it(fmus, name, build, capfd):
    """The layer's start time, which a restore checks: the FIR keeps no copy of its own to forge."""
    from fmpy.fmi1 import FMICallException

    instance = _Instance(fmus[name, build])
    assert instance.serial.count(struct.pack("<d", T0)) == 1
    with pytest.raises(FMICallException):
        instance.restore(_forge(instance.serial, T0, float("nan"), text=False, first=True))
    assert "state" in capfd.readouterr().out
