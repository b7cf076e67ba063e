/* What the FMI 3.0 plant wrapper's two files share: the instance, its modes and the guard of every
 * entry point (plant_fmi3.c: the plant; plant_fmi3_refused.c: what the plant does not provide). */
#ifndef PLANT_FMI3_H
#define PLANT_FMI3_H

#include <stddef.h>

#include "fmi3Functions.h"
#include "fmu_liveness.h"

typedef enum {
    INSTANTIATED = 1 << 0, INITIALIZATION = 1 << 1, EVENT_MODE = 1 << 2, CONTINUOUS_TIME = 1 << 3,
    STEP_MODE = 1 << 4, TERMINATED = 1 << 5, ERROR_STATE = 1 << 6
} Mode;
#define ANY_MODE 0x7f
#define RUNNING (EVENT_MODE | CONTINUOUS_TIME | STEP_MODE)
#define SETTABLE (INSTANTIATED | INITIALIZATION | RUNNING)

typedef struct {
    unsigned long long live_tag;  /* first: fmu_liveness.h reads it through the bare instance pointer */
    int model_exchange;
    Mode mode;
    char *name;
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback log;
    int logging_on;
    size_t n;                  /* 1 + 2 nx + nu + ny + np values, indexed by value reference */
    double *v;
    int derived_valid, jacobians_valid, zoh_valid;
    double zoh_step;
    double *A, *B, *C, *D, *work, *augmented, *exponential, *Phi, *Gamma, *expm_work, *next;
    double *k1, *k2, *k3, *k4, *stage;
    int *expm_iwork;
} Plant;

/* Log an error through the host's logger, enter the error state, return fmi3Error. */
fmi3Status plant_fmi3_fail(Plant *p, const char *format, ...);
#define fail plant_fmi3_fail

/* Guard of every entry point: a live instance (fmu_liveness.h) in one of the allowed modes. */
#define ENTER(instance, allowed, function)                                                          \
    Plant *p = (Plant *)(instance);                                                                 \
    if (!fmu_is_live(p, function)) return fmi3Error;                                          \
    if (!(p->mode & (allowed))) return fail(p, "%s: not allowed in the current state (mode %d)", function, (int)p->mode)

/* A caller's array of count values must exist: NULL with count > 0 is refused, not dereferenced. */
#define REQUIRE_VALUES(array, count, function)                                                      \
    if ((count) > 0 && (array) == NULL)                                                             \
    return fail(p, "%s: %s is NULL but holds %zu values", function, #array, (size_t)(count))

#endif
