"""Random FMI call sequences against one FMU, as a hostile or careless host would make them.

Usage: python fmi_fuzzer.py FMU_DIR VERSION SEED SEQUENCES LOG
FMU_DIR is an extracted FMU, VERSION 2 or 3. Each sequence instantiates (sometimes with a wrong
name or token), makes random calls in random order -- every entry point, with NULL arrays behind
non-zero counts, NULL output pointers, unknown value references, NaN, infinite and huge numbers,
strings that are not UTF-8, FMU states of this instance, of another FMU and forged ones -- then frees
the instance (sometimes twice), instantiates another, and calls the first again through its stale
handle. The FMU must answer every call with a status: the process must not crash or hang. Arrays
passed with a count always hold that many elements, as the standard requires of a host (no FMU can
check a count against a buffer's real size). Each call is written to LOG before it is made, so a
crash leaves the sequence that caused it. Prints "ok <sequences> <calls> <statuses>" at the end.
"""

import ctypes
import random
import sys
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path
from ctypes import byref, c_bool, c_char_p, c_double, c_int, c_int64, c_size_t, c_uint, c_void_p

NUMBERS = [0.0, 1e-3, 1.0, -1.0, 0.5, 2e3, float("nan"), float("inf"), -float("inf"), 1e300, -1e300, 1e-300, 5e-324]
STRINGS = [b"", b"zvd", b"simultaneous", b"\xff\xfe\xfd", b"\xc3\x28", b"x" * 5000, b"ei"]


