"""valgrind memcheck on a C host that drives a plant FMU's sources through a full ME and CS run.

The driver is compiled with the FMU's own sources (wrapper, expm, generated model part) and -g, and
uses only the FMI 2.0 API plus plant_model.h for the sizes and the value-reference layout, so it
runs any generated plant: instantiation, a parameter change, initialisation, Co-Simulation steps of
varying size, FMU state get/serialise/deserialise/set, refused calls (NaN input, negative step,
call out of order) with reset, and a Model Exchange instance with derivatives and directional
derivatives.
"""

import shutil
import subprocess
import zipfile

import pytest

from shapefmu.fmi.native.compile import standard_headers

DRIVER = r"""
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "fmi2Functions.h"
#include "plant_model.h"

static int errors_logged = 0;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env; (void)name; (void)category;
    va_list args;
    va_start(args, message);
    char text[1024];
    vsnprintf(text, sizeof text, message, args);
    va_end(args);
    if (status == fmi2Error) errors_logged++;
}

#define CHECK(call) do { if ((call) != fmi2OK) { fprintf(stderr, "failed: %s\n", #call); return 1; } } while (0)
#define REFUSED(call) do { int before = errors_logged; \
    if ((call) != fmi2Error || errors_logged != before + 1) { fprintf(stderr, "not refused: %s\n", #call); return 1; } \
    } while (0)

int main(void) {
    const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    const int nx = plant_model.n_states, nu = plant_model.n_inputs, ny = plant_model.n_outputs;
    const fmi2ValueReference input = 1 + 2 * nx, output = 1 + 2 * nx + nu, parameter = 1 + 2 * nx + nu + ny;
    double y = 0.0, u, p;

    fmi2Component cs = fmi2Instantiate("cs", fmi2CoSimulation, plant_model.guid, "", &callbacks, fmi2False, fmi2True);
    if (cs == NULL) return 1;
    REFUSED(fmi2DoStep(cs, 0.0, 1e-3, fmi2True));               /* before initialisation */
    CHECK(fmi2Reset(cs));
    CHECK(fmi2SetupExperiment(cs, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    p = plant_model.parameters[0].start * 1.01;
    CHECK(fmi2SetReal(cs, &parameter, 1, &p));
    CHECK(fmi2EnterInitializationMode(cs));
    CHECK(fmi2ExitInitializationMode(cs));
    double t = 0.0;
    fmi2FMUstate state = NULL;
    for (int k = 0; k < 200; k++) {
        const double h = (k % 3 == 0 ? 2e-4 : 1e-4);
        u = sin(0.1 * k);
        CHECK(fmi2SetReal(cs, &input, 1, &u));
        CHECK(fmi2DoStep(cs, t, h, fmi2True));
        t += h;
        CHECK(fmi2GetReal(cs, &output, 1, &y));
        if (k == 100) CHECK(fmi2GetFMUstate(cs, &state));
    }
    size_t size = 0;
    CHECK(fmi2SerializedFMUstateSize(cs, state, &size));
    fmi2Byte *bytes = malloc(size);
    CHECK(fmi2SerializeFMUstate(cs, state, bytes, size));
    fmi2FMUstate copy = NULL;
    CHECK(fmi2DeSerializeFMUstate(cs, bytes, size, &copy));
    REFUSED(fmi2DeSerializeFMUstate(cs, bytes, size - 1, &copy)); /* truncated */
    free(bytes);
    CHECK(fmi2SetFMUstate(cs, copy));
    CHECK(fmi2FreeFMUstate(cs, &copy));
    CHECK(fmi2FreeFMUstate(cs, &state));
    u = NAN;
    REFUSED(fmi2SetReal(cs, &input, 1, &u));
    CHECK(fmi2Reset(cs));
    CHECK(fmi2SetupExperiment(cs, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(cs));
    CHECK(fmi2ExitInitializationMode(cs));
    REFUSED(fmi2DoStep(cs, 0.0, -1e-3, fmi2True));
    CHECK(fmi2Reset(cs));
    CHECK(fmi2EnterInitializationMode(cs));
    CHECK(fmi2ExitInitializationMode(cs));
    CHECK(fmi2DoStep(cs, 0.0, 1e-3, fmi2True));
    CHECK(fmi2Terminate(cs));
    REFUSED(fmi2DoStep(cs, 1e-3, 1e-3, fmi2True));               /* after termination */
    fmi2FreeInstance(cs);

    fmi2Component me = fmi2Instantiate("me", fmi2ModelExchange, plant_model.guid, "", &callbacks, fmi2False, fmi2False);
    if (me == NULL) return 1;
    CHECK(fmi2SetupExperiment(me, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(me));
    CHECK(fmi2ExitInitializationMode(me));
    fmi2EventInfo info;
    CHECK(fmi2NewDiscreteStates(me, &info));
    CHECK(fmi2EnterContinuousTimeMode(me));
    double *x = calloc((size_t)nx, sizeof(double)), *dx = calloc((size_t)nx, sizeof(double));
    for (int i = 0; i < nx; i++) x[i] = 0.1 * (i + 1);
    CHECK(fmi2SetTime(me, 0.5));
    CHECK(fmi2SetContinuousStates(me, x, (size_t)nx));
    CHECK(fmi2GetDerivatives(me, dx, (size_t)nx));
    CHECK(fmi2GetNominalsOfContinuousStates(me, x, (size_t)nx));
    const fmi2ValueReference unknown = 1 + nx, known = 1;
    const double seed = 1.0;
    double derivative;
    CHECK(fmi2GetDirectionalDerivative(me, &unknown, 1, &known, 1, &seed, &derivative));
    fmi2Boolean enter, terminate;
    CHECK(fmi2CompletedIntegratorStep(me, fmi2True, &enter, &terminate));
    REFUSED(fmi2SetReal(me, &parameter, 1, &p));                 /* not in Continuous-Time Mode */
    CHECK(fmi2Reset(me));
    free(x);
    free(dx);
    fmi2FreeInstance(me);
    printf("ok %g %g\n", y, derivative);
    return 0;
}
"""


