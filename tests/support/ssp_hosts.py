"""Run an .ssp file in the two peer hosts, libcosimpy and ecospy, recording outputs per step.

Both hosts step every FMU by the same fixed step (Jacobi); each returns an array of shape
(n_steps + 1, len(variables)) of the values after initialisation and after each step. libcosim's
last-value observer holds nothing before the first step, so its row 0 is NaN.
"""

from __future__ import annotations

import numpy as np

from shapefmu.fmi.ssp import PARAMETER_SET


def run_libcosim(ssp_path, step: float, n_steps: int, variables: list[str]) -> np.ndarray:
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_ssp_file(str(ssp_path), step_size=round(step * 1e9))  # libcosim time is in ns
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    slaves = {info.name.decode(): info.index for info in execution.slave_infos()}
    references = []
    for name in variables:
        component, _, variable = name.partition(".")
        index = slaves[component]
        described = {v.name.decode(): v for v in execution.slave_variables(index)}[variable]
        # Real variables and Integer ones (Integer and Real value references are separate spaces)
        read = observer.last_integer_values if described.type == 1 else observer.last_real_values
        references.append((read, index, described.reference))
    values = np.full((n_steps + 1, len(variables)), np.nan)
    for k in range(1, n_steps + 1):
        execution.step(1)
        values[k] = [read(index, [vr])[0] for read, index, vr in references]
    return values


def run_ecos(ssp_path, step: float, n_steps: int, variables: list[str]) -> np.ndarray:
    from ecospy.EcosSimulation import EcosSimulation

    simulation = EcosSimulation(ssp_path=str(ssp_path), step_size=step)
    simulation.init(parameter_set=PARAMETER_SET)  # ecos applies parameter sets by name
    identifiers = [name.replace(".", "::", 1) for name in variables]
    values = np.empty((n_steps + 1, len(variables)))
    values[0] = [simulation.get_real(i) for i in identifiers]
    for k in range(1, n_steps + 1):
        simulation.step()
        values[k] = [simulation.get_real(i) for i in identifiers]
    simulation.terminate()
    simulation.free()
    return values
