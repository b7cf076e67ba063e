/* Generic FMI 3.0 Model Exchange + Co-Simulation wrapper for the plants of shapefmu.
 *
 * The FMI 3.0 twin of plant_fmi2.c, over the same model part (plant_model.h) and the same
 * numerics: the Co-Simulation step of a linear plant is the exact zero-order hold
 * [Phi, Gamma] = expm([[A, B], [0, 0]] h) (Van Loan 1978) computed and applied in the same order of
 * operations, so an FMI 3.0 plant and an FMI 2.0 plant built from one model give the same numbers
 * to the last bit; a nonlinear plant takes fixed RK4 substeps no longer than its substep parameter.
 *
 * Value references are those of plant_model.h, all Float64: 0 time (the independent variable, listed
 * in modelDescription.xml as FMI 3.0 requires), the states, their derivatives, the inputs, the
 * outputs and the parameters. There are no events and no clocks: Scheduled Execution, clocks,
 * configuration mode and variables of other types are refused with a logged message.
 *
 * Any refused call (bad argument, call out of order, non-finite value) logs a message naming the
 * function and the variable, returns fmi3Error and puts the instance into the error state.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "plant_expm.h"
#include "plant_fmi3.h"
#include "plant_model.h"

/* An FMU state: the mode and the values, marked by this FMU's instantiation token (a state of another
 * FMU, or a pointer that is no state, is refused rather than copied from). */
#define SNAPSHOT_MAGIC 0x7368617053746174ULL /* "shapStat" */
typedef struct { unsigned long long magic; const char *token; Mode mode; double *v; } Snapshot;
static int ours(const Snapshot *s) { return s->magic == SNAPSHOT_MAGIC && s->token == plant_model.guid; }

#define NX plant_model.n_states
#define NU plant_model.n_inputs
#define NY plant_model.n_outputs
#define NP plant_model.n_parameters
#define X(p) ((p)->v + 1)
#define DX(p) ((p)->v + 1 + NX)
#define U(p) ((p)->v + 1 + 2 * NX)
#define Y(p) ((p)->v + 1 + 2 * NX + NU)
#define P(p) ((p)->v + 1 + 2 * NX + NU + NY)

static const char *name_of(size_t vr) {
    const size_t x = 1, dx = x + NX, u = dx + NX, y = u + NU, p = y + NY;
    if (vr == 0) return "time";
    if (vr < dx) return plant_model.state_names[vr - x];
    if (vr < u) return "a state derivative";
    if (vr < y) return plant_model.input_names[vr - u];
    if (vr < p) return plant_model.output_names[vr - y];
    return plant_model.parameters[vr - p].name;
}

fmi3Status plant_fmi3_fail(Plant *p, const char *format, ...) {
    char message[512];
    va_list args;
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    if (p->log != NULL) p->log(p->environment, fmi3Error, "logStatusError", message);
    p->mode = ERROR_STATE;
    return fmi3Error;
}

static int finite_all(const double *x, size_t n) {
    for (size_t i = 0; i < n; i++)
        if (!isfinite(x[i])) return 0;
    return 1;
}

/* ------------------------------------------------------------------ numerics (as plant_fmi2.c) */

static fmi3Status derive(Plant *p, const char *function) {
    if (p->derived_valid) return fmi3OK;
    if (plant_derivatives_outputs(X(p), U(p), P(p), DX(p), Y(p), p->work) != 0 || !finite_all(DX(p), (size_t)NX)
        || !finite_all(Y(p), (size_t)NY))
        return fail(p, "%s: the model gives non-finite derivatives or outputs at time %g", function, p->v[0]);
    p->derived_valid = 1;
    return fmi3OK;
}

