"""valgrind memcheck on C drivers (tests/hosts_c/valgrind_*.c) compiled with a native FMU's own
sources (-g): no invalid access, no leak, every call answering as it should (the driver prints "ok").

- Generated plants, FMI 2.0 and FMI 3.0 (valgrind_plant.c, valgrind_plant3.c): instantiation, a
  parameter change, initialisation, Co-Simulation steps of varying size, the FMU state's round trip,
  refused calls (a NaN input, a negative step, a variable of another type, calls out of order) with
  reset, and a Model Exchange instance with derivatives and a directional derivative; a linear plant
  and the nonlinear pendulum.
- Native Shaper and ShapeFilter FMUs (valgrind_sampled.c): a closed-form re-design in C, steps of
  every kind (whole samples, off the grid, 1e-16 s, several samples), impulses tuned between steps,
  the FMU state's round trip, refused calls with reset, and a second initialisation.

The twins' drivers run in the twin contract (tests/test_native_twin_contract.py).
"""

import pytest

from support import MODELS
from support.valgrind import requires_valgrind, run_driver_under_valgrind

pytestmark = [pytest.mark.foreign, requires_valgrind]


@pytest.mark.parametrize("name", ["disk_drive", "pendulum"])
def test_a_plant_leaks_nothing_and_touches_no_invalid_memory(plant_fmus, tmp_path, name):
    run_driver_under_valgrind(plant_fmus[name], "valgrind_plant", tmp_path)


@pytest.mark.parametrize("model", ["disk_drive.toml", "pendulum.py"])
def test_an_fmi3_plant_leaks_nothing_and_touches_no_invalid_memory(builds, tmp_path, model):
    run_driver_under_valgrind(builds.plant(MODELS / model, fmi_version="3.0"), "valgrind_plant3", tmp_path)


@pytest.mark.parametrize("which", ["shaper", "filter"])
def test_a_native_shaper_or_filter_leaks_nothing_and_touches_no_invalid_memory(native_shapers, native_filters,
                                                                                tmp_path, which):
    fmu = native_shapers[("zv_dn", 2)][0] if which == "shaper" else native_filters["hanning2"][0]
    run_driver_under_valgrind(fmu, "valgrind_sampled", tmp_path)
