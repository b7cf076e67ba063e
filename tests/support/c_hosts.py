"""Our C test hosts (tests/hosts_c/fmi2_host.c, fmi3_host.c): compiled once per session, run on extracted FMUs.

    c_host, fmi3_host            session fixtures: the compiled hosts (gcc, no network)
    fmu_arguments(fmu, folder)   fmi2_host's ``--fmu DIR IDENTIFIER GUID INPUTS OUTPUTS`` for one FMU
    fmi3_arguments(fmu, folder)  fmi3_host's ``--fmu DIR IDENTIFIER TOKEN INPUTS OUTPUTS`` (Float64 scalars)
    run_host(c_host, [fmu args...], *options, env=None) -> subprocess.CompletedProcess
    host_rows(csv) -> {(pass, fmu, instance): array of rows (t, inputs..., outputs...)}

fmi2_host keeps time as ``t += h`` and trims the last step onto the stop time, can step by stop/N
or by random sizes, and tears its instances down normally, from an exit handler registered before
it loaded the FMUs, or never; it can set Reals in initialization mode (``--set-real``), tear down
after a failed call as OMSimulator does (``--on-error omsimulator``), and make any list of calls on
one instance (``--calls``). fmi3_host is its FMI 3.0 twin (and ticks clocks). Their header comments
list the options.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description

from support import FMI_HEADERS, HOSTS_C


@pytest.fixture(scope="session")
def c_host(tmp_path_factory) -> Path:
    """hosts_c/fmi2_host.c, compiled with the system compiler."""
    program = tmp_path_factory.mktemp("c_host") / "fmi2_host"
    subprocess.run(["gcc", "-O2", "-Wall", "-Wextra", "-Werror", "-o", str(program), str(HOSTS_C / "fmi2_host.c"),
                    "-ldl", "-lm"], check=True, capture_output=True, text=True)
    return program


@pytest.fixture(scope="session")
def fmi3_host(tmp_path_factory) -> Path:
    """hosts_c/fmi3_host.c, compiled with the system compiler."""
    program = tmp_path_factory.mktemp("fmi3_host") / "fmi3_host"
    subprocess.run(["gcc", "-O2", "-Wall", "-Wextra", "-Werror", "-I", str(FMI_HEADERS), "-o", str(program),
                    str(HOSTS_C / "fmi3_host.c"), "-ldl", "-lm"], check=True, capture_output=True, text=True)
    return program


def _arguments(fmu, folder: Path, real: str, token: str) -> list[str]:
    md = read_model_description(str(fmu))
    directory = extract(str(fmu), str(folder))
    scalars = [v for v in md.modelVariables if v.type == real and not getattr(v, "dimensions", None)]
    inputs = [v.valueReference for v in scalars if v.causality == "input"]
    outputs = [v.valueReference for v in scalars if v.causality == "output"]
    return ["--fmu", str(Path(directory).resolve()), md.coSimulation.modelIdentifier, getattr(md, token),
            ",".join(map(str, inputs)) or "-", ",".join(map(str, outputs)) or "-"]


def fmu_arguments(fmu, folder: Path) -> list[str]:
    """fmi2_host's ``--fmu`` and its five values for ``fmu``, extracted into ``folder`` (Real inputs and outputs)."""
    return _arguments(fmu, folder, "Real", "guid")


def fmi3_arguments(fmu, folder: Path) -> list[str]:
    """fmi3_host's ``--fmu`` and its five values for ``fmu``, extracted into ``folder`` (Float64 scalars)."""
    return _arguments(fmu, folder, "Float64", "instantiationToken")


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
