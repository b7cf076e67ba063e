"""Forged FMU states and clock abuse against one native FMU, as a hostile host would make them.

Usage: python state_clock_fuzzer.py FMU_DIR VERSION SEED CASES

FMU_DIR is an extracted shapefmu FMU (native, or pythonfmu: its JSON state's numbers are forged), VERSION 2 or 3. Each case instantiates one instance at a
start time drawn from 0, 1e3, 1e6 and 1.7e9, takes a few steps, then, in turn:

- states: serialises its state, overwrites 8 bytes at a random offset (a NaN, an infinity, a huge,
  denormal or negative number, a random bit pattern; in a JSON state, one of its numbers) or cuts or
  lengthens the bytes, and restores it;
- clocks (an FMU with an input clock): random calls of Event Mode, fmi3SetClock, fmi3UpdateDiscreteStates,
  fmi3EnterStepMode and fmi3DoStep with steps to and past the ticks, tiny, huge, aimed at absolute
  instants, negative or NaN, with non-finite inputs set in between.

After every call that answers OK, the outputs are read: a NaN or infinite output then is a silent NaN.
The process must not crash or hang. Prints "ok CASES calls refused silent_nan" at the end.
"""

import ctypes
import math
import random
import re
import struct
import sys
import xml.etree.ElementTree as ET
from ctypes import POINTER, byref, c_bool, c_char_p, c_double, c_int, c_size_t, c_uint, c_void_p
from pathlib import Path

SPECIAL = [math.nan, math.inf, -math.inf, 1e308, -1e308, 5e-324, -0.0, -1.0, 1e300, 2.0**63, -(2.0**63)]
START_TIMES = [0.0, 1e3, 1e6, 1.7e9]
LOG = ctypes.CFUNCTYPE(None, c_void_p, c_char_p, c_int, c_char_p, c_char_p)  # FMI 2.0 logger (no varargs used)
LOG3 = ctypes.CFUNCTYPE(None, c_void_p, c_int, c_char_p, c_char_p)


