/* TypedStair3: TypedStair (typed_stair.c, the same model: typed_stair_model.h) as an FMI 3.0 Model
 * Exchange + Co-Simulation FMU, with Float64, every integer type, Enumeration (fmi3GetInt64), Boolean
 * and String variables. At t = stop_at it asks to end the simulation: fmi3DoStep returns terminateSimulation
 * with lastSuccessfulTime = stop_at; in Model Exchange stop_at is a time event whose
 * fmi3UpdateDiscreteStates sets terminateSimulation.
 *
 * Value references (unique in FMI 3.0): Float64 0 time, 1 + the Real index of typed_stair_model.h;
 * Int32 10 + the Integer index of increment, n_in, counter, n_out; Enumeration (Int64) 10 + the
 * Integer index of mode, e_in, e_out; Boolean 20 + index; String 30 + index; the other integer
 * types (W_INT8 ... W_UINT64 of typed_stair_model.h) 40 + 2 w for the input, 41 + 2 w for the output
 * that echoes it.
 */
#include <stdlib.h>

#include "fmi3Functions.h"
#include "typed_stair_model.h"

#define TOKEN "{6f1c2b7e-typed-stair-0003}"

typedef struct {
    int model_exchange;
    int mode;
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback log;
    State s;
} Instance;

static fmi3Status refuse(Instance *inst, const char *function, const char *why) {
    char message[400];
    snprintf(message, sizeof message, "%s: %s", function, why);
    if (inst != NULL && inst->log != NULL) inst->log(inst->environment, fmi3Error, "logStatusError", message);
    return fmi3Error;
}

static Instance *instantiate(fmi3String token, int model_exchange, fmi3InstanceEnvironment environment,
                             fmi3LogMessageCallback log) {
    if (token == NULL || strcmp(token, TOKEN) != 0) {
        if (log != NULL) log(environment, fmi3Error, "logStatusError", "instantiationToken does not match");
        return NULL;
    }
    Instance *inst = calloc(1, sizeof(Instance));
    if (inst == NULL) return NULL;
    inst->model_exchange = model_exchange;
    inst->mode = INSTANTIATED;
    inst->environment = environment;
    inst->log = log;
    start_values(&inst->s);
    return inst;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String name, fmi3String token, fmi3String resources, fmi3Boolean visible,
                                          fmi3Boolean logging, fmi3InstanceEnvironment environment, fmi3LogMessageCallback log) {
    (void)name; (void)resources; (void)visible; (void)logging;
    return instantiate(token, 1, environment, log);
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String resources, fmi3Boolean visible,
                                         fmi3Boolean logging, fmi3Boolean eventMode, fmi3Boolean earlyReturn,
                                         const fmi3ValueReference required[], size_t nRequired,
                                         fmi3InstanceEnvironment environment, fmi3LogMessageCallback log,
                                         fmi3IntermediateUpdateCallback update) {
    (void)name; (void)resources; (void)visible; (void)logging; (void)eventMode; (void)earlyReturn;
    (void)required; (void)nRequired; (void)update;
    return instantiate(token, 0, environment, log);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean tolDefined, fmi3Float64 tol, fmi3Float64 start,
                                       fmi3Boolean stopDefined, fmi3Float64 stop) {
    Instance *inst = instance;
    (void)tolDefined; (void)tol; (void)stopDefined; (void)stop;
    if (inst == NULL) return fmi3Error;
    inst->s.time = start;
    inst->mode = INITIALIZATION;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    Instance *inst = instance;
    if (inst == NULL) return fmi3Error;
    if (!(inst->s.real[VR_PERIOD] > 0.0)) return refuse(inst, "fmi3ExitInitializationMode", "parameter period must be > 0");
    initialized(&inst->s);
    inst->mode = inst->model_exchange ? EVENT : STEPPING;
    return fmi3OK;
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    Instance *inst = instance;
    if (inst == NULL) return fmi3Error;
    inst->mode = EVENT;
    return fmi3OK;
}
fmi3Status fmi3Terminate(fmi3Instance instance) { return instance == NULL ? fmi3Error : fmi3OK; }

