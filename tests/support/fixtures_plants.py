"""Session-scoped fixtures for the plant FMUs (see conftest.py).

Every plant of models/ (the seven TOML plants and the nonlinear pendulum of models/pendulum.py) is
generated and compiled once per test session into a temporary directory.
"""

import pytest

from support import MODELS
# The linear plants of models/*.toml, by model name.
LINEAR_PLANTS = ("disk_drive", "disk_drive_back_emf", "linear_synchronous_motor", "ten_pendula", "mass_spring_chain",
                 "printer_bed", "gantry_crane")


@pytest.fixture(scope="session")
def plant_fmus(tmp_path_factory) -> dict:
    """{model name: FMU path} for every plant of models/, built by build_all."""
    from fmpy import read_model_description

    from shapefmu.fmi.native import build_all

    paths = build_all(MODELS, tmp_path_factory.mktemp("plant_fmus"))
    return {read_model_description(str(path)).modelName: path for path in paths}


@pytest.fixture(scope="session")
def quiet_libcosim():
    """libcosim logs every FMI call at its default level: keep the test output readable."""
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level

    log_output_level(CosimLogLevel.ERROR)
