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

# The empty model part: u in, y out, a step that does nothing (every hook of fmi2_model.h, minimal).
EMPTY_MODEL = r"""#include <string.h>
#include "fmi2_model.h"

static const char *const names[] = {"u", "y"};
void model_describe(Fmi2ModelInfo *info) { memset(info, 0, sizeof *info); info->guid = "%GUID%"; info->n_real = 2; }
int model_instantiate(Fmi2Instance *inst) { model_reset(inst); return 0; }
void model_free(Fmi2Instance *inst) { (void)inst; }
void model_reset(Fmi2Instance *inst) { inst->reals[0] = inst->reals[1] = 0.0; }
Fmi2Role model_variable(const Fmi2Instance *inst, Fmi2Type type, size_t vr, const char **name) {
    (void)inst;
    if (type != FMI2_REAL || vr > 1) return FMI2_NO_VARIABLE;
    *name = names[vr];
    return vr == 0 ? FMI2_INPUT : FMI2_COMPUTED;
}
fmi2Status model_check_real(Fmi2Instance *inst, size_t vr, double value, const char *f) { (void)inst; (void)vr; (void)value; (void)f; return fmi2OK; }
fmi2Status model_check_integer(Fmi2Instance *inst, size_t vr, int value, const char *f) { (void)vr; (void)value; return fmi2_fail(inst, "%s: no Integer", f); }
fmi2Status model_check_string(Fmi2Instance *inst, size_t vr, const char *value, const char *f) { (void)vr; (void)value; return fmi2_fail(inst, "%s: no String", f); }
void model_changed(Fmi2Instance *inst, size_t vr) { (void)inst; (void)vr; }
fmi2Status model_update(Fmi2Instance *inst, const char *f) { (void)inst; (void)f; return fmi2OK; }
fmi2Status model_exit_initialization(Fmi2Instance *inst) { (void)inst; return fmi2OK; }
fmi2Status model_do_step(Fmi2Instance *inst, double t, double h) { (void)inst; (void)t; (void)h; return fmi2OK; }
size_t model_state_size(const Fmi2Instance *inst) { (void)inst; return 0; }
void model_save_state(const Fmi2Instance *inst, unsigned char *bytes) { (void)inst; (void)bytes; }
int model_restore_state(Fmi2Instance *inst, const unsigned char *bytes, size_t size) { (void)inst; (void)bytes; return size ? -1 : 0; }
void model_states_changed(Fmi2Instance *inst) { (void)inst; }
fmi2Status model_partial_derivative(Fmi2Instance *inst, size_t u, size_t k, double *e, const char *f) { (void)u; (void)k; (void)e; return fmi2_fail(inst, "%s: none", f); }
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