fmi3Status fmi3Reset(fmi3Instance instance) {
    if (instance == NULL) return fmi3Error;
    start_values(&((Instance *)instance)->s);
    ((Instance *)instance)->mode = INSTANTIATED;
    return fmi3OK;
}

/* ------------------------------------------------------------------ get / set */

/* The storage of value reference vr of FMI type `type` ('W' + w: integer type w of the wide ones), or
 * NULL; *settable says whether it may be set now: 1 yes (inputs, parameters before initialisation),
 * 0 no, DISCRETE_WAITS for a discrete input of a Model Exchange instance in continuous-time mode. */
enum { DISCRETE_WAITS = -1 };
static void *slot(Instance *inst, fmi3ValueReference vr, int type, int *settable) {
    State *s = &inst->s;
    const int early = !s->initialized;
    const int discrete = inst->model_exchange && inst->mode == CONTINUOUS ? DISCRETE_WAITS : 1;
    if (type == 'F' && vr == 0) { *settable = 0; return &s->time; }
    if (type == 'F' && vr >= 1 && vr <= N_REAL) {
        const int i = (int)vr - 1;
        *settable = i == VR_X_IN || ((i == VR_PERIOD || i == VR_STOP_AT || i == VR_LEVEL) && early);
        if (i == VR_R_IN) *settable = discrete;
        return &s->real[i];
    }
    const int i = (int)vr - 10;
    const int int32 = (i >= VR_INCREMENT && i <= VR_N_OUT) || i == VR_STEPS || i == VR_PROVISIONAL;
    if ((type == 'I' && int32) || (type == 'E' && i >= VR_MODE && i <= VR_E_OUT)) {
        *settable = ((i == VR_INCREMENT || i == VR_MODE) && early);
        if (i == VR_N_IN || i == VR_E_IN) *settable = discrete;
        return &s->integer[i];
    }
    if (type == 'B' && vr >= 20 && vr < 20 + N_BOOLEAN) {
        *settable = vr == 20 + VR_NEGATE && early;
        if (vr == 20 + VR_B_IN) *settable = discrete;
        return &s->boolean[vr - 20];
    }
    if (type == 'S' && vr >= 30 && vr < 30 + N_STRING) {
        *settable = vr == 30 + VR_LABEL && early;
        if (vr == 30 + VR_S_IN) *settable = discrete;
        return s->string[vr - 30];
    }
    if (type >= 'W' && type < 'W' + N_WIDE && vr >= 40 + 2u * (unsigned)(type - 'W') && vr <= 41 + 2u * (unsigned)(type - 'W')) {
        const int input = vr % 2 == 0;
        *settable = input ? discrete : 0;
        return input ? &s->wide_in[type - 'W'] : &s->wide_out[type - 'W'];
    }
    return NULL;
}

static fmi3Status refuse_set(Instance *inst, const char *function, int settable) {
    return refuse(inst, function, settable == DISCRETE_WAITS
                  ? "a discrete input can be set only in initialization mode or event mode"
                  : "not settable now");
}