@pytest.mark.skipif(shutil.which("valgrind") is None or shutil.which("gcc") is None, reason="needs valgrind and gcc")
@pytest.mark.parametrize("name", ["disk_drive", "pendulum"])
def test_valgrind_finds_no_invalid_access_and_no_leak(plant_fmus, tmp_path, name):
    run_driver_under_valgrind(plant_fmus[name], DRIVER, tmp_path)


def run_driver_under_valgrind(fmu, driver: str, tmp_path) -> None:
    """Compile ``driver`` with the FMU's sources and run it under memcheck: no error, no leak."""
    with zipfile.ZipFile(fmu) as archive:
        archive.extractall(tmp_path)
    sources = tmp_path / "sources"
    (tmp_path / "driver.c").write_text(driver)
    program = tmp_path / "driver"
    # sources/ leaves the FMI standard's headers out: a tool compiles with its own copy
    include = standard_headers(tmp_path / "fmi-headers")
    subprocess.run(["gcc", "-g", "-O1", "-std=c99", "-I", str(sources), "-I", str(include), str(tmp_path / "driver.c"),
                    *map(str, sorted(sources.glob("*.c"))), "-o", str(program), "-lm"], check=True)
    completed = subprocess.run(
        ["valgrind", "--tool=memcheck", "--leak-check=full", "--show-leak-kinds=definite,indirect,possible",
         "--errors-for-leak-kinds=definite,indirect,possible", "--error-exitcode=99", str(program)],
        capture_output=True, text=True, timeout=120)
    assert completed.returncode == 0, completed.stderr[-3000:] + completed.stdout
    assert completed.stdout.startswith("ok ")
    assert "ERROR SUMMARY: 0 errors" in completed.stderr
