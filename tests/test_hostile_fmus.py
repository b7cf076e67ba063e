"""Every FMU answers every call with a status, whatever a host passes it (issue 23).

A fuzzer of FMI 2.0 and 3.0 call sequences (tests/fmi_fuzzer.py, fixed seeds, a few seconds) runs
in a child process against the native plants, Shaper and ShapeFilter and the pythonfmu Shaper, and
directed tests pin what it found: NULL arrays behind non-zero counts in the FMI 3.0 plant, a string
that is not UTF-8, another FMU's or a forged FMU state, and a call through a freed instance's handle
after a new instance was made.
"""

from __future__ import annotations

import ctypes
import struct
import subprocess
import sys
import zipfile
from ctypes import byref, c_bool, c_char_p, c_double, c_int, c_size_t, c_uint, c_void_p
from pathlib import Path

import pytest
from fmpy import read_model_description

from shapefmu.cosim.fmpy_log import listening
from shapefmu.fmi import build_fmu
from shapefmu.fmi.native import build_plant_fmu, model_from_file
from shapefmu.fmi.native.sampled import build_native_fmu

FUZZER = Path(__file__).resolve().parent / "fmi_fuzzer.py"
SHAPER = {"kind": "zvd", "f[1]": 10.0, "zeta[1]": 0.05, "Ts": 1e-3}


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    """{name: (extracted folder, FMI version)} of the FMUs under test."""
    folder = tmp_path_factory.mktemp("hostile_fmus")
    built = {
        "plant": (build_plant_fmu("disk_drive", folder / "DiskDrive.fmu"), 2),
        "pendulum": (build_plant_fmu(model_from_file("pendulum"), folder / "Pendulum.fmu"), 2),
        "plant3": (build_plant_fmu("disk_drive", folder / "DiskDrive3.fmu", fmi_version="3.0"), 3),
        "shaper": (build_native_fmu("Shaper", folder / "NativeShaper.fmu", **SHAPER), 2),
        "other shaper": (build_native_fmu("Shaper", folder / "OtherShaper.fmu", **{**SHAPER, "f[1]": 12.0}), 2),
        "filter": (build_native_fmu("ShapeFilter", folder / "NativeFilter.fmu", kind="hanning", f=7.0, Ts=1e-3,
                                    adjust_Ts=True), 2),
        "python shaper": (build_fmu("Shaper", folder / "Shaper.fmu"), 2),
    }
    extracted = {}
    for name, (fmu, version) in built.items():
        target = folder / name.replace(" ", "_")
        zipfile.ZipFile(fmu).extractall(target)
        extracted[name] = (target, version)
    return extracted


@pytest.mark.parametrize("name, sequences", [("plant", 300), ("pendulum", 300), ("plant3", 300), ("shaper", 300),
                                             ("filter", 300), ("python shaper", 100)])
@pytest.mark.parametrize("seed", [23, 2323])
def test_random_call_sequences_never_crash_an_fmu(fmus, tmp_path, name, sequences, seed):
    folder, version = fmus[name]
    log = tmp_path / "sequence.log"
    done = subprocess.run([sys.executable, str(FUZZER), str(folder), str(version), str(seed), str(sequences), str(log)],
                          capture_output=True, text=True, timeout=120)
    last = log.read_text()[-3000:] if log.exists() else ""
    assert done.returncode == 0, f"exit {done.returncode} in this sequence:\n{last}\n{done.stderr[-2000:]}"
    assert done.stdout.startswith(f"ok {sequences} ")
    statuses = eval(done.stdout.split(" ", 3)[3])  # noqa: S307 - our own fuzzer's summary {status: count}
    assert set(statuses) <= {0, 1, 2, 3} and statuses[0] > 0  # fmi2Fatal never: every refusal is an error


# ------------------------------------------------------------------------- directed cases

LOG3 = ctypes.CFUNCTYPE(None, c_void_p, c_int, c_char_p, c_char_p)