static fmi3Status jacobians(Plant *p, const char *function) {
    if (p->jacobians_valid) return fmi3OK;
    const size_t n = (size_t)NX, m = (size_t)NU, q = (size_t)NY;
    if (plant_jacobians(X(p), U(p), P(p), p->A, p->B, p->C, p->D, p->work) != 0 || !finite_all(p->A, n * n)
        || !finite_all(p->B, n * m) || !finite_all(p->C, q * n) || !finite_all(p->D, q * m))
        return fail(p, "%s: the parameters give a non-finite Jacobian (state-space matrices)", function);
    p->jacobians_valid = plant_model.linear;  /* a linear plant's Jacobians depend on p only */
    return fmi3OK;
}

/* The exact zero-order hold of step h: x+ = Phi x + Gamma u, cached until h or a parameter changes. */
static fmi3Status zoh_step(Plant *p, double h, const char *function) {
    const int n = NX, m = NU, k = n + m;
    if (!(p->zoh_valid && p->zoh_step == h)) {
        if (jacobians(p, function) != fmi3OK) return fmi3Error;
        memset(p->augmented, 0, (size_t)k * (size_t)k * sizeof(double));
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) p->augmented[(size_t)j * k + i] = p->A[(size_t)j * n + i] * h;
        for (int j = 0; j < m; j++)
            for (int i = 0; i < n; i++) p->augmented[(size_t)(n + j) * k + i] = p->B[(size_t)j * n + i] * h;
        if (plant_expm(k, p->augmented, p->exponential, p->expm_work, p->expm_iwork) != 0)
            return fail(p, "%s: the matrix exponential for step %g failed", function, h);
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) p->Phi[(size_t)j * n + i] = p->exponential[(size_t)j * k + i];
        for (int j = 0; j < m; j++)
            for (int i = 0; i < n; i++) p->Gamma[(size_t)j * n + i] = p->exponential[(size_t)(n + j) * k + i];
        p->zoh_step = h;
        p->zoh_valid = 1;
    }
    double *x = X(p);
    const double *u = U(p);
    for (int i = 0; i < n; i++) {
        double s = 0.0;
        for (int j = 0; j < n; j++) s += p->Phi[(size_t)j * n + i] * x[j];
        for (int j = 0; j < m; j++) s += p->Gamma[(size_t)j * n + i] * u[j];
        p->next[i] = s;
    }
    memcpy(x, p->next, (size_t)n * sizeof(double));
    return fmi3OK;
}

static int rates(Plant *p, const double *x, double *dx) {
    return plant_derivatives_outputs(x, U(p), P(p), dx, Y(p), p->work);
}

static fmi3Status rk4_step(Plant *p, double h, const char *function) {
    const int n = NX;
    const double substep = P(p)[plant_model.substep_parameter];
    const long substeps = plant_substeps(h, substep);
    if (substeps == 0)
        return fail(p, "%s: a step of %g s in RK4 substeps of at most substep = %g s needs more than the %ld substeps "
                    "allowed per step; take shorter steps or a longer substep", function, h, substep, PLANT_MAX_SUBSTEPS);
    const double dt = h / (double)substeps;
    double *x = X(p);
    for (long s = 0; s < substeps; s++) {
        int bad = rates(p, x, p->k1);
        for (int i = 0; i < n; i++) p->stage[i] = x[i] + 0.5 * dt * p->k1[i];
        bad |= rates(p, p->stage, p->k2);
        for (int i = 0; i < n; i++) p->stage[i] = x[i] + 0.5 * dt * p->k2[i];
        bad |= rates(p, p->stage, p->k3);
        for (int i = 0; i < n; i++) p->stage[i] = x[i] + dt * p->k3[i];
        bad |= rates(p, p->stage, p->k4);
        for (int i = 0; i < n; i++) p->next[i] = x[i] + dt / 6.0 * (p->k1[i] + 2.0 * p->k2[i] + 2.0 * p->k3[i] + p->k4[i]);
        if (bad || !finite_all(p->next, (size_t)n))
            return fail(p, "%s: the state became non-finite in the substep at time %g", function, p->v[0] + (double)s * dt);
        memcpy(x, p->next, (size_t)n * sizeof(double));
    }
    return fmi3OK;
}