#define ACCESSORS(NAME, TYPE, CODE, GET, SET)                                                       \
    fmi3Status fmi3Get##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, TYPE values[], size_t nValues) { \
        Instance *inst = instance;                                                                  \
        int settable;                                                                               \
        if (inst == NULL || n != nValues) return refuse(inst, "fmi3Get" #NAME, "scalars only");     \
        for (size_t i = 0; i < n; i++) {                                                            \
            void *where = slot(inst, vr[i], CODE, &settable);                                       \
            if (where == NULL) return refuse(inst, "fmi3Get" #NAME, "unknown value reference");     \
            GET;                                                                                    \
        }                                                                                           \
        return fmi3OK;                                                                              \
    }                                                                                               \
    fmi3Status fmi3Set##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const TYPE values[], size_t nValues) { \
        Instance *inst = instance;                                                                  \
        int settable;                                                                               \
        if (inst == NULL || n != nValues) return refuse(inst, "fmi3Set" #NAME, "scalars only");     \
        for (size_t i = 0; i < n; i++) {                                                            \
            void *where = slot(inst, vr[i], CODE, &settable);                                       \
            if (where == NULL || settable != 1) return refuse_set(inst, "fmi3Set" #NAME, settable);  \
            SET;                                                                                    \
        }                                                                                           \
        compute(&inst->s);                                                                          \
        return fmi3OK;                                                                              \
    }

ACCESSORS(Float64, fmi3Float64, 'F', values[i] = *(double *)where,
          if (!isfinite(values[i])) return refuse(inst, "fmi3SetFloat64", "values must be finite");
          *(double *)where = values[i])
ACCESSORS(Int32, fmi3Int32, 'I', values[i] = *(int *)where, *(int *)where = values[i])
ACCESSORS(Enumeration, fmi3Int64, 'E', values[i] = *(int *)where,
          if (values[i] != 1 && values[i] != 2) return refuse(inst, "fmi3SetInt64", "a Direction is 1 (up) or 2 (down)");
          *(int *)where = (int)values[i])
ACCESSORS(WideInt64, fmi3Int64, 'W' + W_INT64, values[i] = (fmi3Int64)*(unsigned long long *)where,
          *(unsigned long long *)where = (unsigned long long)values[i])
#define WIDE(NAME, TYPE, W) ACCESSORS(NAME, TYPE, 'W' + W, values[i] = (TYPE)*(unsigned long long *)where, \
                                      *(unsigned long long *)where = (unsigned long long)values[i])
WIDE(Int8, fmi3Int8, W_INT8)
WIDE(UInt8, fmi3UInt8, W_UINT8)
WIDE(Int16, fmi3Int16, W_INT16)
WIDE(UInt16, fmi3UInt16, W_UINT16)
WIDE(UInt32, fmi3UInt32, W_UINT32)
WIDE(UInt64, fmi3UInt64, W_UINT64)

/* fmi3GetInt64 / fmi3SetInt64 serve the Enumerations (value references 14-16) and the Int64s (50, 51). */
fmi3Status fmi3GetInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3Int64 values[], size_t nValues) {
    for (size_t i = 0; i < n && instance != NULL; i++) {
        const fmi3Status status = vr[i] >= 40 ? fmi3GetWideInt64(instance, &vr[i], 1, &values[i], 1)
                                              : fmi3GetEnumeration(instance, &vr[i], 1, &values[i], 1);
        if (status != fmi3OK) return status;
    }
    return instance == NULL || n != nValues ? refuse(instance, "fmi3GetInt64", "scalars only") : fmi3OK;
}

fmi3Status fmi3SetInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3Int64 values[], size_t nValues) {
    if (instance == NULL || n != nValues) return refuse(instance, "fmi3SetInt64", "scalars only");
    for (size_t i = 0; i < n; i++) {
        const fmi3Status status = vr[i] >= 40 ? fmi3SetWideInt64(instance, &vr[i], 1, &values[i], 1)
                                              : fmi3SetEnumeration(instance, &vr[i], 1, &values[i], 1);
        if (status != fmi3OK) return status;
    }
    return fmi3OK;
}
ACCESSORS(Boolean, fmi3Boolean, 'B', values[i] = *(int *)where != 0, *(int *)where = values[i] ? 1 : 0)
ACCESSORS(String, fmi3String, 'S', values[i] = (const char *)where,
          if (values[i] == NULL || strlen(values[i]) >= TEXT) return refuse(inst, "fmi3SetString", "NULL or too long");
          strcpy((char *)where, values[i]))

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

/* ------------------------------------------------------------------ not provided */

#include "fmi3_common.h"

/* ------------------------------------------------------------------ FMU state: a copy of State */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *state) {
    if (instance == NULL || state == NULL) return fmi3Error;
    if (*state == NULL && (*state = malloc(sizeof(State))) == NULL) return refuse(instance, "fmi3GetFMUState", "out of memory");
    memcpy(*state, &((Instance *)instance)->s, sizeof(State));
    return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState state) {
    if (instance == NULL || state == NULL) return fmi3Error;
    memcpy(&((Instance *)instance)->s, state, sizeof(State));
    return fmi3OK;
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *state) {
    if (instance == NULL) return fmi3Error;
    if (state != NULL) { free(*state); *state = NULL; }
    return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState state, size_t *size) {
    (void)state;
    if (instance == NULL || size == NULL) return fmi3Error;
    *size = sizeof(State);
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState state, fmi3Byte bytes[], size_t size) {
    if (instance == NULL || state == NULL || size != sizeof(State)) return fmi3Error;
    memcpy(bytes, state, sizeof(State));
    return fmi3OK;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte bytes[], size_t size, fmi3FMUState *state) {
    if (instance == NULL || state == NULL || size != sizeof(State)) return fmi3Error;
    if (*state == NULL && (*state = malloc(sizeof(State))) == NULL) return fmi3Error;
    memcpy(*state, bytes, sizeof(State));
    return fmi3OK;
}