class Fuzzer:
    def __init__(self, directory: Path, version: int, rng: random.Random, log):
        self.directory, self.version, self.rng, self.log = directory, version, rng, log
        root = ET.parse(directory / "modelDescription.xml").getroot()
        cs = root.find("CoSimulation")
        self.identifier = cs.get("modelIdentifier")
        self.me = root.find("ModelExchange") is not None
        self.token = (root.get("guid") or root.get("instantiationToken")).encode()
        variables = list(root.iter("ScalarVariable")) if version == 2 else list(root.find("ModelVariables"))
        self.vrs = sorted({int(v.get("valueReference")) for v in variables})
        platform = "linux64" if version == 2 else "x86_64-linux"
        self.lib = ctypes.CDLL(str(directory / "binaries" / platform / f"{self.identifier}.so"))
        self.statuses = Counter()
        self.calls = 0
        self.garbage = (ctypes.c_ubyte * 512)(*(rng.randrange(256) for _ in range(512)))
        self._keep = []

    # ------------------------------------------------------------------ arguments
    def number(self):
        return c_double(self.rng.choice(NUMBERS + [self.rng.uniform(-10, 10)]))

    def vr_array(self, count):
        choices = self.vrs + [max(self.vrs) + 1, 10**6, 2**32 - 1]
        return (c_uint * max(count, 1))(*(self.rng.choice(choices) for _ in range(max(count, 1))))

    def values(self, ctype, count):
        if ctype is c_double:
            return (c_double * max(count, 1))(*(self.rng.choice(NUMBERS) for _ in range(max(count, 1))))
        if ctype is c_char_p:
            return (c_char_p * max(count, 1))(*(self.rng.choice(STRINGS) for _ in range(max(count, 1))))
        return (ctype * max(count, 1))(*(self.rng.choice([0, 1, 2, -1, 62, 63, 2**31 - 1]) % (256 if ctype is c_bool else 2**31)
                                         for _ in range(max(count, 1))))

    def array_call(self, ctype):
        """(vr array or None, count, value array or None): NULL behind a non-zero count now and then."""
        count = self.rng.choice([0, 1, 2, 3, len(self.vrs)])
        vr = None if self.rng.random() < 0.15 else self.vr_array(count)
        values = None if self.rng.random() < 0.15 else self.values(ctype, count)
        return vr, c_size_t(count), values

    def state(self, states):
        """An FMU state: one of this instance's, NULL, or a forged one (bytes that are no state)."""
        pick = self.rng.random()
        if states and pick < 0.6:
            return self.rng.choice(states)
        if pick < 0.8:
            return c_void_p(ctypes.addressof(self.garbage))
        return c_void_p(None)

    def out(self, ctype):
        return None if self.rng.random() < 0.1 else byref(ctype())

    # ------------------------------------------------------------------ calls
    def call(self, name, *args):
        function = getattr(self.lib, name, None)
        if function is None:
            return None
        self.calls += 1
        self.log.write(f"{name}{tuple(type(a).__name__ if a is not None else None for a in args)}\n")
        self.log.flush()
        function.restype = RESTYPES.get(name, c_int)
        status = function(*args)
        if function.restype is c_int:
            assert 0 <= status <= 5, f"{name} returned {status}, which is no FMI status"
            self.statuses[status] += 1
        return status

    def instantiate(self):
        name = b"" if self.rng.random() < 0.05 else b"fuzz"
        token = self.token if self.rng.random() > 0.05 else b"{not-this-fmu}"
        if self.version == 2:
            kind = 0 if self.me and self.rng.random() < 0.4 else 1
            callbacks = self._callbacks()
            location = (self.directory / "resources").resolve().as_uri().encode() if self.rng.random() > 0.05 else b"file:///nowhere"
            return self.call("fmi2Instantiate", name, c_int(kind), token, location, byref(callbacks), 0, 0)
        if self.me and self.rng.random() < 0.4:
            return self.call("fmi3InstantiateModelExchange", name, token, b"/tmp/", c_bool(False), c_bool(False), None, LOG3)
        return self.call("fmi3InstantiateCoSimulation", name, token, b"/tmp/", c_bool(False), c_bool(False),
                         c_bool(False), c_bool(False), None, c_size_t(0), None, LOG3, None)

    def _callbacks(self):
        callbacks = Callbacks(LOG2, ALLOCATE, FREE, None, None)
        self._keep.append(callbacks)
        return callbacks

    def random_call(self, c, states):
        r = self.rng
        t, h = self.number(), self.number()
        if self.version == 2:
            calls = [
                lambda: self.call("fmi2SetupExperiment", c, c_int(r.randrange(2)), self.number(), t, c_int(r.randrange(2)), self.number()),
                lambda: self.call("fmi2EnterInitializationMode", c),
                lambda: self.call("fmi2ExitInitializationMode", c),
                lambda: self.call("fmi2Terminate", c),
                lambda: self.call("fmi2Reset", c),
                lambda: self.call("fmi2GetReal", c, *self.array_call(c_double)),
                lambda: self.call("fmi2SetReal", c, *self.array_call(c_double)),
                lambda: self.call("fmi2GetInteger", c, *self.array_call(c_int)),
                lambda: self.call("fmi2SetInteger", c, *self.array_call(c_int)),
                lambda: self.call("fmi2GetBoolean", c, *self.array_call(c_int)),
                lambda: self.call("fmi2SetBoolean", c, *self.array_call(c_int)),
                lambda: self.call("fmi2GetString", c, *self.array_call(c_char_p)),
                lambda: self.call("fmi2SetString", c, *self.array_call(c_char_p)),
                lambda: self.call("fmi2DoStep", c, t, h, c_int(r.randrange(2))),
                lambda: self.call("fmi2DoStep", c, c_double(0.0), c_double(1e-3), c_int(1)),
                lambda: self.call("fmi2SetDebugLogging", c, c_int(1), c_size_t(r.randrange(3)), None),
                lambda: self.call("fmi2GetStatus", c, c_int(r.randrange(5)), self.out(c_int)),
                lambda: self.call("fmi2GetRealStatus", c, c_int(r.randrange(5)), self.out(c_double)),
                lambda: self.call("fmi2GetBooleanStatus", c, c_int(r.randrange(5)), self.out(c_int)),
                lambda: self.call("fmi2CancelStep", c),
                lambda: self._get_state(c, states, "fmi2GetFMUstate"),
                lambda: self.call("fmi2SetFMUstate", c, self.state(states)),
                lambda: self._free_state(c, states, "fmi2FreeFMUstate"),
                lambda: self.call("fmi2SerializedFMUstateSize", c, self.state(states), self.out(c_size_t)),
                lambda: self._serialise(c, states),
                lambda: self.call("fmi2EnterEventMode", c),
                lambda: self.call("fmi2NewDiscreteStates", c, None if r.random() < 0.3 else byref((c_int * 6)())),
                lambda: self.call("fmi2EnterContinuousTimeMode", c),
                lambda: self.call("fmi2CompletedIntegratorStep", c, c_int(1), self.out(c_int), self.out(c_int)),
                lambda: self.call("fmi2SetTime", c, t),
                lambda: self.call("fmi2SetContinuousStates", c, *self._vector()),
                lambda: self.call("fmi2GetDerivatives", c, *self._vector()),
                lambda: self.call("fmi2GetEventIndicators", c, *self._vector()),
                lambda: self.call("fmi2GetContinuousStates", c, *self._vector()),
                lambda: self.call("fmi2GetNominalsOfContinuousStates", c, *self._vector()),
                lambda: self.call("fmi2GetDirectionalDerivative", c, *self._directional()),
            ]
        else:
            calls = [
                lambda: self.call("fmi3EnterInitializationMode", c, c_bool(r.randrange(2)), self.number(), t,
                                  c_bool(r.randrange(2)), self.number()),
                lambda: self.call("fmi3ExitInitializationMode", c),
                lambda: self.call("fmi3Terminate", c),
                lambda: self.call("fmi3Reset", c),
                lambda: self.call("fmi3GetFloat64", c, *self._array3(c_double)),
                lambda: self.call("fmi3SetFloat64", c, *self._array3(c_double)),
                lambda: self.call("fmi3GetInt32", c, *self._array3(c_int)),
                lambda: self.call("fmi3SetInt64", c, *self._array3(c_int64)),
                lambda: self.call("fmi3SetString", c, *self._array3(c_char_p)),
                lambda: self.call("fmi3DoStep", c, t, h, c_bool(r.randrange(2)), self.out(c_bool), self.out(c_bool),
                                  self.out(c_bool), self.out(c_double)),
                lambda: self.call("fmi3DoStep", c, c_double(0.0), c_double(1e-3), c_bool(True), byref(c_bool()),
                                  byref(c_bool()), byref(c_bool()), byref(c_double())),
                lambda: self.call("fmi3EnterStepMode", c),
                lambda: self.call("fmi3SetDebugLogging", c, c_bool(True), c_size_t(r.randrange(3)), None),
                lambda: self._get_state(c, states, "fmi3GetFMUState"),
                lambda: self.call("fmi3SetFMUState", c, self.state(states)),
                lambda: self._free_state(c, states, "fmi3FreeFMUState"),
                lambda: self.call("fmi3SerializedFMUStateSize", c, self.state(states), self.out(c_size_t)),
                lambda: self._serialise(c, states),
                lambda: self.call("fmi3EnterEventMode", c),
                lambda: self.call("fmi3UpdateDiscreteStates", c, *(self.out(c_bool) for _ in range(5)), self.out(c_double)),
                lambda: self.call("fmi3EnterContinuousTimeMode", c),
                lambda: self.call("fmi3CompletedIntegratorStep", c, c_bool(True), self.out(c_bool), self.out(c_bool)),
                lambda: self.call("fmi3SetTime", c, t),
                lambda: self.call("fmi3SetContinuousStates", c, *self._vector()),
                lambda: self.call("fmi3GetContinuousStateDerivatives", c, *self._vector()),
                lambda: self.call("fmi3GetEventIndicators", c, *self._vector()),
                lambda: self.call("fmi3GetContinuousStates", c, *self._vector()),
                lambda: self.call("fmi3GetNominalsOfContinuousStates", c, *self._vector()),
                lambda: self.call("fmi3GetNumberOfContinuousStates", c, self.out(c_size_t)),
                lambda: self.call("fmi3GetNumberOfEventIndicators", c, self.out(c_size_t)),
                lambda: self.call("fmi3GetDirectionalDerivative", c, *self._directional3()),
            ]
        r.choice(calls)()

    def _vector(self):
        count = self.rng.choice([0, 1, 2, 4, 6, 7])
        return (None if self.rng.random() < 0.3 else (c_double * max(count, 1))()), c_size_t(count)

    def _array3(self, ctype):
        vr, count, values = self.array_call(ctype)
        n_values = count if self.rng.random() < 0.8 else c_size_t(count.value + 1)
        if values is not None and n_values.value > count.value:
            values = self.values(ctype, n_values.value)
        return vr, count, values, n_values

    def _directional(self):
        n, k = self.rng.randrange(3), self.rng.randrange(3)
        pick = lambda array: None if self.rng.random() < 0.2 else array  # noqa: E731
        return (pick(self.vr_array(n)), c_size_t(n), pick(self.vr_array(k)), c_size_t(k),
                pick(self.values(c_double, k)), pick((c_double * max(n, 1))()))

    def _directional3(self):
        unknowns, n, knowns, k, seed, sensitivity = self._directional()
        return unknowns, n, knowns, k, seed, k, sensitivity, n

    def _get_state(self, c, states, name):
        state = c_void_p(None)
        if self.call(name, c, None if self.rng.random() < 0.1 else byref(state)) == 0 and state.value:
            states.append(state)

    def _free_state(self, c, states, name):
        if states and self.rng.random() < 0.7:
            state = states.pop(self.rng.randrange(len(states)))
            self.call(name, c, byref(state))
        else:
            self.call(name, c, None if self.rng.random() < 0.5 else byref(c_void_p(None)))

    SERIAL_CALLS = {2: ("fmi2SerializedFMUstateSize", "fmi2SerializeFMUstate", "fmi2DeSerializeFMUstate"),
                    3: ("fmi3SerializedFMUStateSize", "fmi3SerializeFMUState", "fmi3DeserializeFMUState")}

    def _serialise(self, c, states):
        size_call, serialise_call, deserialise_call = self.SERIAL_CALLS[self.version]
        size = c_size_t(0)
        state = self.state(states)
        if self.call(size_call, c, state, byref(size)) != 0 or size.value > 10**7:
            return
        buffer = (ctypes.c_char * max(size.value, 1))()
        if self.call(serialise_call, c, state, buffer, size) != 0:
            return
        if self.rng.random() < 0.5:  # a forged copy: one byte changed
            buffer[self.rng.randrange(max(size.value, 1))] = bytes([self.rng.randrange(256)])
        length = c_size_t(size.value if self.rng.random() < 0.8 else self.rng.randrange(size.value + 1))
        copy = c_void_p(None)
        if self.call(deserialise_call, c, buffer, length, byref(copy)) == 0 and copy.value:
            states.append(copy)

    def free(self, c):
        self.call("fmi2FreeInstance" if self.version == 2 else "fmi3FreeInstance", c)

    def sequence(self, length):
        c = self.instantiate()
        if not c:
            return
        c = c_void_p(c)
        states = []
        for _ in range(length):
            self.random_call(c, states)
        for state in states:  # through the instance that made them, before it goes
            self.call("fmi2FreeFMUstate" if self.version == 2 else "fmi3FreeFMUState", c, byref(state))
        self.free(c)
        if self.rng.random() < 0.5:
            self.free(c)  # twice
        other = self.instantiate()  # likely at the freed instance's address, were it released
        for _ in range(self.rng.randrange(4)):
            self.random_call(c, [])  # the stale handle: refused, never served by `other`
        if other:
            self.free(c_void_p(other))


