"""valgrind memcheck on a C host that drives native Shaper and ShapeFilter FMUs through full runs.

The driver is compiled with the FMU's own sources and -g, and finds its variables by name in the
generated table (sampled_model.h): a closed-form re-design in C, initialisation, steps of every
kind (whole samples, off the grid, 1e-16 s, several samples), impulses tuned between steps, FMU
state get/serialise/deserialise/set, refused calls (a bad parameter, a step over too many samples,
a call out of order) with reset, and a second initialisation.
"""

import shutil
import pytest
from test_plantgen_valgrind import run_driver_under_valgrind

DRIVER = r"""
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "fmi2Functions.h"
#include "sampled_model.h"

static int errors_logged = 0;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env; (void)name; (void)category; (void)message;
    if (status == fmi2Error) errors_logged++;
}

static fmi2ValueReference vr_of(const char *name) {
    for (size_t vr = 0; vr < sampled_model.variables.n_real + sampled_model.variables.n_integer + sampled_model.variables.n_boolean
                             + sampled_model.variables.n_string; vr++)
        if (strcmp(sampled_model.variables.rows[vr].name, name) == 0) return (fmi2ValueReference)vr;
    fprintf(stderr, "no variable %s\n", name);
    exit(1);
}

#define CHECK(call) do { if ((call) != fmi2OK) { fprintf(stderr, "failed: %s\n", #call); return 1; } } while (0)
#define REFUSED(call) do { int before = errors_logged; \
    if ((call) != fmi2Error || errors_logged != before + 1) { fprintf(stderr, "not refused: %s\n", #call); return 1; } \
    } while (0)

static int run(fmi2Component c, fmi2ValueReference u, fmi2ValueReference y, double *t, int steps, double *out) {
    static const double sizes[] = {1e-3, 2.5e-4, 1e-16, 3e-3, 7.3e-4, 1e-3};
    for (int k = 0; k < steps; k++) {
        const double value = (double)((k * 31) % 17) - 8.0, h = sizes[k % 6];
        CHECK(fmi2SetReal(c, &u, 1, &value));
        CHECK(fmi2DoStep(c, *t, h, fmi2True));
        *t += h;
        CHECK(fmi2GetReal(c, &y, 1, out));
    }
    return 0;
}

int main(void) {
    const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    const fmi2ValueReference u = vr_of("u"), y = vr_of("y");
    double out = 0.0, t = 0.0, value;
    fmi2Component c = fmi2Instantiate("c", fmi2CoSimulation, sampled_model.variables.guid, "", &callbacks, fmi2False, fmi2True);
    if (c == NULL) return 1;
    REFUSED(fmi2DoStep(c, 0.0, 1e-3, fmi2True));                     /* before initialisation */
    CHECK(fmi2Reset(c));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    if (sampled_model.impulses) {
        const fmi2ValueReference f1 = vr_of("f[1]"), kind = vr_of("kind");
        const fmi2String mzv = "mzv";
        value = 11.0;
        CHECK(fmi2SetReal(c, &f1, 1, &value));
        CHECK(fmi2SetString(c, &kind, 1, &mzv));
    }
    CHECK(fmi2ExitInitializationMode(c));
    if (run(c, u, y, &t, 150, &out)) return 1;
    fmi2FMUstate state = NULL;
    CHECK(fmi2GetFMUstate(c, &state));
    if (sampled_model.impulses) {
        const fmi2ValueReference a1 = vr_of("impulse_amplitude[1]");
        value = 0.5;
        CHECK(fmi2SetReal(c, &a1, 1, &value));                         /* tuned between steps */
    }
    if (run(c, u, y, &t, 150, &out)) return 1;
    size_t size = 0;
    CHECK(fmi2SerializedFMUstateSize(c, state, &size));
    fmi2Byte *bytes = malloc(size);
    CHECK(fmi2SerializeFMUstate(c, state, bytes, size));
    fmi2FMUstate copy = NULL;
    CHECK(fmi2DeSerializeFMUstate(c, bytes, size, &copy));
    REFUSED(fmi2DeSerializeFMUstate(c, bytes, size - 1, &copy));        /* truncated */
    free(bytes);
    CHECK(fmi2SetFMUstate(c, copy));
    CHECK(fmi2FreeFMUstate(c, &copy));
    CHECK(fmi2FreeFMUstate(c, &state));
    REFUSED(fmi2DoStep(c, t, 2e7, fmi2True));                          /* too many samples */
    CHECK(fmi2Reset(c));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.5, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    const fmi2ValueReference rest = vr_of("u0");
    value = 1.0 / 0.0;
    REFUSED(fmi2SetReal(c, &rest, 1, &value));                         /* not finite */
    CHECK(fmi2Reset(c));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.5, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    CHECK(fmi2ExitInitializationMode(c));
    t = 0.5;
    if (run(c, u, y, &t, 100, &out)) return 1;
    CHECK(fmi2Terminate(c));
    fmi2FreeInstance(c);
    printf("ok %g\n", out);
    return 0;
}
"""


@pytest.mark.skipif(shutil.which("valgrind") is None or shutil.which("gcc") is None, reason="needs valgrind and gcc")
@pytest.mark.parametrize("which", ["shaper", "filter"])
def test_valgrind_finds_no_invalid_access_and_no_leak(native_shapers, native_filters, tmp_path, which):
    fmu = native_shapers[("zv_dn", 2)][0] if which == "shaper" else native_filters["hanning2"][0]
    run_driver_under_valgrind(fmu, DRIVER, tmp_path)
