/* ArrayGain3: an FMI 3.0 Co-Simulation FMU with 1-D array variables, for the master's array tests.
 *
 *   Float64 u[3]  input, start 1 2 3         Float64 y[3]   output  y = k .* u (feeds through)
 *   Float64 k[3]  tunable parameter, 1 1 1   Float64 total  output  total = s + sum(y) (feeds through)
 *   Float64 s     input, start 0             Float64 x[3]   output  x += h * y over each step (from the
 *   Int32   m[2]  input, start 0 0                                  step's start), x(t0) = 0
 *                                            Int32   m2[2]  output  m2 = 2 * m (feeds through)
 *
 * Value references: 0 time, 1 u, 2 k, 3 s, 4 y, 5 total, 6 x, 7 m, 8 m2. The getters and setters
 * take an array's value reference once and move all its elements (FMI 3.0): nValues must
 * be the number of elements over all the value references, or the call fails; that is what the tests
 * check the master passes. Other types, Model Exchange and FMU states are not provided.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

#define TOKEN "{6f1c2b7e-array-gain-0003}"

typedef struct {
    double time, u[3], k[3], s, y[3], total, x[3];
    int m[2], m2[2];
    int initialized;
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback log;
} Instance;

static fmi3Status refuse(Instance *inst, const char *function, const char *why) {
    if (inst != NULL && inst->log != NULL) {
        char message[300];
        snprintf(message, sizeof message, "%s: %s", function, why);
        inst->log(inst->environment, fmi3Error, "logStatusError", message);
    }
    return fmi3Error;
}

static void start_values(Instance *inst) {
    for (int i = 0; i < 3; i++) {
        inst->u[i] = i + 1.0;
        inst->k[i] = 1.0;
        inst->x[i] = 0.0;
    }
    inst->s = 0.0;
    inst->m[0] = inst->m[1] = 0;
    inst->time = 0.0;
    inst->initialized = 0;
}

static void compute(Instance *inst) {
    inst->total = inst->s;
    for (int i = 0; i < 3; i++) {
        inst->y[i] = inst->k[i] * inst->u[i];
        inst->total += inst->y[i];
    }
    for (int i = 0; i < 2; i++) inst->m2[i] = 2 * inst->m[i];
}

/* The storage of Float64 value reference vr, its element count, and whether it may be set now. */
static double *float64(Instance *inst, fmi3ValueReference vr, size_t *size, int *settable) {
    double *where[] = {&inst->time, inst->u, inst->k, &inst->s, inst->y, &inst->total, inst->x};
    const size_t sizes[] = {1, 3, 3, 1, 3, 1, 3};
    if (vr > 6) return NULL;
    *size = sizes[vr];
    *settable = vr == 1 || vr == 2 || vr == 3;  /* inputs and the tunable parameter, in every mode */
    return where[vr];
}

static int *int32(Instance *inst, fmi3ValueReference vr, size_t *size, int *settable) {
    if (vr != 7 && vr != 8) return NULL;
    *size = 2;
    *settable = vr == 7;
    return vr == 7 ? inst->m : inst->m2;
}