RESTYPES = {"fmi2Instantiate": c_void_p, "fmi3InstantiateCoSimulation": c_void_p, "fmi3InstantiateModelExchange": c_void_p,
            "fmi2FreeInstance": None, "fmi3FreeInstance": None}
LOG2 = ctypes.CFUNCTYPE(None, c_void_p, c_char_p, c_int, c_char_p, c_char_p)(lambda *args: None)
LOG3 = ctypes.CFUNCTYPE(None, c_void_p, c_int, c_char_p, c_char_p)(lambda *args: None)
_libc = ctypes.CDLL(None)
ALLOCATE = ctypes.cast(_libc.calloc, c_void_p)
FREE = ctypes.cast(_libc.free, c_void_p)


class Callbacks(ctypes.Structure):
    _fields_ = [("logger", type(LOG2)), ("allocateMemory", c_void_p), ("freeMemory", c_void_p),
                ("stepFinished", c_void_p), ("componentEnvironment", c_void_p)]


def main():
    directory, version, seed, sequences, log = Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
    with open(log, "w") as handle:
        fuzzer = Fuzzer(directory, version, random.Random(seed), handle)
        for number in range(sequences):
            handle.seek(0)
            handle.truncate()
            handle.write(f"sequence {number} of seed {seed}\n")
            fuzzer.sequence(fuzzer.rng.randrange(5, 40))
    print(f"ok {sequences} {fuzzer.calls} {dict(sorted(fuzzer.statuses.items()))}")


if __name__ == "__main__":
    main()
