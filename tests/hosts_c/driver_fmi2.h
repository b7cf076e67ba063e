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

/* What a driver of a sampled twin with two inputs and two outputs runs (run_steps, two_by_two_run). */
typedef struct {
    const char *in[2], *out[2];
    void (*inputs)(double t, double values[2]);  /* the inputs at t */
    int read_before;                              /* outputs also read before each step (feed-through) */
} TwoByTwo;

/* Steps of 1 ms, 0.25 ms, 1e-16 s, 3 ms, 0.75 ms and 1 ms in turn from *t, the inputs set before each
 * and the outputs read into out after it. */
static int run_steps(fmi2Component c, const TwoByTwo *plan, double *t, int steps, double *out) {
    static const double sizes[] = {1e-3, 2.5e-4, 1e-16, 3e-3, 7.5e-4, 1e-3};
    const fmi2ValueReference in[2] = {vr_of(plan->in[0]), vr_of(plan->in[1])};
    const fmi2ValueReference y[2] = {vr_of(plan->out[0]), vr_of(plan->out[1])};
    for (int k = 0; k < steps; k++) {
        double values[2];
        plan->inputs(*t, values);
        CHECK(fmi2SetReal(c, in, 2, values));
        if (plan->read_before) CHECK(fmi2GetReal(c, y, 2, out));
        CHECK(fmi2DoStep(c, *t, sizes[k % 6], fmi2True));
        *t += sizes[k % 6];
        CHECK(fmi2GetReal(c, y, 2, out));
    }
    return 0;
}

/* The initialised instance c through a driver's run: `first` steps of run_steps, its FMU state taken,
 * `second` steps more, check(out) (0: it did what it should), the state's serialised round trip,
 * refuse_then_restart with the Real `refused`, `last` steps from t = 0.5, fmi2Terminate and
 * fmi2FreeInstance; prints "ok" and the outputs. */
static int two_by_two_run(fmi2Component c, const TwoByTwo *plan, int first, int second, int (*check)(const double *out),
                          const char *refused, int last) {
    double out[2] = {0.0, 0.0}, t = 0.0;
    if (run_steps(c, plan, &t, first, out)) return 1;
    fmi2FMUstate state = NULL;
    CHECK(fmi2GetFMUstate(c, &state));
    if (run_steps(c, plan, &t, second, out) || check(out)) return 1;
    if (restore_serialised(c, &state)) return 1;
    if (refuse_then_restart(c, t, 2e7, vr_of(refused))) return 1;
    t = 0.5;
    if (run_steps(c, plan, &t, last, out)) return 1;
    CHECK(fmi2Terminate(c));
    fmi2FreeInstance(c);
    printf("ok %g %g\n", out[0], out[1]);
    return 0;
}

#endif