#define ACCESSORS(NAME, TYPE, STORAGE)                                                              \
    fmi3Status fmi3Get##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, TYPE values[], size_t nValues) { \
        Instance *inst = instance;                                                                  \
        size_t at = 0, size;                                                                        \
        int settable;                                                                               \
        if (inst == NULL) return fmi3Error;                                                         \
        for (size_t i = 0; i < n; i++) {                                                            \
            const TYPE *where = STORAGE(inst, vr[i], &size, &settable);                             \
            if (where == NULL) return refuse(inst, "fmi3Get" #NAME, "unknown value reference");     \
            if (at + size > nValues) return refuse(inst, "fmi3Get" #NAME, "nValues is less than the elements"); \
            memcpy(values + at, where, size * sizeof(TYPE));                                        \
            at += size;                                                                             \
        }                                                                                           \
        return at == nValues ? fmi3OK : refuse(inst, "fmi3Get" #NAME, "nValues is not the element count"); \
    }                                                                                               \
    fmi3Status fmi3Set##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const TYPE values[], size_t nValues) { \
        Instance *inst = instance;                                                                  \
        size_t at = 0, size;                                                                        \
        int settable;                                                                               \
        if (inst == NULL) return fmi3Error;                                                         \
        for (size_t i = 0; i < n; i++) {                                                            \
            TYPE *where = STORAGE(inst, vr[i], &size, &settable);                                   \
            if (where == NULL || !settable) return refuse(inst, "fmi3Set" #NAME, "not settable");   \
            if (at + size > nValues) return refuse(inst, "fmi3Set" #NAME, "nValues is less than the elements"); \
            memcpy(where, values + at, size * sizeof(TYPE));                                        \
            at += size;                                                                             \
        }                                                                                           \
        if (at != nValues) return refuse(inst, "fmi3Set" #NAME, "nValues is not the element count"); \
        compute(inst);                                                                              \
        return fmi3OK;                                                                              \
    }
ACCESSORS(Float64, fmi3Float64, float64)
ACCESSORS(Int32, fmi3Int32, int32)

#define NO_TYPE(NAME, TYPE)                                                                         \
    fmi3Status fmi3Get##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, TYPE values[], size_t m) { \
        (void)vr; (void)values; (void)m;                                                            \
        return n == 0 ? fmi3OK : refuse(instance, "fmi3Get" #NAME, "no such variables");            \
    }                                                                                               \
    fmi3Status fmi3Set##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const TYPE values[], size_t m) { \
        (void)vr; (void)values; (void)m;                                                            \
        return n == 0 ? fmi3OK : refuse(instance, "fmi3Set" #NAME, "no such variables");            \
    }
NO_TYPE(Float32, fmi3Float32)
NO_TYPE(Int8, fmi3Int8)
NO_TYPE(UInt8, fmi3UInt8)
NO_TYPE(Int16, fmi3Int16)
NO_TYPE(UInt16, fmi3UInt16)
NO_TYPE(UInt32, fmi3UInt32)
NO_TYPE(Int64, fmi3Int64)
NO_TYPE(UInt64, fmi3UInt64)
NO_TYPE(Boolean, fmi3Boolean)
NO_TYPE(String, fmi3String)

/* ------------------------------------------------------------------ life cycle */

fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String resources, fmi3Boolean visible,
                                         fmi3Boolean logging, fmi3Boolean eventMode, fmi3Boolean earlyReturn,
                                         const fmi3ValueReference required[], size_t nRequired,
                                         fmi3InstanceEnvironment environment, fmi3LogMessageCallback log,
                                         fmi3IntermediateUpdateCallback update) {
    (void)name; (void)resources; (void)visible; (void)logging; (void)eventMode; (void)earlyReturn;
    (void)required; (void)nRequired; (void)update;
    if (token == NULL || strcmp(token, TOKEN) != 0) {
        if (log != NULL) log(environment, fmi3Error, "logStatusError", "instantiationToken does not match");
        return NULL;
    }
    Instance *inst = calloc(1, sizeof(Instance));
    if (inst == NULL) return NULL;
    inst->environment = environment;
    inst->log = log;
    start_values(inst);
    compute(inst);
    return inst;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String name, fmi3String token, fmi3String resources, fmi3Boolean visible,
                                          fmi3Boolean logging, fmi3InstanceEnvironment environment, fmi3LogMessageCallback log) {
    (void)name; (void)token; (void)resources; (void)visible; (void)logging; (void)environment; (void)log;
    return NULL;
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean tolDefined, fmi3Float64 tol, fmi3Float64 start,
                                       fmi3Boolean stopDefined, fmi3Float64 stop) {
    (void)tolDefined; (void)tol; (void)stopDefined; (void)stop;
    if (instance == NULL) return fmi3Error;
    ((Instance *)instance)->time = start;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    if (instance == NULL) return fmi3Error;
    ((Instance *)instance)->initialized = 1;
    compute(instance);
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance) { return instance == NULL ? fmi3Error : fmi3OK; }

fmi3Status fmi3Reset(fmi3Instance instance) {
    if (instance == NULL) return fmi3Error;
    start_values(instance);
    compute(instance);
    return fmi3OK;
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance) { return instance == NULL ? fmi3Error : fmi3OK; }

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 t, fmi3Float64 h, fmi3Boolean noSet, fmi3Boolean *event,
                      fmi3Boolean *terminate, fmi3Boolean *early, fmi3Float64 *last) {
    Instance *inst = instance;
    (void)noSet;
    if (inst == NULL) return fmi3Error;
    *event = *early = *terminate = fmi3False;
    *last = inst->time;
    if (!(h >= 0.0) || fabs(t - inst->time) > 1e-9 * fmax(1.0, fabs(t)))
        return refuse(inst, "fmi3DoStep", "the step must start at the FMU's time and have h >= 0");
    for (int i = 0; i < 3; i++) inst->x[i] += h * inst->y[i];
    inst->time = t + h;
    compute(inst);
    *last = inst->time;
    return fmi3OK;
}

/* ------------------------------------------------------------------ not provided */

#include "fmi3_common.h"
fmi3Status fmi3EnterEventMode(fmi3Instance instance) NOT_PROVIDED(fmi3EnterEventMode, (void)0)
fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *state) NOT_PROVIDED(fmi3GetFMUState, (void)state)
fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState state) NOT_PROVIDED(fmi3SetFMUState, (void)state)
fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *state) NOT_PROVIDED(fmi3FreeFMUState, (void)state)
fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState state, size_t *size)
    NOT_PROVIDED(fmi3SerializedFMUStateSize, (void)state; (void)size)
fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState state, fmi3Byte bytes[], size_t size)
    NOT_PROVIDED(fmi3SerializeFMUState, (void)state; (void)bytes; (void)size)
fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte bytes[], size_t size, fmi3FMUState *state)
    NOT_PROVIDED(fmi3DeserializeFMUState, (void)bytes; (void)size; (void)state)
fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) NOT_PROVIDED(fmi3EvaluateDiscreteStates, (void)0)
fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *needed, fmi3Boolean *terminate, fmi3Boolean *nominals,
                                    fmi3Boolean *values, fmi3Boolean *defined, fmi3Float64 *next)
    NOT_PROVIDED(fmi3UpdateDiscreteStates, (void)needed; (void)terminate; (void)nominals; (void)values; (void)defined; (void)next)
fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) NOT_PROVIDED(fmi3EnterContinuousTimeMode, (void)0)
fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSet, fmi3Boolean *event, fmi3Boolean *stop)
    NOT_PROVIDED(fmi3CompletedIntegratorStep, (void)noSet; (void)event; (void)stop)
fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) NOT_PROVIDED(fmi3SetTime, (void)time)
fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 x[], size_t n)
    NOT_PROVIDED(fmi3SetContinuousStates, (void)x; (void)n)
fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 dx[], size_t n)
    NOT_PROVIDED(fmi3GetContinuousStateDerivatives, (void)dx; (void)n)
fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 z[], size_t n)
    NOT_PROVIDED(fmi3GetEventIndicators, (void)z; (void)n)
fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t n)
    NOT_PROVIDED(fmi3GetContinuousStates, (void)x; (void)n)
fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t n)
    NOT_PROVIDED(fmi3GetNominalsOfContinuousStates, (void)x; (void)n)
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n) NOT_PROVIDED(fmi3GetNumberOfEventIndicators, (void)n)
fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *n) NOT_PROVIDED(fmi3GetNumberOfContinuousStates, (void)n)
