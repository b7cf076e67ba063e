"""Plant FMU step cost: the native disk-drive FMU against the same plant as a pythonfmu FMU.

Both are driven through fmpy's FMU2Slave with the same inputs and step, and both take the exact
zero-order-hold step x+ = Phi x + Gamma u (the native FMU in C, the pythonfmu one in numpy, each
computing Phi and Gamma once for the step size). Prints microseconds per fmi2DoStep and the ratio,
and checks that both FMUs give the same outputs.

    .venv/bin/python benchmarks/plant_step.py
"""

import tempfile
import textwrap
import time
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from pythonfmu import FmuBuilder

from shapefmu.fmi.native import build_plant_fmu
from shapefmu.plants import load

MODEL = Path(__file__).resolve().parent.parent / "models" / "disk_drive.toml"
H = 1e-5
STEPS = 20_000

PYTHON_SLAVE = '''
import numpy as np
import scipy.linalg
from pythonfmu import Fmi2Causality, Fmi2Slave, Real

A = np.array({A})
B = np.array({B})
C = np.array({C})


class DiskDriveNumpy(Fmi2Slave):
    """The disk drive of models/disk_drive.toml, exact zero-order hold in numpy."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.voltage = 0.0
        self.position = self.deflection_1 = self.deflection_2 = 0.0
        self.register_variable(Real("voltage", causality=Fmi2Causality.input))
        for name in ("position", "deflection_1", "deflection_2"):
            self.register_variable(Real(name, causality=Fmi2Causality.output))
        self._x = np.zeros(A.shape[0])
        self._step = None

    def do_step(self, current_time, step_size):
        if step_size != self._step:
            n, m = B.shape
            M = np.zeros((n + m, n + m))
            M[:n, :n], M[:n, n:] = A * step_size, B * step_size
            E = scipy.linalg.expm(M)
            self._phi, self._gamma, self._step = E[:n, :n], E[:n, n:].ravel(), step_size
        self._x = self._phi @ self._x + self._gamma * self.voltage
        self.position, self.deflection_1, self.deflection_2 = C @ self._x
        return True
'''


def build_python_fmu(directory: Path) -> Path:
    plant = load(MODEL)
    script = directory / "disk_drive_numpy.py"
    script.write_text(textwrap.dedent(PYTHON_SLAVE).format(A=plant.A.tolist(), B=plant.B.tolist(), C=plant.C.tolist()))
    return FmuBuilder.build_FMU(script, dest=directory)


def run(fmu: Path, inputs):
    """(microseconds per doStep, outputs after every step)."""
    description = read_model_description(str(fmu))
    refs = {v.name: v.valueReference for v in description.modelVariables}
    slave = FMU2Slave(guid=description.guid, unzipDirectory=extract(str(fmu)),
                      modelIdentifier=description.coSimulation.modelIdentifier, instanceName="bench")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    outputs = [refs["position"], refs["deflection_1"], refs["deflection_2"]]
    recorded = np.empty((len(inputs), 3))
    elapsed = 0.0
    for k, u in enumerate(inputs):
        slave.setReal([refs["voltage"]], [u])
        start = time.perf_counter()
        slave.doStep(currentCommunicationPoint=k * H, communicationStepSize=H)
        elapsed += time.perf_counter() - start
        recorded[k] = slave.getReal(outputs)
    slave.terminate()
    slave.freeInstance()
    return 1e6 * elapsed / len(inputs), recorded


def main():
    inputs = 11.0 * np.sign(np.sin(np.arange(STEPS) / 50.0))
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        native = build_plant_fmu(MODEL, tmp / "DiskDrive.fmu")
        python = build_python_fmu(tmp)
        native_us, native_y = run(native, inputs)
        python_us, python_y = run(python, inputs)
    difference = np.max(np.abs(native_y - python_y)) / np.max(np.abs(python_y))
    print(f"disk drive, {STEPS} steps of {H:g} s through fmpy (exact ZOH in both):")
    print(f"  native C plant FMU     {native_us:8.2f} us per doStep")
    print(f"  pythonfmu numpy FMU    {python_us:8.2f} us per doStep")
    print(f"  ratio pythonfmu/native {python_us / native_us:8.1f}x   (outputs agree to {difference:.1e} relative)")


if __name__ == "__main__":
    main()
