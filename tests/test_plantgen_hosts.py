"""Every plant FMU of models/ gives the same outputs in three FMI hosts: fmpy, libcosim, ecos."""

import numpy as np
import pytest

from support.fixtures_plants import LINEAR_PLANTS
from support.hosts import HOSTS

# Per plant: (step, number of steps, start values set before initialisation, input amplitude).
CASES = {
    "disk_drive": (1e-5, 200, {"f[2]": 3.2e3}, 11.0),
    "disk_drive_back_emf": (1e-5, 200, {"R": 8.0}, 11.0),
    "linear_synchronous_motor": (1e-3, 200, {}, 1.0),
    "ten_pendula": (1e-2, 300, {"lengths[10]": 0.9}, 0.7),
    "mass_spring_chain": (5e-3, 200, {"masses[3]": 0.3}, 10.0),
    "printer_bed": (1e-3, 200, {"masses[1]": 1.3}, 1.0),
    "gantry_crane": (1e-2, 300, {"lengths[1]": 2.0}, 1.0),
    "pendulum": (1e-2, 200, {"state.theta": 1.0, "c": 0.1}, 3.0),
}


@pytest.mark.parametrize("name", [*LINEAR_PLANTS, "pendulum"])
def test_plant_fmu_outputs_are_identical_in_fmpy_libcosim_and_ecos(plant_fmus, quiet_libcosim, name):
    step, steps, start_values, amplitude = CASES[name]
    from fmpy import read_model_description

    input_name = next(v.name for v in read_model_description(str(plant_fmus[name])).modelVariables
                      if v.causality == "input")
    inputs = [{input_name: u} for u in amplitude * np.sign(np.sin(np.arange(steps) / 13.0))]
    runs = {host: np.array(run(plant_fmus[name], inputs, step, start_values=start_values)) for host, run in HOSTS.items()}
    reference = runs["fmpy"]
    scale = np.max(np.abs(reference), axis=0)
    assert np.all(scale > 0)
    for host in ("libcosim", "ecos"):
        assert runs[host].shape == reference.shape
        assert np.all(np.max(np.abs(runs[host] - reference), axis=0) <= 1e-12 * scale), host