class Host:
    """One FMU's library through ctypes; ``messages``: what the FMUs logged since it was made."""

    def __init__(self, folder: Path, version: int):
        self.description = read_model_description(str(folder))
        self.version = version
        identifier = self.description.coSimulation.modelIdentifier
        platform = "linux64" if version == 2 else "x86_64-linux"
        self.lib = ctypes.CDLL(str(folder / "binaries" / platform / f"{identifier}.so"))
        self.messages = messages = []  # the loggers hold the list, not the host
        self.folder = folder
        if version == 2:  # fmpy's proxy formats the C varargs message before it reaches Python
            self.callbacks = listening(lambda status, category, message: messages.append(message))
        else:
            self.logger = LOG3(lambda env, status, category, message: messages.append(message.decode()))
        self.vr = {v.name: v.valueReference for v in self.description.modelVariables}

    def __call__(self, name, *args):
        function = getattr(self.lib, name)
        function.restype = c_int
        return function(*args)

    def instantiate(self, model_exchange=False):
        if self.version == 3 and model_exchange:
            self.lib.fmi3InstantiateModelExchange.restype = c_void_p
            c = self.lib.fmi3InstantiateModelExchange(b"i", self.description.instantiationToken.encode(), b"/tmp/", False,
                                                      False, None, self.logger)
        elif self.version == 2:
            self.lib.fmi2Instantiate.restype = c_void_p
            location = (self.folder / "resources").resolve().as_uri().encode()
            c = self.lib.fmi2Instantiate(b"i", 1, self.description.guid.encode(), location, byref(self.callbacks), 0, 0)
        else:
            self.lib.fmi3InstantiateCoSimulation.restype = c_void_p
            c = self.lib.fmi3InstantiateCoSimulation(b"i", self.description.instantiationToken.encode(), b"/tmp/", False,
                                                     False, False, False, None, c_size_t(0), None, self.logger, None)
        assert c
        return c_void_p(c)

    def initialized(self, model_exchange=False):
        c = self.instantiate(model_exchange)
        if self.version == 2:
            assert self("fmi2SetupExperiment", c, 0, c_double(0), c_double(0), 0, c_double(0)) == 0
            assert self("fmi2EnterInitializationMode", c) == 0 and self("fmi2ExitInitializationMode", c) == 0
        else:
            assert self("fmi3EnterInitializationMode", c, False, c_double(0), c_double(0), False, c_double(0)) == 0
            assert self("fmi3ExitInitializationMode", c) == 0
        return c


@pytest.mark.parametrize("call, arguments, words", [
    ("fmi3GetFloat64", lambda: (None, c_size_t(2), (c_double * 2)(), c_size_t(2)), "vr is NULL but holds 2 values"),
    ("fmi3SetFloat64", lambda: ((c_uint * 1)(7), c_size_t(1), None, c_size_t(1)), "values is NULL but holds 1 values"),
    ("fmi3GetContinuousStates", lambda: (None, c_size_t(6)), "x is NULL but holds 6 values"),
    ("fmi3SetContinuousStates", lambda: (None, c_size_t(6)), "x is NULL but holds 6 values"),
    ("fmi3GetContinuousStateDerivatives", lambda: (None, c_size_t(6)), "derivatives is NULL but holds 6 values"),
    ("fmi3GetNominalsOfContinuousStates", lambda: (None, c_size_t(6)), "nominals is NULL but holds 6 values"),
    ("fmi3GetDirectionalDerivative", lambda: ((c_uint * 1)(7), c_size_t(1), (c_uint * 1)(1), c_size_t(1), None,
                                              c_size_t(1), (c_double * 1)(), c_size_t(1)), "seed is NULL but holds 1"),
])
def test_the_fmi3_plant_refuses_null_arrays_behind_a_count(fmus, call, arguments, words):
    host = Host(*fmus["plant3"])
    c = host.initialized(model_exchange=True)  # in Event Mode: every one of these calls is allowed there
    assert host(call, c, *arguments()) == 3  # fmi3Error, no segfault
    assert any(words in message for message in host.messages), host.messages
    host("fmi3FreeInstance", c)


def test_a_string_that_is_not_utf8_is_an_error_not_a_fatal(fmus):
    host = Host(*fmus["python shaper"])
    c = host.instantiate()
    kind = (c_uint * 1)(host.vr["kind"])
    assert host("fmi2SetString", c, kind, c_size_t(1), (c_char_p * 1)(b"zv\xff\xfe")) == 3
    assert any("not UTF-8" in message for message in host.messages)
    assert host("fmi2SetString", c, kind, c_size_t(1), (c_char_p * 1)(b"zvd")) == 0  # still alive, not fatal
    host("fmi2FreeInstance", c)