static const char *out_of_range(int i, double value) {
    switch (plant_model.parameters[i].constraint) {
    case PLANT_ANY: return isfinite(value) ? NULL : "a finite number";
    case PLANT_POSITIVE: return isfinite(value) && value > 0.0 ? NULL : "> 0";
    case PLANT_NONNEGATIVE: return isfinite(value) && value >= 0.0 ? NULL : ">= 0";
    case PLANT_NONZERO: return isfinite(value) && value != 0.0 ? NULL : "finite and != 0";
    case PLANT_DAMPING_RATIO: return isfinite(value) && value >= 0.0 && value < 1.0 ? NULL : "in [0, 1)";
    }
    return "valid";
}

static void start_values(Plant *p) {
    memset(p->v, 0, p->n * sizeof(double));
    memcpy(X(p), plant_model.state_start, (size_t)NX * sizeof(double));
    memcpy(U(p), plant_model.input_start, (size_t)NU * sizeof(double));
    for (int i = 0; i < NP; i++) P(p)[i] = plant_model.parameters[i].start;
    p->derived_valid = p->jacobians_valid = p->zoh_valid = 0;
}

/* ------------------------------------------------------------------ life cycle */

/* Everything a plant holds but its struct (released on a failed instantiation, retired on free). */
static void free_buffers(Plant *p) {
    void *buffers[] = {p->name, p->v, p->A, p->B, p->C, p->D, p->work, p->augmented, p->exponential, p->Phi, p->Gamma,
                       p->expm_work, p->next, p->k1, p->k2, p->k3, p->k4, p->stage, p->expm_iwork};
    for (size_t i = 0; i < sizeof buffers / sizeof buffers[0]; i++) free(buffers[i]);
}

