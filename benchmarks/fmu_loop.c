/* The limit no master can beat: a hand-written C loop calling FMUs' FMI functions directly.
 * Compiled and run by benchmarks/native_loop.py for benchmarks/fmu_step.py and benchmarks/cosim.py.
 *
 * Usage: fmu_loop STEPS H FACTOR LIB GUID IN OUT [LIB2 GUID2 IN2 OUT2]
 *   one FMU:  per step set IN = sin-like command (IN "-": an FMU without inputs), doStep, get OUT
 *   two FMUs: FMU 1's IN held at 1 (a step command); per step set FMU 2's IN2 = FACTOR * (FMU 1's
 *             OUT read after the last step), doStep both, get OUT; every 100th step also get FMU 2's
 *             OUT2 (what a master records)
 * Prints the seconds the loop took (clock_gettime, monotonic), then the last output read.
 */
#define _POSIX_C_SOURCE 199309L
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "fmi2Functions.h"

typedef struct {
    fmi2Component c;
    fmi2SetRealTYPE *set;
    fmi2GetRealTYPE *get;
    fmi2DoStepTYPE *step;
    fmi2FreeInstanceTYPE *free_instance;
    fmi2ValueReference in, out;
    int has_input;
} Fmu;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env; (void)category;
    fprintf(stderr, "[%s %d] %s\n", name, (int)status, message);
}

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

static int open_fmu(Fmu *fmu, char **argv) {
    void *library = dlopen(argv[0], RTLD_NOW | RTLD_LOCAL);
    if (library == NULL) return fprintf(stderr, "%s\n", dlerror()), -1;
    fmi2InstantiateTYPE *instantiate = (fmi2InstantiateTYPE *)dlsym(library, "fmi2Instantiate");
    fmi2SetupExperimentTYPE *setup = (fmi2SetupExperimentTYPE *)dlsym(library, "fmi2SetupExperiment");
    fmi2EnterInitializationModeTYPE *enter = (fmi2EnterInitializationModeTYPE *)dlsym(library, "fmi2EnterInitializationMode");
    fmi2ExitInitializationModeTYPE *exit_ = (fmi2ExitInitializationModeTYPE *)dlsym(library, "fmi2ExitInitializationMode");
    fmu->set = (fmi2SetRealTYPE *)dlsym(library, "fmi2SetReal");
    fmu->get = (fmi2GetRealTYPE *)dlsym(library, "fmi2GetReal");
    fmu->step = (fmi2DoStepTYPE *)dlsym(library, "fmi2DoStep");
    fmu->free_instance = (fmi2FreeInstanceTYPE *)dlsym(library, "fmi2FreeInstance");
    fmu->has_input = argv[2][0] != '-';
    fmu->in = (fmi2ValueReference)atol(argv[2]);
    fmu->out = (fmi2ValueReference)atol(argv[3]);
    fmu->c = instantiate("loop", fmi2CoSimulation, argv[1], "", &callbacks, fmi2False, fmi2False);
    if (fmu->c == NULL || setup(fmu->c, fmi2False, 0.0, 0.0, fmi2False, 0.0) > fmi2Warning
        || enter(fmu->c) > fmi2Warning || exit_(fmu->c) > fmi2Warning)
        return fprintf(stderr, "could not initialise %s\n", argv[0]), -1;
    return 0;
}

static double seconds(void) {
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
}

#define CALL(x) if ((x) > fmi2Warning) { fprintf(stderr, "failed at step %ld: %s\n", k, #x); return 1; }

int main(int argc, char **argv) {
    if (argc != 8 && argc != 12) {
        fprintf(stderr, "usage: %s STEPS H FACTOR LIB GUID IN OUT [LIB2 GUID2 IN2 OUT2]\n", argv[0]);
        return 2;
    }
    const long steps = atol(argv[1]);
    const double h = atof(argv[2]), factor = atof(argv[3]);
    Fmu a, b;
    if (open_fmu(&a, argv + 4) != 0 || (argc == 12 && open_fmu(&b, argv + 8) != 0)) return 1;
    double y = 0.0, recorded = 0.0;
    long k = 0;
    const double start = seconds();
    if (argc == 8) {
        for (k = 0; k < steps; k++) {
            const double u = (double)((k * 7919) % 200) / 100.0 - 1.0;
            if (a.has_input) CALL(a.set(a.c, &a.in, 1, &u));
            CALL(a.step(a.c, (double)k * h, h, fmi2True));
            CALL(a.get(a.c, &a.out, 1, &y));
        }
    } else {
        const double command = 1.0;
        CALL(a.set(a.c, &a.in, 1, &command));
        CALL(a.get(a.c, &a.out, 1, &y));
        for (k = 0; k < steps; k++) {
            const double t = (double)k * h, u = factor * y;
            CALL(b.set(b.c, &b.in, 1, &u));
            CALL(a.step(a.c, t, h, fmi2True));
            CALL(b.step(b.c, t, h, fmi2True));
            CALL(a.get(a.c, &a.out, 1, &y));
            if (k % 100 == 99) CALL(b.get(b.c, &b.out, 1, &recorded));
        }
    }
    const double elapsed = seconds() - start;
    printf("%.9f %.17g\n", elapsed, argc == 8 ? y : recorded);
    a.free_instance(a.c);
    if (argc == 12) b.free_instance(b.c);
    return 0;
}