def test_a_native_fmu_refuses_another_fmus_state(fmus):
    plant, shaper = Host(*fmus["plant"]), Host(*fmus["shaper"])
    p, s = plant.initialized(), shaper.initialized()
    state = c_void_p()
    assert plant("fmi2GetFMUstate", p, byref(state)) == 0
    assert shaper("fmi2SetFMUstate", s, state) == 3
    assert any("not one of this FMU" in m for m in shaper.messages)
    assert plant("fmi2FreeFMUstate", p, byref(state)) == 0
    for host, c in ((plant, p), (shaper, s)):
        host("fmi2FreeInstance", c)


def serialised(host, c) -> bytearray:
    state, size = c_void_p(), c_size_t()
    assert host("fmi2GetFMUstate", c, byref(state)) == 0
    assert host("fmi2SerializedFMUstateSize", c, state, byref(size)) == 0
    buffer = (ctypes.c_char * size.value)()
    assert host("fmi2SerializeFMUstate", c, state, buffer, size) == 0
    host("fmi2FreeFMUstate", c, byref(state))
    return bytearray(buffer.raw)


def test_a_native_shaper_refuses_the_serialised_state_of_another_shaper_build(fmus):
    one, other = Host(*fmus["shaper"]), Host(*fmus["other shaper"])
    a, b = one.initialized(), other.initialized()
    data = serialised(other, b)
    copy = c_void_p()
    assert one("fmi2DeSerializeFMUstate", a, (ctypes.c_char * len(data)).from_buffer(data), c_size_t(len(data)), byref(copy)) == 3
    assert any("not a serialised state of this FMU" in m for m in one.messages), one.messages
    one("fmi2FreeInstance", a), other("fmi2FreeInstance", b)


@pytest.mark.parametrize("variable, value, words", [
    ("impulse_time[1]", float("nan"), "impulse_time[1] must be >= 0 (s), got nan"),
    ("Ts", -1.0, "Ts must be > 0, got -1"),
    ("impulse_amplitude[1]", float("inf"), "impulse_amplitude[1] must be finite, got inf"),
])
def test_a_forged_state_with_values_a_set_would_refuse_is_refused(fmus, variable, value, words):
    host = Host(*fmus["shaper"])
    c = host.initialized()
    data = serialised(host, c)
    offset = 8 * 8 + 3 * 8 + 3 * 8 + 8 * host.vr[variable]  # the header, time, start time, clock ticks, clock position, Reals
    data[offset:offset + 8] = struct.pack("<d", value)
    forged = c_void_p()
    assert host("fmi2DeSerializeFMUstate", c, (ctypes.c_char * len(data)).from_buffer(data), c_size_t(len(data)),
                byref(forged)) == 0  # well-formed bytes: refused when they would be used
    assert host("fmi2SetFMUstate", c, forged) == 3
    assert any(f"fmi2SetFMUstate: {words}" in m for m in host.messages), host.messages
    host("fmi2FreeInstance", c)


@pytest.mark.parametrize("name", ["plant", "shaper", "plant3"])
def test_a_freed_handle_is_refused_after_a_new_instance_is_made(fmus, capfd, name):
    host = Host(*fmus[name])
    first = host.initialized()
    prefix = f"fmi{host.version}"
    host(f"{prefix}FreeInstance", first)
    second = host.initialized()  # where the allocator would put it, were the first's memory released
    if host.version == 2:
        stale = host("fmi2DoStep", first, c_double(0.0), c_double(1e-3), 1)
    else:
        stale = host("fmi3DoStep", first, c_double(0.0), c_double(1e-3), True, byref(c_bool()), byref(c_bool()),
                     byref(c_bool()), byref(c_double()))
    assert stale == 3 and f"{prefix}DoStep called on an instance that is not live" in capfd.readouterr().err
    # the second instance did not take the first's step: its own first step still starts at t = 0
    if host.version == 2:
        assert host("fmi2DoStep", second, c_double(0.0), c_double(1e-3), 1) == 0
    else:
        assert host("fmi3DoStep", second, c_double(0.0), c_double(1e-3), True, byref(c_bool()), byref(c_bool()),
                    byref(c_bool()), byref(c_double())) == 0
    host(f"{prefix}FreeInstance", second)
