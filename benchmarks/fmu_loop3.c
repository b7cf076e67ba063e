/* fmu_loop.c's one-FMU loop over the FMI 3.0 API: a hand-written C loop calling an FMI 3.0 FMU's
 * functions directly. Compiled and run by benchmarks/fmi3_step.py, beside fmu_loop.c on the same FMU's
 * FMI 2.0 twin, with the same inputs.
 *
 * Usage: fmu_loop3 STEPS H LIB TOKEN IN OUT
 *   per step set IN = the sin-like command of fmu_loop.c (IN "-": an FMU without inputs), doStep, get OUT
 * Prints the seconds the loop took (clock_gettime, monotonic), then the last output read.
 */
#define _POSIX_C_SOURCE 199309L
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "fmi3FunctionTypes.h"

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env; (void)category;
    fprintf(stderr, "[%d] %s\n", (int)status, message);
}

static double seconds(void) {
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
}

#define CALL(x) if ((x) > fmi3Warning) { fprintf(stderr, "failed at step %ld: %s\n", k, #x); return 1; }

int main(int argc, char **argv) {
    if (argc != 7) {
        fprintf(stderr, "usage: %s STEPS H LIB TOKEN IN OUT\n", argv[0]);
        return 2;
    }
    const long steps = atol(argv[1]);
    const double h = atof(argv[2]);
    void *library = dlopen(argv[3], RTLD_NOW | RTLD_LOCAL);
    if (library == NULL) return fprintf(stderr, "%s\n", dlerror()), 1;
    fmi3InstantiateCoSimulationTYPE *instantiate = (fmi3InstantiateCoSimulationTYPE *)dlsym(library, "fmi3InstantiateCoSimulation");
    fmi3EnterInitializationModeTYPE *enter = (fmi3EnterInitializationModeTYPE *)dlsym(library, "fmi3EnterInitializationMode");
    fmi3ExitInitializationModeTYPE *exit_ = (fmi3ExitInitializationModeTYPE *)dlsym(library, "fmi3ExitInitializationMode");
    fmi3SetFloat64TYPE *set = (fmi3SetFloat64TYPE *)dlsym(library, "fmi3SetFloat64");
    fmi3GetFloat64TYPE *get = (fmi3GetFloat64TYPE *)dlsym(library, "fmi3GetFloat64");
    fmi3DoStepTYPE *step = (fmi3DoStepTYPE *)dlsym(library, "fmi3DoStep");
    fmi3FreeInstanceTYPE *free_instance = (fmi3FreeInstanceTYPE *)dlsym(library, "fmi3FreeInstance");
    const int has_input = argv[5][0] != '-';
    const fmi3ValueReference in = (fmi3ValueReference)atol(argv[5]), out = (fmi3ValueReference)atol(argv[6]);
    fmi3Instance c = instantiate("loop", argv[4], "", fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0, NULL, logger, NULL);
    long k = 0;
    if (c == NULL) return fprintf(stderr, "could not instantiate %s\n", argv[3]), 1;
    CALL(enter(c, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    CALL(exit_(c));
    double y = 0.0;
    fmi3Boolean event, terminate, early;
    fmi3Float64 last;
    const double start = seconds();
    for (k = 0; k < steps; k++) {
        const double u = (double)((k * 7919) % 200) / 100.0 - 1.0;
        if (has_input) CALL(set(c, &in, 1, &u, 1));
        CALL(step(c, (double)k * h, h, fmi3True, &event, &terminate, &early, &last));
        CALL(get(c, &out, 1, &y, 1));
    }
    const double elapsed = seconds() - start;
    printf("%.9f %.17g\n", elapsed, y);
    free_instance(c);
    return 0;
}