static fmi3Instance instantiate(fmi3String name, fmi3String token, int model_exchange, fmi3Boolean logging_on,
                                fmi3InstanceEnvironment environment, fmi3LogMessageCallback log) {
    const char *why = NULL;
    if (name == NULL || name[0] == '\0') why = "instanceName must be a non-empty string";
    else if (token == NULL || strcmp(token, plant_model.guid) != 0)
        why = "instantiationToken does not match the one in this FMU's modelDescription.xml";
    if (why != NULL) {
        if (log != NULL) log(environment, fmi3Error, "logStatusError", why);
        return NULL;
    }
    Plant *p = calloc(1, sizeof(Plant));
    if (p == NULL) return NULL;
    const size_t n = (size_t)NX, m = (size_t)NU, q = (size_t)NY, k = n + m;
    p->model_exchange = model_exchange;
    p->environment = environment;
    p->log = log;
    p->logging_on = logging_on;
    p->mode = INSTANTIATED;
    p->n = 1 + 2 * n + m + q + (size_t)NP;
    p->name = malloc(strlen(name) + 1);
    p->v = calloc(p->n, sizeof(double));
    p->A = calloc(n * n + 1, sizeof(double));
    p->B = calloc(n * m + 1, sizeof(double));
    p->C = calloc(q * n + 1, sizeof(double));
    p->D = calloc(q * m + 1, sizeof(double));
    p->work = calloc(plant_model.work_size + 1, sizeof(double));
    p->augmented = calloc(k * k + 1, sizeof(double));
    p->exponential = calloc(k * k + 1, sizeof(double));
    p->Phi = calloc(n * n + 1, sizeof(double));
    p->Gamma = calloc(n * m + 1, sizeof(double));
    p->expm_work = calloc(PLANT_EXPM_WORK(k) + 1, sizeof(double));
    p->expm_iwork = calloc(PLANT_EXPM_IWORK(k) + 1, sizeof(int));
    p->next = calloc(n + 1, sizeof(double));
    p->k1 = calloc(n + 1, sizeof(double));
    p->k2 = calloc(n + 1, sizeof(double));
    p->k3 = calloc(n + 1, sizeof(double));
    p->k4 = calloc(n + 1, sizeof(double));
    p->stage = calloc(n + 1, sizeof(double));
    if (!(p->name && p->v && p->A && p->B && p->C && p->D && p->work && p->augmented && p->exponential && p->Phi
          && p->Gamma && p->expm_work && p->expm_iwork && p->next && p->k1 && p->k2 && p->k3 && p->k4 && p->stage)) {
        if (log != NULL) log(environment, fmi3Error, "logStatusError", "out of memory");
        free_buffers(p), free(p);
        return NULL;
    }
    strcpy(p->name, name);
    start_values(p);
    fmu_mark_live(p);
    return p;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage) {
    (void)resourcePath; (void)visible;
    return instantiate(instanceName, instantiationToken, 1, loggingOn, instanceEnvironment, logMessage);
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
                                         fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)resourcePath; (void)visible; (void)eventModeUsed; (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables; (void)nRequiredIntermediateVariables; (void)intermediateUpdate;
    return instantiate(instanceName, instantiationToken, 0, loggingOn, instanceEnvironment, logMessage);
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instanceName; (void)instantiationToken; (void)resourcePath; (void)visible; (void)loggingOn;
    (void)clockUpdate; (void)lockPreemption; (void)unlockPreemption;
    if (logMessage != NULL) logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                                       "fmi3InstantiateScheduledExecution: the plant has no Scheduled Execution interface");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) {
    /* An instance freed already (or never made here) is not touched: see fmu_liveness.h. */
    if (fmu_mark_freed(instance)) { free_buffers((Plant *)instance); fmu_retire(instance); }
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories, const fmi3String categories[]) {
    ENTER(instance, ANY_MODE, "fmi3SetDebugLogging");
    (void)nCategories; (void)categories;
    p->logging_on = loggingOn;
    return fmi3OK;
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    ENTER(instance, INSTANTIATED, "fmi3EnterInitializationMode");
    (void)toleranceDefined; (void)tolerance;
    if (!isfinite(startTime)) return fail(p, "fmi3EnterInitializationMode: startTime must be finite, got %g", startTime);
    if (stopTimeDefined && !(stopTime >= startTime))
        return fail(p, "fmi3EnterInitializationMode: stopTime must be >= startTime = %g, got %g", startTime, stopTime);
    p->v[0] = startTime;
    p->mode = INITIALIZATION;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    ENTER(instance, INITIALIZATION, "fmi3ExitInitializationMode");
    if (jacobians(p, "fmi3ExitInitializationMode") != fmi3OK || derive(p, "fmi3ExitInitializationMode") != fmi3OK)
        return fmi3Error;
    p->mode = p->model_exchange ? EVENT_MODE : STEP_MODE;
    return fmi3OK;
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    ENTER(instance, CONTINUOUS_TIME | STEP_MODE | EVENT_MODE, "fmi3EnterEventMode");
    if (!p->model_exchange) return fail(p, "fmi3EnterEventMode: this Co-Simulation instance has no event mode");
    p->mode = EVENT_MODE;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    ENTER(instance, RUNNING, "fmi3Terminate");
    p->mode = TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    ENTER(instance, ANY_MODE, "fmi3Reset");
    start_values(p);
    p->mode = INSTANTIATED;
    return fmi3OK;
}

