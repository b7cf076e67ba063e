"""Small FMUs with closed-form behaviour, for the co-simulation tests.

Each FMU is a pythonfmu slave built from a few lines of source below, so what the master must
produce can be written down by hand: a ramp source, a gain ``y = k*u + c`` (feed-through), a
forward-Euler integrator, and a gain that refuses to save its state (for the algebraic-loop error).
The modules have distinct names because pythonfmu FMUs share one interpreter per process.
"""

from __future__ import annotations

import re
import textwrap
import zipfile
from pathlib import Path

SOURCES = {
    # y(t) = slope * t + bias, t the time reached by the last step (the start time before any).
    "CosimRamp": """
        class CosimRamp(Fmi2Slave):
            def __init__(self, **kwargs):
                super().__init__(**kwargs)
                self.slope = 1.0
                self.bias = 0.0
                self.time = 0.0
                self.register_variable(Real("slope", causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))
                self.register_variable(Real("bias", causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))
                self.register_variable(Real("time", causality=Fmi2Causality.local))
                self.register_variable(Real("y", causality=Fmi2Causality.output, getter=lambda: self.slope * self.time + self.bias))

            def do_step(self, current_time, step_size):
                self.time = current_time + step_size
                return True
    """,
    # y = k*u + c: the output after a step (and in initialisation) follows the input directly.
    "CosimGain": """
        class CosimGain(Fmi2Slave):
            def __init__(self, **kwargs):
                super().__init__(**kwargs)
                self.k = 1.0
                self.c = 0.0
                self.u = 0.0
                self.register_variable(Real("k", causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))
                self.register_variable(Real("c", causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))
                self.register_variable(Real("u", causality=Fmi2Causality.input))
                self.register_variable(Real("y", causality=Fmi2Causality.output, getter=lambda: self.k * self.u + self.c))

            def do_step(self, current_time, step_size):
                return True
    """,
    # x' = u by forward Euler over each step; y = x (no feed-through).
    "CosimIntegrator": """
        class CosimIntegrator(Fmi2Slave):
            def __init__(self, **kwargs):
                super().__init__(**kwargs)
                self.x0 = 0.0
                self.u = 0.0
                self.integral = 0.0
                self.register_variable(Real("x0", causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed))
                self.register_variable(Real("u", causality=Fmi2Causality.input))
                self.register_variable(Real("integral", causality=Fmi2Causality.local))
                self.register_variable(Real("y", causality=Fmi2Causality.output, getter=lambda: self.x0 + self.integral))

            def do_step(self, current_time, step_size):
                self.integral += self.u * step_size
                return True
    """,
    # Returns fmi2Error from doStep once t reaches fail_at.
    "CosimFailing": """
        class CosimFailing(Fmi2Slave):
            def __init__(self, **kwargs):
                super().__init__(**kwargs)
                self.fail_at = 1.0
                self.y = 0.0
                self.register_variable(Real("fail_at", causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))
                self.register_variable(Real("y", causality=Fmi2Causality.output))

            def do_step(self, current_time, step_size):
                self.y = current_time + step_size
                return current_time + step_size < self.fail_at
    """,
}

# Same as CosimGain, built without FMU-state support.
SOURCES["CosimGainNoState"] = SOURCES["CosimGain"].replace("CosimGain", "CosimGainNoState")

_HEADER = (
    "from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real\n"
)

WITHOUT_STATE = {"CosimGainNoState"}

# pythonfmu lists outputs without a ``dependencies`` attribute, which FMI 2.0 reads as "depends on
# every input"; these FMUs' outputs depend on no input at the same instant, so we say so.
WITHOUT_FEEDTHROUGH = {"CosimRamp", "CosimIntegrator", "CosimFailing"}


def build_test_fmu(name: str, directory: Path) -> Path:
    """Build one of the FMUs above into ``directory`` and return its path."""
    from pythonfmu import FmuBuilder

    directory.mkdir(parents=True, exist_ok=True)
    script = directory / f"{name}.py"
    script.write_text(_HEADER + textwrap.dedent(SOURCES[name]))
    options = {} if name in WITHOUT_STATE else {"canGetAndSetFMUstate": True, "canSerializeFMUstate": True}
    options["needsExecutionTool"] = False
    path = Path(FmuBuilder.build_FMU(script, dest=directory / f"{name}.fmu", **options))
    if name in WITHOUT_FEEDTHROUGH:
        _declare_no_feedthrough(path)
    return path


def _declare_no_feedthrough(path: Path) -> None:
    with zipfile.ZipFile(path) as archive:
        members = {info.filename: archive.read(info) for info in archive.infolist()}
    xml = members["modelDescription.xml"].decode()
    xml = re.sub(r'(<Outputs>.*?</Outputs>)', lambda m: m.group(1).replace('<Unknown ', '<Unknown dependencies="" '), xml, flags=re.S)
    members["modelDescription.xml"] = xml.encode()
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for filename, data in members.items():
            archive.writestr(filename, data)
