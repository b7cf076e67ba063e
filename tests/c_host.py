"""Our C test host (hosts_c/fmi2_host.c): compiled once per session, run on extracted FMUs.

    c_host                      session fixture: the compiled host (gcc, no network)
    fmu_arguments(fmu, folder)  the host's ``--fmu DIR IDENTIFIER GUID INPUTS OUTPUTS`` for one FMU
    run_host(c_host, [fmu args...], *options, env=None) -> subprocess.CompletedProcess
    host_rows(csv) -> {(pass, fmu, instance): array of rows (t, inputs..., outputs...)}

The host keeps time as ``t += h`` and trims the last step onto the stop time, can step by stop/N
or by random sizes, and tears its instances down normally, from an exit handler registered before
it loaded the FMUs, or never; it can set Reals in initialization mode (``--set-real``), tear down
after a failed call as OMSimulator does (``--on-error omsimulator``), and make any list of calls on
one instance (``--calls``). Its header comment lists the options.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest

SOURCE = Path(__file__).parent / "hosts_c" / "fmi2_host.c"


@pytest.fixture(scope="session")
def c_host(tmp_path_factory) -> Path:
    """The C host, compiled with the system compiler."""
    program = tmp_path_factory.mktemp("c_host") / "fmi2_host"
    subprocess.run(["gcc", "-O2", "-Wall", "-Wextra", "-Werror", "-o", str(program), str(SOURCE), "-ldl", "-lm"],
                   check=True, capture_output=True, text=True)
    return program


def fmu_arguments(fmu, folder: Path) -> list[str]:
    """``--fmu`` and its five values for ``fmu``, extracted into ``folder`` (Real inputs and outputs)."""
    from fmpy import extract, read_model_description

    md = read_model_description(str(fmu))
    directory = extract(str(fmu), str(folder))
    inputs = [v.valueReference for v in md.modelVariables if v.causality == "input" and v.type == "Real"]
    outputs = [v.valueReference for v in md.modelVariables if v.causality == "output" and v.type == "Real"]
    return ["--fmu", str(Path(directory).resolve()), md.coSimulation.modelIdentifier, md.guid,
            ",".join(map(str, inputs)) or "-", ",".join(map(str, outputs)) or "-"]


def run_host(c_host: Path, fmus: list[list[str]], *options, env=None, timeout=300) -> subprocess.CompletedProcess:
    """The host run on ``fmus`` (lists from ``fmu_arguments``) with ``options``; never raises on failure."""
    command = [str(c_host), *map(str, options)]
    for arguments in fmus:
        command += arguments
    return subprocess.run(command, capture_output=True, text=True, errors="replace", timeout=timeout, env=env)


def host_rows(csv: Path) -> dict:
    """The host's CSV by (pass, fmu index, instance index): rows of (t, inputs..., outputs...)."""
    rows = {}
    for line in Path(csv).read_text().splitlines():
        cells = line.split(",")
        rows.setdefault(tuple(int(c) for c in cells[:3]), []).append([float(c) for c in cells[3:]])
    return {key: np.array(value) for key, value in rows.items()}