/* ------------------------------------------------------------------ get / set */

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[], size_t nValues) {
    ENTER(instance, ANY_MODE & ~INSTANTIATED, "fmi3GetFloat64");
    if (nValues != nvr) return fail(p, "fmi3GetFloat64: nValues %zu must equal nValueReferences %zu (scalars only)", nValues, nvr);
    REQUIRE_VALUES(vr, nvr, "fmi3GetFloat64");
    REQUIRE_VALUES(values, nValues, "fmi3GetFloat64");
    for (size_t i = 0; i < nvr; i++)
        if (vr[i] >= p->n) return fail(p, "fmi3GetFloat64: no Float64 variable has value reference %u", (unsigned)vr[i]);
    if (p->mode != ERROR_STATE && derive(p, "fmi3GetFloat64") != fmi3OK) return fmi3Error;
    for (size_t i = 0; i < nvr; i++) values[i] = p->v[vr[i]];
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Float64 values[], size_t nValues) {
    ENTER(instance, SETTABLE, "fmi3SetFloat64");
    const size_t state = 1, derivative = state + NX, input = derivative + NX, output = input + NU, parameter = output + NY;
    if (nValues != nvr) return fail(p, "fmi3SetFloat64: nValues %zu must equal nValueReferences %zu (scalars only)", nValues, nvr);
    REQUIRE_VALUES(vr, nvr, "fmi3SetFloat64");
    REQUIRE_VALUES(values, nValues, "fmi3SetFloat64");
    for (size_t i = 0; i < nvr; i++) {  /* check everything first: a refused call changes nothing */
        const size_t r = vr[i];
        const int early = (p->mode & (INSTANTIATED | INITIALIZATION)) != 0;
        if (r >= p->n) return fail(p, "fmi3SetFloat64: no Float64 variable has value reference %u", (unsigned)r);
        if (r == 0 || (r >= derivative && r < input) || (r >= output && r < parameter))
            return fail(p, "fmi3SetFloat64: %s is computed by the FMU and cannot be set", name_of(r));
        if (r < derivative && !early)
            return fail(p, "fmi3SetFloat64: state %s can be set only before initialisation is complete", name_of(r));
        if (r >= parameter) {
            const int j = (int)(r - parameter);
            const char *range = out_of_range(j, values[i]);
            if (range != NULL) return fail(p, "fmi3SetFloat64: parameter %s must be %s, got %g", name_of(r), range, values[i]);
            if (!early && !plant_model.parameters[j].tunable)
                return fail(p, "fmi3SetFloat64: parameter %s is fixed and cannot be set after initialisation", name_of(r));
            if (!early && (p->mode & CONTINUOUS_TIME))
                return fail(p, "fmi3SetFloat64: tunable parameter %s can be set only in Event Mode or Step Mode", name_of(r));
        } else if (!isfinite(values[i])) {
            return fail(p, "fmi3SetFloat64: %s must be finite, got %g", name_of(r), values[i]);
        }
    }
    for (size_t i = 0; i < nvr; i++) {
        if (p->v[vr[i]] == values[i]) continue;
        p->v[vr[i]] = values[i];
        p->derived_valid = 0;
        if (vr[i] >= parameter) p->jacobians_valid = p->zoh_valid = 0;
        else if (!plant_model.linear) p->jacobians_valid = 0;
    }
    return fmi3OK;
}