/* ------------------------------------------------------------------ Model Exchange */

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) { return instance == NULL ? fmi3Error : fmi3OK; }

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *needed, fmi3Boolean *terminate, fmi3Boolean *nominals,
                                    fmi3Boolean *values, fmi3Boolean *defined, fmi3Float64 *next) {
    Instance *inst = instance;
    if (inst == NULL) return fmi3Error;
    State *s = &inst->s;
    compute(s);
    s->terminated = reached(s, s->time);
    *needed = *nominals = *values = fmi3False;
    *terminate = s->terminated ? fmi3True : fmi3False;
    *defined = fmi3True;
    *next = fmin((double)(boundaries(s, s->time) + 1) * s->real[VR_PERIOD], s->real[VR_STOP_AT]);
    return fmi3OK;
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    Instance *inst = instance;
    if (inst == NULL) return fmi3Error;
    inst->mode = CONTINUOUS;
    return fmi3OK;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSet, fmi3Boolean *event, fmi3Boolean *stop) {
    (void)noSet;
    if (instance == NULL) return fmi3Error;
    *event = *stop = fmi3False;
    return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    if (instance == NULL) return fmi3Error;
    ((Instance *)instance)->s.time = time;
    return fmi3OK;
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 x[], size_t n) {
    if (instance == NULL || n != 1) return fmi3Error;
    ((Instance *)instance)->s.real[VR_LEVEL] = x[0];
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 dx[], size_t n) {
    if (instance == NULL || n != 1) return fmi3Error;
    dx[0] = ((Instance *)instance)->s.real[VR_X_IN];
    return fmi3OK;
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 z[], size_t n) {
    (void)z;
    return instance == NULL || n != 0 ? fmi3Error : fmi3OK;
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t n) {
    if (instance == NULL || n != 1) return fmi3Error;
    x[0] = ((Instance *)instance)->s.real[VR_LEVEL];
    return fmi3OK;
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t n) {
    if (instance == NULL || n != 1) return fmi3Error;
    x[0] = 1.0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n) {
    if (instance == NULL) return fmi3Error;
    *n = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *n) {
    if (instance == NULL) return fmi3Error;
    *n = 1;
    return fmi3OK;
}

/* ------------------------------------------------------------------ Co-Simulation */

fmi3Status fmi3EnterStepMode(fmi3Instance instance) { return instance == NULL ? fmi3Error : fmi3OK; }

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 t, fmi3Float64 h, fmi3Boolean noSet, fmi3Boolean *event,
                      fmi3Boolean *terminate, fmi3Boolean *early, fmi3Float64 *last) {
    Instance *inst = instance;
    if (inst == NULL) return fmi3Error;
    State *s = &inst->s;
    *event = *early = *terminate = fmi3False;
    *last = s->time;
    if (s->terminated) return refuse(inst, "fmi3DoStep", "the simulation was terminated at stop_at");
    if (!(h >= 0.0) || fabs(t - s->time) > 1e-9 * fmax(1.0, fabs(t)))
        return refuse(inst, "fmi3DoStep", "the step must start at the FMU's time and have h >= 0");
    double end = t + h;
    if (reached(s, end)) {  /* stop at stop_at, as a time event inside the step would */
        end = fmax(t, s->real[VR_STOP_AT]);
        s->terminated = 1;
    }
    begin_step(s, noSet);
    s->real[VR_LEVEL] += s->real[VR_X_IN] * (end - t);
    s->time = end;
    compute(s);
    *terminate = s->terminated ? fmi3True : fmi3False;
    *last = end;
    return fmi3OK;
}
