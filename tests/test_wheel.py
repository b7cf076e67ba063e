"""shapefmu installed from its wheel, used from an empty folder, does what it does in the repository.

The wheel is built from this checkout and installed without dependencies into a new virtual
environment; the dependencies come from the test environment's site-packages through a .pth line
(whose own .pth files, the editable install of this checkout among them, Python does not run), so
the shapefmu imported there is the wheel's. Then, in an empty folder, ``shapefmu build``, ``plant
show disk_drive`` and ``compare disk_drive`` must work and print what they print from the checkout.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import sysconfig
import venv
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> Path:
    """The python of a new venv holding shapefmu from a wheel of this checkout."""
    folder = tmp_path_factory.mktemp("wheel")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet",
                    "-w", str(folder / "dist"), str(ROOT)], check=True, capture_output=True, text=True)
    wheel = next((folder / "dist").glob("shapefmu-*.whl"))
    venv.create(folder / "venv", with_pip=False)
    python = folder / "venv" / "bin" / "python"
    site = Path(subprocess.run([python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               check=True, capture_output=True, text=True).stdout.strip())
    (site / "test_dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    subprocess.run([python, "-m", "pip", "install", "--no-deps", "--quiet", str(wheel)], check=True,
                   capture_output=True, text=True, env={**os.environ, "PIP_NO_INDEX": "1"})
    return python


def shapefmu(python, *arguments, cwd) -> str:
    environment = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    done = subprocess.run([python, "-m", "shapefmu", *arguments], cwd=cwd, capture_output=True, text=True,
                          env=environment, timeout=600)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_the_wheel_carries_the_papers_models_and_runs_its_own_code(installed, tmp_path):
    where = subprocess.run([installed, "-c", "import shapefmu, shapefmu.plants.shipped as s; "
                            "print(shapefmu.__file__); print(s.models_folder())"],
                           cwd=tmp_path, check=True, capture_output=True, text=True).stdout.split()
    assert str(ROOT) not in where[0] and "site-packages" in where[0]
    assert where[1].endswith("shapefmu/plants/models")
    def models(folder):
        return sorted(p.name for p in Path(folder).iterdir() if p.suffix in (".toml", ".py", ".ssd"))

    assert models(where[1]) == models(ROOT / "models") and len(models(where[1])) == 10
    listing = shapefmu(installed, "plant", "list", cwd=tmp_path)
    assert "disk_drive " in listing and "ten_pendula " in listing and "disk_drive_shaped " in listing


def test_build_plant_show_and_compare_from_an_empty_folder_print_what_the_checkout_prints(installed, tmp_path):
    here, there = tmp_path / "checkout", tmp_path / "empty"
    here.mkdir()
    there.mkdir()
    for folder, python in ((here, sys.executable), (there, installed)):
        built = shapefmu(python, "build", cwd=folder)
        assert len(re.findall(r"^built fmus/\w+\.fmu$", built, re.M)) == 14, built
    assert sorted(p.name for p in (there / "fmus").iterdir()) == sorted(p.name for p in (here / "fmus").iterdir())
    for arguments in (("plant", "show", "disk_drive"), ("compare", "disk_drive", "--distance", "0.05")):
        assert shapefmu(installed, *arguments, cwd=there) == shapefmu(sys.executable, *arguments, cwd=here)
