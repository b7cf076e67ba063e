"""The FMU builder and ``shapefmu build``: every FMU validates; bad designs fail the build."""

import zipfile

import numpy as np
import pytest
from fmpy.validation import validate_fmu

from support.fixtures_fmi import SHAPER_STARTS
from support.hosts import run_ecos_program, run_fmpy, y_of_u

from shapefmu.cli import main
from shapefmu.fmi import build_fmu
from shapefmu.fmi.python.builder import bundled_sources, package_name
from shapefmu.fmi.kinds import KINDS as SLAVES

def test_every_registered_fmu_builds_and_validates(all_fmus):
    assert sorted(p.stem for p in all_fmus) == sorted(SLAVES)
    for path in all_fmus:
        assert validate_fmu(str(path)) == [], path


def test_cli_builds_the_disk_drive_shaper(tmp_path):
    out = tmp_path / "DiskDriveShaper.fmu"
    assert main(["build", "shaper", "--kind", "simultaneous", "--mode", "2000:0.01", "--mode", "3000:0.01", "-o", str(out)]) == 0
    assert validate_fmu(str(out)) == []
    baked = zipfile.ZipFile(out).read("resources/shapefmu_build.json").decode()
    assert '"kind": "simultaneous"' in baked and '"f[2]": 3000.0' in baked


def test_a_bad_start_value_fails_the_build_naming_it(tmp_path):
    with pytest.raises(ValueError, match=r"zeta\[1\] must be in \[0, 1\), got 1.0"):
        build_fmu("Shaper", tmp_path / "x.fmu", **{"zeta[1]": 1.0})
    with pytest.raises(ValueError, match="has no parameter or input 'omega'"):
        build_fmu("Shaper", tmp_path / "x.fmu", omega=3.0)
    assert not (tmp_path / "x.fmu").exists()


def test_the_bundled_package_name_follows_the_sources():
    files = bundled_sources("Shaper")
    changed = dict(files, **{"runtime/checks.py": files["runtime/checks.py"] + b"\n"})
    assert package_name(files) == package_name(dict(files)) != package_name(changed)


def test_runs_in_the_ecos_command_line_host_without_python_or_ld_preload(shaper_fmu, tmp_path):
    y = run_ecos_program(shaper_fmu, step=0.001, stop_time=0.12, workdir=tmp_path)["instance::y[REAL]"]
    # Same FMU in fmpy, u at its start value 0 from rest at u0 = -1: ecos writes 6 decimals.
    reference = [-0.5 * 1.0] + y_of_u(run_fmpy, shaper_fmu, [0.0] * (y.size - 1), 1e-3)
    assert SHAPER_STARTS["u0"] == -1.0  # the rest value the reference's first sample assumes
    np.testing.assert_allclose(y, reference, rtol=0, atol=5e-7)