/* ------------------------------------------------------------------ FMU state */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *state) {
    ENTER(instance, ANY_MODE & ~ERROR_STATE, "fmi3GetFMUState");
    if (state == NULL) return fail(p, "fmi3GetFMUState: FMUState is NULL");
    Snapshot *s = *state;
    if (s != NULL && !ours(s)) return fail(p, "fmi3GetFMUState: FMUState is not NULL nor a state of this FMU");
    if (s == NULL) {
        s = calloc(1, sizeof(Snapshot));
        if (s == NULL || (s->v = calloc(p->n, sizeof(double))) == NULL) {
            free(s);
            return fail(p, "fmi3GetFMUState: out of memory");
        }
        s->magic = SNAPSHOT_MAGIC;
        s->token = plant_model.guid;
    }
    s->mode = p->mode;
    memcpy(s->v, p->v, p->n * sizeof(double));
    *state = s;
    return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState state) {
    ENTER(instance, ANY_MODE, "fmi3SetFMUState");
    if (state == NULL) return fail(p, "fmi3SetFMUState: FMUState is NULL");
    const Snapshot *s = state;
    if (!ours(s)) return fail(p, "fmi3SetFMUState: the state is not one of this FMU (another FMU's, or no state at all)");
    const size_t parameter = 1 + 2 * (size_t)NX + NU + NY;  /* as fmi3SetFloat64 checks a value set alone */
    for (size_t r = 0; r < p->n; r++) {
        const char *range = r >= parameter ? out_of_range((int)(r - parameter), s->v[r]) : isfinite(s->v[r]) ? NULL : "finite";
        if (range != NULL) return fail(p, "fmi3SetFMUState: %s must be %s, got %g", name_of(r), range, s->v[r]);
    }
    memcpy(p->v, s->v, p->n * sizeof(double));
    p->mode = s->mode;
    p->derived_valid = p->jacobians_valid = p->zoh_valid = 0;
    return fmi3OK;
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *state) {
    ENTER(instance, ANY_MODE, "fmi3FreeFMUState");
    if (state != NULL && *state != NULL) {
        if (!ours(*state)) return fail(p, "fmi3FreeFMUState: the state is not one of this FMU (another FMU's, or none)");
        free(((Snapshot *)*state)->v);
        free(*state);
        *state = NULL;
    }
    return fmi3OK;
}

/* Serialised: the mode (as a double), then the values. */
fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState state, size_t *size) {
    ENTER(instance, ANY_MODE, "fmi3SerializedFMUStateSize");
    if (state == NULL || size == NULL) return fail(p, "fmi3SerializedFMUStateSize: NULL FMUState or size");
    if (!ours(state)) return fail(p, "fmi3SerializedFMUStateSize: the state is not one of this FMU");
    *size = (p->n + 1) * sizeof(double);
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState state, fmi3Byte bytes[], size_t size) {
    ENTER(instance, ANY_MODE, "fmi3SerializeFMUState");
    if (state == NULL || bytes == NULL || size != (p->n + 1) * sizeof(double))
        return fail(p, "fmi3SerializeFMUState: NULL FMUState or buffer, or a buffer of the wrong size %zu", size);
    const Snapshot *s = state;
    if (!ours(s)) return fail(p, "fmi3SerializeFMUState: the state is not one of this FMU");
    const double mode = (double)s->mode;
    memcpy(bytes, &mode, sizeof mode);
    memcpy(bytes + sizeof mode, s->v, p->n * sizeof(double));
    return fmi3OK;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte bytes[], size_t size, fmi3FMUState *state) {
    ENTER(instance, ANY_MODE, "fmi3DeserializeFMUState");
    double mode;
    if (bytes == NULL || state == NULL || size != (p->n + 1) * sizeof(double))
        return fail(p, "fmi3DeserializeFMUState: got %zu bytes, a state of this FMU has %zu", size, (p->n + 1) * sizeof(double));
    memcpy(&mode, bytes, sizeof mode);
    if (!(mode >= 1.0 && mode <= (double)ANY_MODE) || mode != floor(mode))
        return fail(p, "fmi3DeserializeFMUState: the bytes are not a serialised state of this FMU");
    if (fmi3GetFMUState(instance, state) != fmi3OK) return fmi3Error;  /* a snapshot to fill, with its marks */
    memcpy(((Snapshot *)*state)->v, bytes + sizeof mode, p->n * sizeof(double));
    ((Snapshot *)*state)->mode = (Mode)mode;
    return fmi3OK;
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    ENTER(instance, INITIALIZATION | RUNNING | TERMINATED, "fmi3GetDirectionalDerivative");
    const size_t x = 1, dx = x + NX, u = dx + NX, y = u + NU, par = y + NY;
    if (nSeed != nKnowns || nSensitivity != nUnknowns) return fail(p, "fmi3GetDirectionalDerivative: scalars only");
    REQUIRE_VALUES(unknowns, nUnknowns, "fmi3GetDirectionalDerivative");
    REQUIRE_VALUES(knowns, nKnowns, "fmi3GetDirectionalDerivative");
    REQUIRE_VALUES(seed, nSeed, "fmi3GetDirectionalDerivative");
    REQUIRE_VALUES(sensitivity, nSensitivity, "fmi3GetDirectionalDerivative");
    if (jacobians(p, "fmi3GetDirectionalDerivative") != fmi3OK) return fmi3Error;
    for (size_t i = 0; i < nUnknowns; i++) {
        double sum = 0.0;
        for (size_t j = 0; j < nKnowns; j++) {
            const size_t r = unknowns[i], k = knowns[j];
            double entry;
            if (r >= dx && r < u && k >= x && k < dx) entry = p->A[(k - x) * NX + (r - dx)];
            else if (r >= dx && r < u && k >= u && k < y) entry = p->B[(k - u) * NX + (r - dx)];
            else if (r >= y && r < par && k >= x && k < dx) entry = p->C[(k - x) * NY + (r - y)];
            else if (r >= y && r < par && k >= u && k < y) entry = p->D[(k - u) * NY + (r - y)];
            else return fail(p, "fmi3GetDirectionalDerivative: unknowns must be derivatives or outputs, knowns states or inputs");
            sum += entry * seed[j];
        }
        sensitivity[i] = sum;
    }
    return fmi3OK;
}

