"""Build step: the papers' plant models and SSP systems, the top-level models/ folder of the
repository, ship inside the package as shapefmu/plants/models, where shapefmu.plants.shipped finds
them by name. Everything else about the package is in pyproject.toml."""

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

SHIPPED = ("*.toml", "*.py", "*.ssd")


class BuildWithModels(build_py):
    def run(self):
        super().run()
        if self.editable_mode:  # an editable install reads the checkout's models/ itself
            return
        target = Path(self.build_lib, "shapefmu", "plants", "models")
        target.mkdir(parents=True, exist_ok=True)
        for pattern in SHIPPED:
            for file in sorted(Path(__file__).parent.joinpath("models").glob(pattern)):
                shutil.copy2(file, target / file.name)


setup(cmdclass={"build_py": BuildWithModels})
