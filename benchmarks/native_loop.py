"""Benchmark helpers for native FMUs: the hand-written C loop (benchmarks/fmu_loop.c) and an empty
native FMU (the generic FMI 2.0 layer with a model part that does nothing), the floor of a native
FMU's step.

    c_loop_seconds(steps, h, [fmu1] or [fmu1, fmu2], factor=1.0) -> seconds of the C loop
    build_empty_native(path) -> Path
"""

from __future__ import annotations

import subprocess
import tempfile
import zipfile
from pathlib import Path

from fmpy import read_model_description

from shapefmu.fmi.native.compile import LAYER_HEADERS, LAYER_SOURCES, build_binaries, build_description, copy_c_files, zip_fmu
from shapefmu.fmi.description import ModelDescription, fmi2
from shapefmu.fmi.kinds.interface import input_, output

HERE = Path(__file__).parent
HEADERS = HERE.parent / "src" / "shapefmu" / "fmi" / "native" / "c"
GUID = "{00000000-0000-0000-0000-00000000e0f7}"

# The empty model part: u in, y out, a step that does nothing (model.h: the hooks it cannot do without;
# the layer's defaults for the rest).
EMPTY_MODEL = r"""#include <stddef.h>
#include "model.h"

static const VariableRow rows[] = {{"u", ROLE_INPUT, 0, 0.0, NULL}, {"y", ROLE_COMPUTED, 0, 0.0, NULL}};
static const VariableTable variables = {"%GUID%", 2, 0, 0, 0, rows};

static ModelStatus do_step(ModelInstance *inst, double t, double h, const char *f) {
    (void)inst, (void)t, (void)h, (void)f;
    return MODEL_OK;
}

const ModelPart model_part = {.variables = &variables, .do_step = do_step};
"""


def build_empty_native(path: Path) -> Path:
    """An FMU of the generic layer and the empty model part (y stays 0)."""
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        sources = root / "sources"
        sources.mkdir()
        copy_c_files(sources, LAYER_SOURCES + LAYER_HEADERS)
        (sources / "model.c").write_text(EMPTY_MODEL.replace("%GUID%", GUID))
        c_files = [*LAYER_SOURCES, "model.c"]
        (sources / "buildDescription.xml").write_text(build_description("Empty", c_files))
        build_binaries(root, "Empty", c_files, "empty native")
        description = ModelDescription(
            model_name="Empty", identifier="Empty", guid=GUID, description="empty native FMU: the generic layer alone",
            generation_tool="shapefmu benchmarks/native_loop.py",
            variables=(input_("u", 0.0, "input"), output("y", "output, always 0")), dependencies={"y": []},
            log_categories=(("logStatusError", "errors"), ("logAll", "debug")), experiment=(0.0, 1.0, 1e-3),
            source_files=tuple(c_files))
        (root / "modelDescription.xml").write_text(fmi2.write(description))
        return zip_fmu(root, Path(path))


_PROGRAM: dict[str, Path] = {}


def _program() -> Path:
    if "loop" not in _PROGRAM:
        folder = Path(tempfile.mkdtemp(prefix="shapefmu-loop-"))
        program = folder / "fmu_loop"
        subprocess.run(["gcc", "-O2", "-std=c99", "-I", str(HEADERS), str(HERE / "fmu_loop.c"), "-o", str(program),
                        "-ldl"], check=True)
        _PROGRAM["loop"] = program
    return _PROGRAM["loop"]


def _arguments(fmu: Path, input_name: str | None, output_name: str) -> list[str]:
    md = read_model_description(str(fmu))
    folder = Path(tempfile.mkdtemp(prefix="shapefmu-loop-fmu-"))
    zipfile.ZipFile(fmu).extractall(folder)
    library = folder / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    vr = {v.name: v.valueReference for v in md.modelVariables}
    return [str(library), md.guid, "-" if input_name is None else str(vr[input_name]), str(vr[output_name])]


def c_loop_seconds(steps: int, h: float, fmus: list[tuple[Path, str, str]], factor: float = 1.0) -> float:
    """Seconds of fmu_loop.c over ``fmus`` [(path, input or None, output)], one FMU or a chain of two."""
    arguments = [a for fmu in fmus for a in _arguments(*fmu)]
    completed = subprocess.run([str(_program()), str(steps), repr(h), repr(factor), *arguments],
                               capture_output=True, text=True, check=True)
    return float(completed.stdout.split()[0])


if __name__ == "__main__":  # `make bench` runs every script here: this one is a helper of two others
    print("helper of fmu_step.py and cosim.py (the hand-written C loop and the empty native FMU); nothing to run")