/* ------------------------------------------------------------------ Model Exchange */

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    ENTER(instance, EVENT_MODE | CONTINUOUS_TIME, "fmi3EvaluateDiscreteStates");
    return fmi3OK;
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *needed, fmi3Boolean *terminate, fmi3Boolean *nominals,
                                    fmi3Boolean *values, fmi3Boolean *defined, fmi3Float64 *next) {
    ENTER(instance, EVENT_MODE | STEP_MODE, "fmi3UpdateDiscreteStates");
    if (!needed || !terminate || !nominals || !values || !defined || !next)
        return fail(p, "fmi3UpdateDiscreteStates: NULL argument");
    *needed = *terminate = *nominals = *values = *defined = fmi3False;  /* no discrete states, no time events */
    *next = 0.0;
    return fmi3OK;
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    ENTER(instance, EVENT_MODE, "fmi3EnterContinuousTimeMode");
    p->mode = CONTINUOUS_TIME;
    return fmi3OK;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    ENTER(instance, CONTINUOUS_TIME, "fmi3CompletedIntegratorStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    if (enterEventMode == NULL || terminateSimulation == NULL) return fail(p, "fmi3CompletedIntegratorStep: NULL argument");
    *enterEventMode = *terminateSimulation = fmi3False;
    return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    ENTER(instance, EVENT_MODE | CONTINUOUS_TIME, "fmi3SetTime");
    if (!isfinite(time)) return fail(p, "fmi3SetTime: time must be finite, got %g", time);
    p->v[0] = time;
    return fmi3OK;
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 x[], size_t n) {
    ENTER(instance, CONTINUOUS_TIME | EVENT_MODE, "fmi3SetContinuousStates");
    if (n != (size_t)NX) return fail(p, "fmi3SetContinuousStates: nx must be %d, got %zu", NX, n);
    REQUIRE_VALUES(x, n, "fmi3SetContinuousStates");
    if (!finite_all(x, n)) return fail(p, "fmi3SetContinuousStates: states must be finite");
    memcpy(X(p), x, n * sizeof(double));
    p->derived_valid = 0;
    if (!plant_model.linear) p->jacobians_valid = 0;
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[], size_t n) {
    ENTER(instance, ANY_MODE & ~INSTANTIATED, "fmi3GetContinuousStateDerivatives");
    if (n != (size_t)NX) return fail(p, "fmi3GetContinuousStateDerivatives: nx must be %d, got %zu", NX, n);
    REQUIRE_VALUES(derivatives, n, "fmi3GetContinuousStateDerivatives");
    if (p->mode != ERROR_STATE && derive(p, "fmi3GetContinuousStateDerivatives") != fmi3OK) return fmi3Error;
    memcpy(derivatives, DX(p), n * sizeof(double));
    return fmi3OK;
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 indicators[], size_t n) {
    ENTER(instance, ANY_MODE, "fmi3GetEventIndicators");
    (void)indicators;
    return n == 0 ? fmi3OK : fail(p, "fmi3GetEventIndicators: the plant has no event indicators, got n = %zu", n);
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t n) {
    ENTER(instance, ANY_MODE & ~INSTANTIATED, "fmi3GetContinuousStates");
    if (n != (size_t)NX) return fail(p, "fmi3GetContinuousStates: nx must be %d, got %zu", NX, n);
    REQUIRE_VALUES(x, n, "fmi3GetContinuousStates");
    memcpy(x, X(p), n * sizeof(double));
    return fmi3OK;
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[], size_t n) {
    ENTER(instance, ANY_MODE, "fmi3GetNominalsOfContinuousStates");
    if (n != (size_t)NX) return fail(p, "fmi3GetNominalsOfContinuousStates: nx must be %d, got %zu", NX, n);
    REQUIRE_VALUES(nominals, n, "fmi3GetNominalsOfContinuousStates");
    memcpy(nominals, plant_model.state_nominal, n * sizeof(double));
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n) {
    ENTER(instance, ANY_MODE, "fmi3GetNumberOfEventIndicators");
    if (n == NULL) return fail(p, "fmi3GetNumberOfEventIndicators: NULL argument");
    *n = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *n) {
    ENTER(instance, ANY_MODE, "fmi3GetNumberOfContinuousStates");
    if (n == NULL) return fail(p, "fmi3GetNumberOfContinuousStates: NULL argument");
    *n = (size_t)NX;
    return fmi3OK;
}

/* ------------------------------------------------------------------ Co-Simulation */

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    ENTER(instance, EVENT_MODE | STEP_MODE, "fmi3EnterStepMode");
    if (p->model_exchange) return fail(p, "fmi3EnterStepMode: only for Co-Simulation instances");
    p->mode = STEP_MODE;
    return fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean *eventHandlingNeeded,
                      fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    ENTER(instance, STEP_MODE, "fmi3DoStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    const double h = communicationStepSize, t = p->v[0];
    if (!eventHandlingNeeded || !terminateSimulation || !earlyReturn || !lastSuccessfulTime)
        return fail(p, "fmi3DoStep: NULL output argument");
    *eventHandlingNeeded = *terminateSimulation = *earlyReturn = fmi3False;
    *lastSuccessfulTime = t;
    if (p->model_exchange) return fail(p, "fmi3DoStep: only for Co-Simulation instances");
    if (!isfinite(h) || h < 0.0) return fail(p, "fmi3DoStep: communicationStepSize must be finite and >= 0, got %g", h);
    if (!isfinite(currentCommunicationPoint) || fabs(currentCommunicationPoint - t) > 1e-9 * fmax(1.0, fabs(t)))
        return fail(p, "fmi3DoStep: currentCommunicationPoint %.17g is not the FMU's time %.17g", currentCommunicationPoint, t);
    if (h == 0.0) return fmi3OK;
    if ((plant_model.linear ? zoh_step(p, h, "fmi3DoStep") : rk4_step(p, h, "fmi3DoStep")) != fmi3OK) return fmi3Error;
    p->v[0] = currentCommunicationPoint + h;
    *lastSuccessfulTime = p->v[0];
    p->derived_valid = 0;
    if (!plant_model.linear) p->jacobians_valid = 0;
    return derive(p, "fmi3DoStep");
}