class Fuzzer:
    def __init__(self, directory: Path, version: int, rng: random.Random):
        self.rng, self.version = rng, version
        root = ET.parse(directory / "modelDescription.xml").getroot()
        identifier = root.find("CoSimulation").get("modelIdentifier")
        self.token = (root.get("guid") or root.get("instantiationToken")).encode()
        self.resources = (directory / "resources").resolve().as_uri().encode()  # a pythonfmu FMU reads its code there
        platform = "linux64" if version == 2 else "x86_64-linux"
        self.lib = ctypes.CDLL(str(directory / "binaries" / platform / f"{identifier}.so"))
        variables = list(root.iter("ScalarVariable")) if version == 2 else list(root.find("ModelVariables"))
        kind = (lambda v: v.find("Real") is not None) if version == 2 else (lambda v: v.tag == "Float64")
        scalar = (lambda v: True) if version == 2 else (lambda v: v.find("Dimension") is None)
        self.inputs = [int(v.get("valueReference")) for v in variables
                       if v.get("causality") == "input" and kind(v) and scalar(v)]
        self.outputs = [int(v.get("valueReference")) for v in variables
                        if v.get("causality") == "output" and kind(v) and scalar(v)]
        self.clock = [int(v.get("valueReference")) for v in variables if v.tag == "Clock"]
        interval = [v.get("intervalDecimal") for v in variables if v.tag == "Clock"]
        self.ts = float(interval[0]) if interval else 1e-3
        self.calls = self.refused = self.silent_nan = 0
        self._log2, self._log3 = LOG(lambda *a: None), LOG3(lambda *a: None)
        self.f = {}

    def fn(self, name, restype=c_int):
        if name not in self.f:
            self.f[name] = getattr(self.lib, name)
            self.f[name].restype = restype
        return self.f[name]

    def call(self, name, *args):
        self.calls += 1
        status = self.fn(name)(*args)
        if status > 1:
            self.refused += 1
        return status

    def prefix(self, name):
        return f"fmi{self.version}{name}"

    # ------------------------------------------------------------------ life cycle
    def instantiate(self, t0):
        if self.version == 2:
            callbacks = (c_void_p * 5)(ctypes.cast(self._log2, c_void_p), ctypes.cast(ctypes.CDLL(None).calloc, c_void_p),
                                       ctypes.cast(ctypes.CDLL(None).free, c_void_p), None, None)
            self.fn("fmi2Instantiate", c_void_p).argtypes = [c_char_p, c_int, c_char_p, c_char_p, c_void_p, c_int, c_int]
            c = self.fn("fmi2Instantiate", c_void_p)(b"fuzz", 1, self.token, self.resources, callbacks, 0, 0)
            self._callbacks = callbacks
            c = c_void_p(c)
            self.call("fmi2SetupExperiment", c, 0, c_double(0.0), c_double(t0), 0, c_double(0.0))
            self.call("fmi2EnterInitializationMode", c)
            self.call("fmi2ExitInitializationMode", c)
            return c
        inst = self.fn("fmi3InstantiateCoSimulation", c_void_p)
        inst.argtypes = [c_char_p, c_char_p, c_char_p, c_bool, c_bool, c_bool, c_bool, c_void_p, c_size_t, c_void_p,
                         LOG3, c_void_p]
        c = c_void_p(inst(b"fuzz", self.token, b"", False, False, bool(self.clock), False, None, 0, None, self._log3, None))
        self.call("fmi3EnterInitializationMode", c, False, c_double(0.0), c_double(t0), False, c_double(0.0))
        self.call("fmi3ExitInitializationMode", c)
        return c

    def free(self, c):
        self.call(self.prefix("Terminate"), c)
        self.fn(self.prefix("FreeInstance"), None)(c)

    def set_inputs(self, c, value=None):
        if not self.inputs:
            return
        values = (c_double * len(self.inputs))(*[value if value is not None else self.rng.uniform(-1, 1)
                                                 for _ in self.inputs])
        vrs = (c_uint * len(self.inputs))(*self.inputs)
        name = "fmi2SetReal" if self.version == 2 else "fmi3SetFloat64"
        if self.version == 2:
            return self.call(name, c, vrs, c_size_t(len(self.inputs)), values)
        return self.call(name, c, vrs, c_size_t(len(self.inputs)), values, c_size_t(len(self.inputs)))

    def outputs_finite(self, c):
        """Read the outputs; counts a silent NaN if the call answers OK with a non-finite value."""
        if not self.outputs:
            return
        values = (c_double * len(self.outputs))()
        vrs = (c_uint * len(self.outputs))(*self.outputs)
        if self.version == 2:
            status = self.call("fmi2GetReal", c, vrs, c_size_t(len(self.outputs)), values)
        else:
            status = self.call("fmi3GetFloat64", c, vrs, c_size_t(len(self.outputs)), values, c_size_t(len(self.outputs)))
        if status <= 1 and not all(math.isfinite(v) for v in values):
            self.silent_nan += 1
            print("silent NaN", list(values), file=sys.stderr)

    def step(self, c, t, h):
        if self.version == 2:
            return self.call("fmi2DoStep", c, c_double(t), c_double(h), 1)
        flags = (c_bool(), c_bool(), c_bool(), c_double())
        return self.call("fmi3DoStep", c, c_double(t), c_double(h), True, *[byref(x) for x in flags])

    def tick(self, c):
        """Event Mode at a tick: the inputs, the clock, back to Step Mode."""
        self.set_inputs(c)
        self.call("fmi3SetClock", c, (c_uint * 1)(*self.clock), c_size_t(1), (c_bool * 1)(True))
        flags = [c_bool(), c_bool(), c_bool(), c_bool(), c_bool(), c_double()]
        self.call("fmi3UpdateDiscreteStates", c, *[byref(x) for x in flags])
        self.call("fmi3EnterStepMode", c)

    def run_steps(self, c, t, n):
        """n steps of Ts (clocked: ticking at each); returns the time reached."""
        for _ in range(n):
            if self.clock:
                self.tick(c)
            else:
                self.set_inputs(c)
            if self.step(c, t, self.ts) <= 1:
                t += self.ts
            if self.clock:
                self.call("fmi3EnterEventMode", c)
            self.outputs_finite(c)
        return t

    # ------------------------------------------------------------------ cases
    def forged_state(self, c, t):
        name = self.prefix
        state = c_void_p()
        if self.call(name("GetFMUState" if self.version == 3 else "GetFMUstate"), c, byref(state)) > 1:
            return
        size = c_size_t()
        self.call(name("SerializedFMUStateSize" if self.version == 3 else "SerializedFMUstateSize"), c, state, byref(size))
        buffer = (ctypes.c_ubyte * size.value)()
        self.call(name("SerializeFMUState" if self.version == 3 else "SerializeFMUstate"), c, state, buffer, size)
        data = bytearray(buffer)
        choice = self.rng.random()
        json_state = 0 <= data.find(b'{"') < 64  # a pythonfmu FMU's: JSON after the front end's header
        numbers = list(re.finditer(rb"-?\d+\.\d+(e[-+]?\d+)?", data)) if json_state else []
        if numbers and choice < 0.8:  # one of its numbers made another
            number = self.rng.choice(numbers)
            data[number.start():number.end()] = self.rng.choice([b"NaN", b"Infinity", b"-Infinity", b"1e999", b"-0.0",
                                                                 b"1e308", b"5e-324", b"3", b"true", b"null"])
        elif choice < 0.8 and len(data) >= 8:
            # mostly a whole double of the state (its fields are 8 bytes each), sometimes across two
            at = 8 * self.rng.randrange(len(data) // 8) if self.rng.random() < 0.8 else self.rng.randrange(len(data) - 7)
            value = self.rng.choice(SPECIAL) if self.rng.random() < 0.7 else None
            data[at:at + 8] = struct.pack("<d", value) if value is not None else self.rng.randbytes(8)
        elif choice < 0.9:
            data = data[: self.rng.randrange(0, len(data) + 1)]
        else:
            data += self.rng.randbytes(self.rng.choice([1, 8, 64]))
        forged = (ctypes.c_ubyte * max(1, len(data)))(*data)
        copy = c_void_p()
        deserialize = name("DeserializeFMUState" if self.version == 3 else "DeSerializeFMUstate")
        if self.call(deserialize, c, forged, c_size_t(len(data)), byref(copy)) <= 1:
            if self.call(name("SetFMUState" if self.version == 3 else "SetFMUstate"), c, copy) <= 1:
                self.outputs_finite(c)
                self.run_steps(c, t, 200)  # long enough for a forged value anywhere in a delay line to reach a tap

    def clock_abuse(self, c, t0, t):
        choices = ["event", "set", "update", "stepmode", "step", "inputs"]
        for _ in range(self.rng.randrange(5, 30)):
            what = self.rng.choice(choices)
            if what == "event":
                self.call("fmi3EnterEventMode", c)
            elif what == "set":
                self.call("fmi3SetClock", c, (c_uint * 1)(*self.clock), c_size_t(1), (c_bool * 1)(self.rng.random() < 0.9))
            elif what == "update":
                flags = [c_bool(), c_bool(), c_bool(), c_bool(), c_bool(), c_double()]
                self.call("fmi3UpdateDiscreteStates", c, *[byref(x) for x in flags])
            elif what == "stepmode":
                self.call("fmi3EnterStepMode", c)
            elif what == "inputs":
                self.set_inputs(c, self.rng.choice([None, math.nan, math.inf, 1e308]))
            else:
                k = math.floor((t - t0) / self.ts) + self.rng.randint(1, 3)
                h = self.rng.choice([self.ts, 0.7 * self.ts, 1e-16, 1e-300, 5e-324, 1e300, -self.ts, math.nan, math.inf,
                                     t0 + k * self.ts - t, self.rng.uniform(0, 3 * self.ts)])
                if self.step(c, t, h) <= 1:
                    t += h
            self.outputs_finite(c)
        return t

    def case(self):
        t0 = self.rng.choice(START_TIMES)
        c = self.instantiate(t0)
        if not c.value:
            return
        t = self.run_steps(c, t0, self.rng.randrange(1, 20))
        if self.clock and self.rng.random() < 0.5:
            self.clock_abuse(c, t0, t)
        else:
            self.forged_state(c, t)
        self.free(c)


def main():
    directory, version, seed, cases = Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
    fuzzer = Fuzzer(directory, version, random.Random(seed))
    for _ in range(cases):
        fuzzer.case()
    print(f"ok {cases} {fuzzer.calls} {fuzzer.refused} {fuzzer.silent_nan}")


if __name__ == "__main__":
    main()
