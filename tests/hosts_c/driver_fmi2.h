/* What the FMI 2.0 valgrind drivers share (driver.h, plus): a logger that formats every message, as a
 * host does (so memcheck sees the FMU's format and arguments), and counts the errors; the callback
 * functions of an instance; the FMU state's serialised round trip. */
#ifndef DRIVER_FMI2_H
#define DRIVER_FMI2_H

#include <stdarg.h>

#include "fmi2Functions.h"
#include "driver.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env; (void)name; (void)category;
    char text[1024];
    va_list args;
    va_start(args, message);
    vsnprintf(text, sizeof text, message, args);
    va_end(args);
    if (status == fmi2Error) errors_logged++;
}

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

/* A Co-Simulation instance "c" that refused a step before initialisation, was reset, and is now in
 * Initialization Mode from t0 = 0; NULL if any of that failed. */
static fmi2Component initialising(void) {
    fmi2Component c = fmi2Instantiate("c", fmi2CoSimulation, FMU_GUID, "", &callbacks, fmi2False, fmi2True);
    int before = errors_logged;
    if (c == NULL || fmi2DoStep(c, 0.0, 1e-3, fmi2True) != fmi2Error || errors_logged != before + 1
        || fmi2Reset(c) != fmi2OK || fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK
        || fmi2EnterInitializationMode(c) != fmi2OK) {
        fprintf(stderr, "instantiation, the refused early step, reset or initialisation failed\n");
        return NULL;
    }
    return c;
}

/* From t: a step of h over too many samples is refused; after a reset, an infinite value of the Real
 * `vr` is refused in initialisation; after another reset the instance is initialised from t0 = 0.5. */
static int refuse_then_restart(fmi2Component c, double t, double h, fmi2ValueReference vr) {
    const double infinite = 1.0 / 0.0;
    REFUSED(fmi2DoStep(c, t, h, fmi2True));                            /* too many samples */
    CHECK(fmi2Reset(c));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.5, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    REFUSED(fmi2SetReal(c, &vr, 1, &infinite));                        /* not finite */
    CHECK(fmi2Reset(c));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.5, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    CHECK(fmi2ExitInitializationMode(c));
    return 0;
}

/* Serialise *state, read the bytes back (a copy one byte short is refused), set the copy, and free
 * both states. */
static int restore_serialised(fmi2Component c, fmi2FMUstate *state) {
    size_t size = 0;
    CHECK(fmi2SerializedFMUstateSize(c, *state, &size));
    fmi2Byte *bytes = malloc(size);
    CHECK(fmi2SerializeFMUstate(c, *state, bytes, size));
    fmi2FMUstate copy = NULL;
    CHECK(fmi2DeSerializeFMUstate(c, bytes, size, &copy));
    REFUSED(fmi2DeSerializeFMUstate(c, bytes, size - 1, &copy));        /* truncated */
    free(bytes);
    CHECK(fmi2SetFMUstate(c, copy));
    CHECK(fmi2FreeFMUstate(c, &copy));
    CHECK(fmi2FreeFMUstate(c, state));
    return 0;
}

#endif
