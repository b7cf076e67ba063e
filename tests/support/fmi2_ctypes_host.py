"""A standard-library-only FMI 2.0 co-simulation host (ctypes), run as a ``python -I -S`` script.

Usage: python -I -S fmi2_ctypes_host.py FMU_DIR[,FMU_DIR...] STEPS H
FMU_DIR is an extracted FMU. For each step k the command is sin(0.05 k) + (1 if 20 <= k < 60); the
FMUs are stepped interleaved in one process, and one JSON line per FMU gives its outputs y. The
script first proves the isolation: numpy, shapefmu, fmpy and pythonfmu must not be importable.
"""

import ctypes
import importlib.util
import json
import math
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

for forbidden in ("numpy", "shapefmu", "fmpy", "pythonfmu"):
    if importlib.util.find_spec(forbidden) is not None:
        sys.exit(f"isolation broken: {forbidden} is importable")

LOGGER = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p)


class Callbacks(ctypes.Structure):
    _fields_ = [("logger", LOGGER), ("allocateMemory", ctypes.c_void_p), ("freeMemory", ctypes.c_void_p),
                ("stepFinished", ctypes.c_void_p), ("componentEnvironment", ctypes.c_void_p)]


@LOGGER
def log(env, name, status, category, message):
    print(f"[{status}] {message.decode()}", file=sys.stderr)


def check(status, what):
    if status > 1:
        sys.exit(f"{what} returned status {status}")


def open_fmu(directory):
    md = ET.parse(directory / "modelDescription.xml").getroot()
    identifier = md.find("CoSimulation").get("modelIdentifier")
    vr = {v.get("name"): int(v.get("valueReference")) for v in md.iter("ScalarVariable")}
    lib = ctypes.CDLL(str(directory / "binaries" / "linux64" / f"{identifier}.so"))
    lib.fmi2Instantiate.restype = ctypes.c_void_p
    lib.fmi2Instantiate.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p,
                                    ctypes.POINTER(Callbacks), ctypes.c_int, ctypes.c_int]
    callbacks = Callbacks(log, None, None, None, None)
    c = lib.fmi2Instantiate(b"i", 1, md.get("guid").encode(), (directory / "resources").resolve().as_uri().encode(),
                            ctypes.byref(callbacks), 0, 0)
    if not c:
        sys.exit(f"fmi2Instantiate failed for {directory}")
    c = ctypes.c_void_p(c)
    check(lib.fmi2SetupExperiment(c, 0, ctypes.c_double(0), ctypes.c_double(0), 0, ctypes.c_double(0)), "setup")
    check(lib.fmi2EnterInitializationMode(c), "enter")
    check(lib.fmi2ExitInitializationMode(c), "exit")
    return lib, c, vr, callbacks


def main():
    directories = [Path(p) for p in sys.argv[1].split(",")]
    steps, h = int(sys.argv[2]), float(sys.argv[3])
    fmus = [open_fmu(d) for d in directories]
    outputs = [[] for _ in fmus]
    for k in range(steps):
        u = math.sin(0.05 * k) + (1.0 if 20 <= k < 60 else 0.0)
        for (lib, c, vr, _), out in zip(fmus, outputs):
            check(lib.fmi2SetReal(c, (ctypes.c_uint * 1)(vr["u"]), 1, (ctypes.c_double * 1)(u)), "setReal")
            check(lib.fmi2DoStep(c, ctypes.c_double(k * h), ctypes.c_double(h), 1), "doStep")
            y = (ctypes.c_double * 1)()
            check(lib.fmi2GetReal(c, (ctypes.c_uint * 1)(vr["y"]), 1, y), "getReal")
            out.append(y[0])
    for lib, c, _, _ in fmus:
        lib.fmi2Terminate(c)
        lib.fmi2FreeInstance(c)
    for out in outputs:
        print(json.dumps(out))


main()
