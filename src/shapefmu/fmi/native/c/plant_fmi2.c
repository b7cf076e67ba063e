/* Generic FMI 2.0 Model Exchange + Co-Simulation wrapper for the plants of shapefmu.
 *
 * Written once, shared by every generated plant (as src/fmi2Functions.c is shared by the FMI
 * Reference FMUs); the plant itself is the model part declared in plant_model.h. This file owns:
 * instantiation with the host's memory callbacks, the FMI 2.0 state machine (FMI 2.0.x standard,
 * sections 3.2.3 and 4.2.4), get/set of Real, Integer, Boolean and String variables with the
 * causality and variability rules, FMU state get/set/serialise, directional derivatives, the
 * Co-Simulation step (exact zero-order hold for linear plants, fixed-substep RK4 otherwise) and
 * the logging of every error through the host's logger.
 *
 * Any refused call (bad argument, call out of order, non-finite value) logs a message naming the
 * function, the variable and the value, returns fmi2Error and puts the instance into the error
 * state, from which only getters, fmi2SetFMUstate, fmi2Reset and fmi2FreeInstance are accepted.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "fmi2Functions.h"
#include "plant_expm.h"
#include "plant_model.h"

typedef enum {
    INSTANTIATED = 1 << 0,
    INITIALIZATION = 1 << 1,
    EVENT_MODE = 1 << 2,
    CONTINUOUS_TIME = 1 << 3,
    STEP_COMPLETE = 1 << 4,
    TERMINATED = 1 << 5,
    ERROR_STATE = 1 << 6
} Mode;

#define ANY_MODE (INSTANTIATED | INITIALIZATION | EVENT_MODE | CONTINUOUS_TIME | STEP_COMPLETE | TERMINATED | ERROR_STATE)
#define AFTER_INSTANTIATION (ANY_MODE & ~INSTANTIATED)
#define RUNNING (EVENT_MODE | CONTINUOUS_TIME | STEP_COMPLETE)

typedef enum { TIME, STATE, DERIVATIVE, INPUT, OUTPUT, PARAMETER, NO_VARIABLE } Role;

/* What an FMU state snapshot holds besides the Real values: enough to resume exactly. */
typedef struct {
    Mode mode;
    double *values;
} Snapshot;

#define SERIAL_MAGIC 0x706c616e74463032ULL /* "plantF02" */

typedef struct {
    fmi2Type type;
    Mode mode;
    char *name;
    fmi2CallbackFunctions callbacks;
    fmi2Boolean logging_on;
    size_t n_values;           /* 1 + 2 nx + nu + ny + np */
    double *values;            /* every Real variable, indexed by value reference */
    int derived_valid;         /* derivatives and outputs are those of the current x, u, p */
    int jacobians_valid;       /* A, B, C, D are those of the current p (linear) or x, u, p */
    double *A, *B, *C, *D;
    double *work;              /* scratch of the generated CasADi functions */
    /* exact zero-order hold of linear plants: Phi, Gamma for step zoh_step, cached */
    int zoh_valid;
    double zoh_step;
    double *augmented, *exponential, *Phi, *Gamma, *expm_work;
    int *expm_iwork;
    /* RK4 stages of nonlinear plants */
    double *k1, *k2, *k3, *k4, *x_stage, *x_next;
} Instance;

/* ---------------------------------------------------------------- layout and logging */

static int nx(void) { return plant_model.n_states; }
static int nu(void) { return plant_model.n_inputs; }
static int ny(void) { return plant_model.n_outputs; }
static int np(void) { return plant_model.n_parameters; }
static size_t off_state(void) { return 1; }
static size_t off_derivative(void) { return 1 + (size_t)nx(); }
static size_t off_input(void) { return 1 + 2 * (size_t)nx(); }
static size_t off_output(void) { return off_input() + (size_t)nu(); }
static size_t off_parameter(void) { return off_output() + (size_t)ny(); }

static Role role_of(const Instance *inst, fmi2ValueReference vr, int *index) {
    if (vr >= inst->n_values) return NO_VARIABLE;
    if (vr == 0) { *index = 0; return TIME; }
    if (vr < off_derivative()) { *index = (int)(vr - off_state()); return STATE; }
    if (vr < off_input()) { *index = (int)(vr - off_derivative()); return DERIVATIVE; }
    if (vr < off_output()) { *index = (int)(vr - off_input()); return INPUT; }
    if (vr < off_parameter()) { *index = (int)(vr - off_output()); return OUTPUT; }
    *index = (int)(vr - off_parameter());
    return PARAMETER;
}

static const char *variable_name(const Instance *inst, fmi2ValueReference vr) {
    int i;
    switch (role_of(inst, vr, &i)) {
    case TIME: return "time";
    case STATE: return plant_model.state_names[i];
    case DERIVATIVE: return "a state derivative";
    case INPUT: return plant_model.input_names[i];
    case OUTPUT: return plant_model.output_names[i];
    case PARAMETER: return plant_model.parameters[i].name;
    default: return "(no variable)";
    }
}

static const char *mode_name(Mode mode) {
    switch (mode) {
    case INSTANTIATED: return "Instantiated";
    case INITIALIZATION: return "Initialization Mode";
    case EVENT_MODE: return "Event Mode";
    case CONTINUOUS_TIME: return "Continuous-Time Mode";
    case STEP_COMPLETE: return "Step Complete";
    case TERMINATED: return "Terminated";
    default: return "Error";
    }
}

static void log_message(const Instance *inst, fmi2Status status, const char *category, const char *format, va_list args) {
    if (inst->callbacks.logger == NULL) return;
    char message[512];
    vsnprintf(message, sizeof message, format, args);
    /* The logger takes a printf-style format: pass the message as an argument, never as format. */
    inst->callbacks.logger(inst->callbacks.componentEnvironment, inst->name, status, category, "%s", message);
}

/* Log an error (always: an error is never debug output), enter the error state, return fmi2Error. */
static fmi2Status fail(Instance *inst, const char *format, ...) {
    va_list args;
    va_start(args, format);
    log_message(inst, fmi2Error, "logStatusError", format, args);
    va_end(args);
    inst->mode = ERROR_STATE;
    return fmi2Error;
}

static void debug(const Instance *inst, const char *format, ...) {
    if (!inst->logging_on) return;
    va_list args;
    va_start(args, format);
    log_message(inst, fmi2OK, "logAll", format, args);
    va_end(args);
}

/* Guard of every entry point: a live instance in one of the allowed modes. */
#define REQUIRE(instance, allowed, function)                                                        \
    Instance *inst = (Instance *)(instance);                                                        \
    if (inst == NULL) return fmi2Error;                                                             \
    if (!(inst->mode & (allowed)))                                                                  \
        return fail(inst, "%s: not allowed in %s", function, mode_name(inst->mode));                \
    debug(inst, "%s", function)

#define REQUIRE_ARRAY(pointer, count, function)                                                     \
    if ((count) > 0 && (pointer) == NULL) return fail(inst, "%s: NULL array for %zu values", function, (size_t)(count))

/* ---------------------------------------------------------------- numerics */

static double *x_of(Instance *inst) { return inst->values + off_state(); }
static double *u_of(Instance *inst) { return inst->values + off_input(); }
static double *p_of(Instance *inst) { return inst->values + off_parameter(); }

static int all_finite(const double *v, size_t n) {
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i])) return 0;
    return 1;
}

static void invalidate(Instance *inst) {
    inst->derived_valid = 0;
    inst->jacobians_valid = 0;
    inst->zoh_valid = 0;
}

static fmi2Status update_derived(Instance *inst, const char *function) {
    if (inst->derived_valid) return fmi2OK;
    double *dx = inst->values + off_derivative(), *y = inst->values + off_output();
    if (plant_derivatives_outputs(x_of(inst), u_of(inst), p_of(inst), dx, y, inst->work) != 0
        || !all_finite(dx, (size_t)nx()) || !all_finite(y, (size_t)ny()))
        return fail(inst, "%s: the model gives non-finite derivatives or outputs at time %g", function, inst->values[0]);
    inst->derived_valid = 1;
    return fmi2OK;
}

static fmi2Status update_jacobians(Instance *inst, const char *function) {
    if (inst->jacobians_valid) return fmi2OK;
    const size_t n = (size_t)nx(), m = (size_t)nu(), p = (size_t)ny();
    if (plant_jacobians(x_of(inst), u_of(inst), p_of(inst), inst->A, inst->B, inst->C, inst->D, inst->work) != 0
        || !all_finite(inst->A, n * n) || !all_finite(inst->B, n * m) || !all_finite(inst->C, p * n)
        || !all_finite(inst->D, p * m))
        return fail(inst, "%s: the parameters give a non-finite Jacobian (state-space matrices)", function);
    /* A linear plant's Jacobians depend on p only: valid until a parameter changes. */
    inst->jacobians_valid = plant_model.linear;
    return fmi2OK;
}

/* Phi = e^{A h}, Gamma = int_0^h e^{A s} ds B from expm([[A, B], [0, 0]] h) = [[Phi, Gamma], [0, I]]
 * (Van Loan, IEEE TAC 23(3), 1978): the exact zero-order-hold discretisation. */
static fmi2Status update_zoh(Instance *inst, double h, const char *function) {
    if (inst->zoh_valid && inst->zoh_step == h) return fmi2OK;
    if (update_jacobians(inst, function) != fmi2OK) return fmi2Error;
    const int n = nx(), m = nu(), k = n + m;
    double *M = inst->augmented;
    memset(M, 0, (size_t)k * (size_t)k * sizeof(double));
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) M[(size_t)j * k + i] = inst->A[(size_t)j * n + i] * h;
    for (int j = 0; j < m; j++)
        for (int i = 0; i < n; i++) M[(size_t)(n + j) * k + i] = inst->B[(size_t)j * n + i] * h;
    if (plant_expm(k, M, inst->exponential, inst->expm_work, inst->expm_iwork) != 0)
        return fail(inst, "%s: the matrix exponential for step %g failed", function, h);
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) inst->Phi[(size_t)j * n + i] = inst->exponential[(size_t)j * k + i];
    for (int j = 0; j < m; j++)
        for (int i = 0; i < n; i++) inst->Gamma[(size_t)j * n + i] = inst->exponential[(size_t)(n + j) * k + i];
    inst->zoh_step = h;
    inst->zoh_valid = 1;
    debug(inst, "%s: zero-order-hold matrices computed for step %g", function, h);
    return fmi2OK;
}

static fmi2Status step_zoh(Instance *inst, double h, const char *function) {
    if (update_zoh(inst, h, function) != fmi2OK) return fmi2Error;
    const int n = nx(), m = nu();
    double *x = x_of(inst), *next = inst->x_next;
    const double *u = u_of(inst);
    for (int i = 0; i < n; i++) {
        double s = 0.0;
        for (int j = 0; j < n; j++) s += inst->Phi[(size_t)j * n + i] * x[j];
        for (int j = 0; j < m; j++) s += inst->Gamma[(size_t)j * n + i] * u[j];
        next[i] = s;
    }
    memcpy(x, next, (size_t)n * sizeof(double));
    return fmi2OK;
}

static int rhs(Instance *inst, const double *x, double *dx) {
    /* Outputs are not needed inside a stage: write them to the output slots, recomputed later. */
    return plant_derivatives_outputs(x, u_of(inst), p_of(inst), dx, inst->values + off_output(), inst->work);
}

/* Classic fourth-order Runge-Kutta with the input held over the step, in equal substeps no longer
 * than the substep parameter. */
static fmi2Status step_rk4(Instance *inst, double h, const char *function) {
    const int n = nx();
    const double substep = p_of(inst)[plant_model.substep_parameter];
    const double count = ceil(h / substep * (1.0 - 1e-12));
    const long substeps = count < 1.0 ? 1 : (long)count;
    const double dt = h / (double)substeps;
    double *x = x_of(inst);
    for (long s = 0; s < substeps; s++) {
        int status = rhs(inst, x, inst->k1);
        for (int i = 0; i < n; i++) inst->x_stage[i] = x[i] + 0.5 * dt * inst->k1[i];
        status |= rhs(inst, inst->x_stage, inst->k2);
        for (int i = 0; i < n; i++) inst->x_stage[i] = x[i] + 0.5 * dt * inst->k2[i];
        status |= rhs(inst, inst->x_stage, inst->k3);
        for (int i = 0; i < n; i++) inst->x_stage[i] = x[i] + dt * inst->k3[i];
        status |= rhs(inst, inst->x_stage, inst->k4);
        for (int i = 0; i < n; i++)
            inst->x_next[i] = x[i] + dt / 6.0 * (inst->k1[i] + 2.0 * inst->k2[i] + 2.0 * inst->k3[i] + inst->k4[i]);
        if (status != 0 || !all_finite(inst->x_next, (size_t)n))
            return fail(inst, "%s: the state became non-finite in the substep at time %g", function,
                        inst->values[0] + (double)s * dt);
        memcpy(x, inst->x_next, (size_t)n * sizeof(double));
    }
    return fmi2OK;
}

/* ---------------------------------------------------------------- value checks */

static fmi2Status check_parameter(Instance *inst, int i, double value, const char *function) {
    const PlantParameter *parameter = &plant_model.parameters[i];
    const char *range = NULL;
    switch (parameter->constraint) {
    case PLANT_ANY: if (!isfinite(value)) range = "a finite number"; break;
    case PLANT_POSITIVE: if (!(isfinite(value) && value > 0.0)) range = "> 0"; break;
    case PLANT_NONNEGATIVE: if (!(isfinite(value) && value >= 0.0)) range = ">= 0"; break;
    case PLANT_NONZERO: if (!(isfinite(value) && value != 0.0)) range = "finite and != 0"; break;
    case PLANT_DAMPING_RATIO: if (!(isfinite(value) && value >= 0.0 && value < 1.0)) range = "in [0, 1)"; break;
    }
    if (range != NULL) return fail(inst, "%s: parameter %s must be %s, got %g", function, parameter->name, range, value);
    return fmi2OK;
}

/* Whether variable vr may be set now (FMI 2.0, Table in 3.2.3 for ME, 4.2.4 for CS). */
static fmi2Status check_settable(Instance *inst, fmi2ValueReference vr, const char *function) {
    int i;
    const Role role = role_of(inst, vr, &i);
    const char *name = variable_name(inst, vr);
    switch (role) {
    case NO_VARIABLE:
        return fail(inst, "%s: no Real variable has value reference %u", function, (unsigned)vr);
    case TIME: case DERIVATIVE: case OUTPUT:
        return fail(inst, "%s: %s is computed by the FMU and cannot be set", function, name);
    case STATE:
        if (inst->mode & (INSTANTIATED | INITIALIZATION)) return fmi2OK;
        return fail(inst, "%s: state %s can be set only before initialisation is complete "
                    "(use fmi2SetContinuousStates or an FMU state), not in %s", function, name, mode_name(inst->mode));
    case INPUT:
        return fmi2OK;
    case PARAMETER: {
        if (inst->mode & (INSTANTIATED | INITIALIZATION)) return fmi2OK;
        if (!plant_model.parameters[i].tunable)
            return fail(inst, "%s: parameter %s is fixed and cannot be set after initialisation (in %s)",
                        function, name, mode_name(inst->mode));
        if (inst->mode & (EVENT_MODE | STEP_COMPLETE)) return fmi2OK;
        return fail(inst, "%s: tunable parameter %s can be set only in Event Mode or between steps, not in %s",
                    function, name, mode_name(inst->mode));
    }
    }
    return fmi2Error;
}

/* ---------------------------------------------------------------- life cycle */

static void *allocate(const fmi2CallbackFunctions *callbacks, size_t count, size_t size) {
    return count == 0 ? NULL : callbacks->allocateMemory(count, size);
}

static void release(Instance *inst, void *pointer) {
    if (pointer != NULL) inst->callbacks.freeMemory(pointer);
}

static void free_instance(Instance *inst) {
    void *buffers[] = {inst->name, inst->values, inst->A, inst->B, inst->C, inst->D, inst->work,
                       inst->augmented, inst->exponential, inst->Phi, inst->Gamma, inst->expm_work,
                       inst->expm_iwork, inst->k1, inst->k2, inst->k3, inst->k4, inst->x_stage, inst->x_next};
    for (size_t i = 0; i < sizeof buffers / sizeof buffers[0]; i++) release(inst, buffers[i]);
    inst->callbacks.freeMemory(inst);
}

static void set_start_values(Instance *inst) {
    memset(inst->values, 0, inst->n_values * sizeof(double));
    memcpy(x_of(inst), plant_model.state_start, (size_t)nx() * sizeof(double));
    memcpy(u_of(inst), plant_model.input_start, (size_t)nu() * sizeof(double));
    for (int i = 0; i < np(); i++) p_of(inst)[i] = plant_model.parameters[i].start;
    invalidate(inst);
}

static void log_instantiation_error(const fmi2CallbackFunctions *callbacks, fmi2String name, const char *message) {
    if (callbacks != NULL && callbacks->logger != NULL)
        callbacks->logger(callbacks->componentEnvironment, name != NULL ? name : "?", fmi2Error, "logStatusError",
                          "fmi2Instantiate: %s", message);
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)fmuResourceLocation;
    (void)visible;
    if (functions == NULL || functions->allocateMemory == NULL || functions->freeMemory == NULL) {
        log_instantiation_error(functions, instanceName, "the callbacks allocateMemory and freeMemory are required");
        return NULL;
    }
    if (instanceName == NULL || instanceName[0] == '\0') {
        log_instantiation_error(functions, instanceName, "instanceName must be a non-empty string");
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, plant_model.guid) != 0) {
        log_instantiation_error(functions, instanceName, "fmuGUID does not match the GUID of this FMU's modelDescription.xml");
        return NULL;
    }
    if (fmuType != fmi2ModelExchange && fmuType != fmi2CoSimulation) {
        log_instantiation_error(functions, instanceName, "fmuType must be fmi2ModelExchange or fmi2CoSimulation");
        return NULL;
    }
    Instance *inst = allocate(functions, 1, sizeof(Instance));
    if (inst == NULL) return NULL;
    memset(inst, 0, sizeof *inst);
    inst->callbacks = *functions;
    inst->type = fmuType;
    inst->logging_on = loggingOn;
    inst->mode = INSTANTIATED;
    const size_t n = (size_t)nx(), m = (size_t)nu(), p = (size_t)ny(), k = n + m;
    inst->n_values = 1 + 2 * n + m + p + (size_t)np();
    inst->name = allocate(functions, strlen(instanceName) + 1, 1);
    inst->values = allocate(functions, inst->n_values, sizeof(double));
    inst->A = allocate(functions, n * n, sizeof(double));
    inst->B = allocate(functions, n * m, sizeof(double));
    inst->C = allocate(functions, p * n, sizeof(double));
    inst->D = allocate(functions, p * m, sizeof(double));
    inst->work = allocate(functions, plant_model.work_size + 1, sizeof(double));
    inst->x_next = allocate(functions, n, sizeof(double));
    int complete = inst->name && inst->values && inst->A && inst->B && inst->C && inst->D && inst->work && inst->x_next;
    if (plant_model.linear) {
        inst->augmented = allocate(functions, k * k, sizeof(double));
        inst->exponential = allocate(functions, k * k, sizeof(double));
        inst->Phi = allocate(functions, n * n, sizeof(double));
        inst->Gamma = allocate(functions, n * m, sizeof(double));
        inst->expm_work = allocate(functions, PLANT_EXPM_WORK(k), sizeof(double));
        inst->expm_iwork = allocate(functions, PLANT_EXPM_IWORK(k), sizeof(int));
        complete = complete && inst->augmented && inst->exponential && inst->Phi && inst->Gamma && inst->expm_work
                   && inst->expm_iwork;
    } else {
        inst->k1 = allocate(functions, n, sizeof(double));
        inst->k2 = allocate(functions, n, sizeof(double));
        inst->k3 = allocate(functions, n, sizeof(double));
        inst->k4 = allocate(functions, n, sizeof(double));
        inst->x_stage = allocate(functions, n, sizeof(double));
        complete = complete && inst->k1 && inst->k2 && inst->k3 && inst->k4 && inst->x_stage;
    }
    if (!complete) {
        log_instantiation_error(functions, instanceName, "out of memory");
        free_instance(inst);
        return NULL;
    }
    strcpy(inst->name, instanceName);
    set_start_values(inst);
    debug(inst, "fmi2Instantiate: %d states, %d inputs, %d outputs, %d parameters", nx(), nu(), ny(), np());
    return inst;
}

void fmi2FreeInstance(fmi2Component c) {
    if (c != NULL) free_instance((Instance *)c);
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories, const fmi2String categories[]) {
    REQUIRE(c, ANY_MODE, "fmi2SetDebugLogging");
    REQUIRE_ARRAY(categories, nCategories, "fmi2SetDebugLogging");
    for (size_t i = 0; i < nCategories; i++)
        if (categories[i] == NULL || (strcmp(categories[i], "logAll") != 0 && strcmp(categories[i], "logStatusError") != 0))
            return fail(inst, "fmi2SetDebugLogging: unknown log category %s (known: logAll, logStatusError)",
                        categories[i] == NULL ? "NULL" : categories[i]);
    inst->logging_on = loggingOn;
    return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    REQUIRE(c, INSTANTIATED, "fmi2SetupExperiment");
    (void)toleranceDefined;
    (void)tolerance;
    if (!isfinite(startTime)) return fail(inst, "fmi2SetupExperiment: startTime must be finite, got %g", startTime);
    if (stopTimeDefined && !(stopTime >= startTime))
        return fail(inst, "fmi2SetupExperiment: stopTime must be >= startTime = %g, got %g", startTime, stopTime);
    inst->values[0] = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    REQUIRE(c, INSTANTIATED, "fmi2EnterInitializationMode");
    inst->mode = INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    REQUIRE(c, INITIALIZATION, "fmi2ExitInitializationMode");
    if (update_jacobians(inst, "fmi2ExitInitializationMode") != fmi2OK) return fmi2Error;
    if (update_derived(inst, "fmi2ExitInitializationMode") != fmi2OK) return fmi2Error;
    inst->mode = inst->type == fmi2ModelExchange ? EVENT_MODE : STEP_COMPLETE;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    REQUIRE(c, RUNNING, "fmi2Terminate");
    inst->mode = TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    REQUIRE(c, ANY_MODE, "fmi2Reset");
    set_start_values(inst);
    inst->mode = INSTANTIATED;
    return fmi2OK;
}

/* ---------------------------------------------------------------- get / set */

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    REQUIRE(c, AFTER_INSTANTIATION, "fmi2GetReal");
    REQUIRE_ARRAY(vr, nvr, "fmi2GetReal");
    REQUIRE_ARRAY(value, nvr, "fmi2GetReal");
    for (size_t i = 0; i < nvr; i++)
        if (vr[i] >= inst->n_values)
            return fail(inst, "fmi2GetReal: no Real variable has value reference %u", (unsigned)vr[i]);
    if (inst->mode != ERROR_STATE && update_derived(inst, "fmi2GetReal") != fmi2OK) return fmi2Error;
    for (size_t i = 0; i < nvr; i++) value[i] = inst->values[vr[i]];
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    REQUIRE(c, INSTANTIATED | INITIALIZATION | RUNNING, "fmi2SetReal");
    REQUIRE_ARRAY(vr, nvr, "fmi2SetReal");
    REQUIRE_ARRAY(value, nvr, "fmi2SetReal");
    /* Check every value first, so that a refused call changes nothing. */
    for (size_t i = 0; i < nvr; i++) {
        if (check_settable(inst, vr[i], "fmi2SetReal") != fmi2OK) return fmi2Error;
        int index;
        const Role role = role_of(inst, vr[i], &index);
        if (role == PARAMETER) {
            if (check_parameter(inst, index, value[i], "fmi2SetReal") != fmi2OK) return fmi2Error;
        } else if (!isfinite(value[i])) {
            return fail(inst, "fmi2SetReal: %s must be finite, got %g", variable_name(inst, vr[i]), value[i]);
        }
    }
    for (size_t i = 0; i < nvr; i++) {
        int index;
        const Role role = role_of(inst, vr[i], &index);
        if (inst->values[vr[i]] == value[i]) continue;
        inst->values[vr[i]] = value[i];
        inst->derived_valid = 0;
        if (role == PARAMETER) invalidate(inst);
        else if (!plant_model.linear) inst->jacobians_valid = 0;
    }
    return fmi2OK;
}

static fmi2Status no_variables(Instance *inst, const fmi2ValueReference vr[], size_t nvr, const char *function,
                               const char *type) {
    REQUIRE_ARRAY(vr, nvr, function);
    if (nvr > 0) return fail(inst, "%s: this FMU has no %s variables (value reference %u)", function, type, (unsigned)vr[0]);
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    REQUIRE(c, AFTER_INSTANTIATION, "fmi2GetInteger");
    (void)value;
    return no_variables(inst, vr, nvr, "fmi2GetInteger", "Integer");
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    REQUIRE(c, INSTANTIATED | INITIALIZATION | RUNNING, "fmi2SetInteger");
    (void)value;
    return no_variables(inst, vr, nvr, "fmi2SetInteger", "Integer");
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    REQUIRE(c, AFTER_INSTANTIATION, "fmi2GetBoolean");
    (void)value;
    return no_variables(inst, vr, nvr, "fmi2GetBoolean", "Boolean");
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    REQUIRE(c, INSTANTIATED | INITIALIZATION | RUNNING, "fmi2SetBoolean");
    (void)value;
    return no_variables(inst, vr, nvr, "fmi2SetBoolean", "Boolean");
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    REQUIRE(c, AFTER_INSTANTIATION, "fmi2GetString");
    (void)value;
    return no_variables(inst, vr, nvr, "fmi2GetString", "String");
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    REQUIRE(c, INSTANTIATED | INITIALIZATION | RUNNING, "fmi2SetString");
    (void)value;
    return no_variables(inst, vr, nvr, "fmi2SetString", "String");
}

/* ---------------------------------------------------------------- FMU state */

static Snapshot *new_snapshot(Instance *inst) {
    Snapshot *s = allocate(&inst->callbacks, 1, sizeof(Snapshot));
    if (s == NULL) return NULL;
    s->values = allocate(&inst->callbacks, inst->n_values, sizeof(double));
    if (s->values == NULL) {
        inst->callbacks.freeMemory(s);
        return NULL;
    }
    return s;
}

static void restore(Instance *inst, Mode mode, const double *values) {
    memcpy(inst->values, values, inst->n_values * sizeof(double));
    inst->mode = mode;
    invalidate(inst);
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    REQUIRE(c, ANY_MODE & ~ERROR_STATE, "fmi2GetFMUstate");
    REQUIRE_ARRAY(FMUstate, 1, "fmi2GetFMUstate");
    Snapshot *s = *FMUstate;
    if (s == NULL && (s = new_snapshot(inst)) == NULL) return fail(inst, "fmi2GetFMUstate: out of memory");
    s->mode = inst->mode;
    memcpy(s->values, inst->values, inst->n_values * sizeof(double));
    *FMUstate = s;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    REQUIRE(c, ANY_MODE, "fmi2SetFMUstate");
    if (FMUstate == NULL) return fail(inst, "fmi2SetFMUstate: FMUstate is NULL");
    const Snapshot *s = FMUstate;
    restore(inst, s->mode, s->values);
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    REQUIRE(c, ANY_MODE, "fmi2FreeFMUstate");
    if (FMUstate == NULL || *FMUstate == NULL) return fmi2OK;
    Snapshot *s = *FMUstate;
    release(inst, s->values);
    inst->callbacks.freeMemory(s);
    *FMUstate = NULL;
    return fmi2OK;
}

/* Serialised layout: magic, n_values, mode (3 x uint64), then n_values doubles. */
static size_t serial_size(const Instance *inst) { return 3 * sizeof(unsigned long long) + inst->n_values * sizeof(double); }

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    REQUIRE(c, ANY_MODE, "fmi2SerializedFMUstateSize");
    if (FMUstate == NULL || size == NULL) return fail(inst, "fmi2SerializedFMUstateSize: NULL FMUstate or size");
    *size = serial_size(inst);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    REQUIRE(c, ANY_MODE, "fmi2SerializeFMUstate");
    if (FMUstate == NULL || serializedState == NULL) return fail(inst, "fmi2SerializeFMUstate: NULL FMUstate or buffer");
    if (size != serial_size(inst))
        return fail(inst, "fmi2SerializeFMUstate: buffer holds %zu bytes, the state needs %zu", size, serial_size(inst));
    const Snapshot *s = FMUstate;
    const unsigned long long header[3] = {SERIAL_MAGIC, inst->n_values, (unsigned long long)s->mode};
    memcpy(serializedState, header, sizeof header);
    memcpy(serializedState + sizeof header, s->values, inst->n_values * sizeof(double));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size, fmi2FMUstate *FMUstate) {
    REQUIRE(c, ANY_MODE, "fmi2DeSerializeFMUstate");
    if (serializedState == NULL || FMUstate == NULL) return fail(inst, "fmi2DeSerializeFMUstate: NULL buffer or FMUstate");
    unsigned long long header[3];
    if (size != serial_size(inst))
        return fail(inst, "fmi2DeSerializeFMUstate: got %zu bytes, a state of this FMU has %zu", size, serial_size(inst));
    memcpy(header, serializedState, sizeof header);
    if (header[0] != SERIAL_MAGIC || header[1] != inst->n_values || (header[2] & ~(unsigned long long)ANY_MODE) != 0
        || header[2] == 0)
        return fail(inst, "fmi2DeSerializeFMUstate: the bytes are not a serialised state of this FMU");
    Snapshot *s = *FMUstate;
    if (s == NULL && (s = new_snapshot(inst)) == NULL) return fail(inst, "fmi2DeSerializeFMUstate: out of memory");
    s->mode = (Mode)header[2];
    memcpy(s->values, serializedState + sizeof header, inst->n_values * sizeof(double));
    *FMUstate = s;
    return fmi2OK;
}

/* ---------------------------------------------------------------- directional derivatives */

/* d(unknown)/d(known) from the Jacobians: unknowns are derivatives or outputs, knowns states or inputs. */
static int jacobian_entry(Instance *inst, fmi2ValueReference unknown, fmi2ValueReference known, double *entry) {
    int r, k;
    const Role ru = role_of(inst, unknown, &r), rk = role_of(inst, known, &k);
    const int n = nx(), p = ny();
    if (ru == DERIVATIVE && rk == STATE) *entry = inst->A[(size_t)k * n + r];
    else if (ru == DERIVATIVE && rk == INPUT) *entry = inst->B[(size_t)k * n + r];
    else if (ru == OUTPUT && rk == STATE) *entry = inst->C[(size_t)k * p + r];
    else if (ru == OUTPUT && rk == INPUT) *entry = inst->D[(size_t)k * p + r];
    else return -1;
    return 0;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    REQUIRE(c, INITIALIZATION | RUNNING | TERMINATED, "fmi2GetDirectionalDerivative");
    REQUIRE_ARRAY(vUnknown_ref, nUnknown, "fmi2GetDirectionalDerivative");
    REQUIRE_ARRAY(dvUnknown, nUnknown, "fmi2GetDirectionalDerivative");
    REQUIRE_ARRAY(vKnown_ref, nKnown, "fmi2GetDirectionalDerivative");
    REQUIRE_ARRAY(dvKnown, nKnown, "fmi2GetDirectionalDerivative");
    if (update_jacobians(inst, "fmi2GetDirectionalDerivative") != fmi2OK) return fmi2Error;
    for (size_t i = 0; i < nUnknown; i++) {
        double sum = 0.0;
        for (size_t j = 0; j < nKnown; j++) {
            double entry;
            if (jacobian_entry(inst, vUnknown_ref[i], vKnown_ref[j], &entry) != 0)
                return fail(inst, "fmi2GetDirectionalDerivative: unknowns must be state derivatives or outputs and "
                            "knowns states or inputs, got %s with respect to %s",
                            variable_name(inst, vUnknown_ref[i]), variable_name(inst, vKnown_ref[j]));
            sum += entry * dvKnown[j];
        }
        dvUnknown[i] = sum;
    }
    return fmi2OK;
}

/* ---------------------------------------------------------------- Model Exchange */

#define REQUIRE_TYPE(wanted, function)                                                              \
    if (inst->type != (wanted))                                                                     \
    return fail(inst, "%s: only for %s instances", function,                                        \
                (wanted) == fmi2ModelExchange ? "Model Exchange" : "Co-Simulation")

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    REQUIRE(c, EVENT_MODE | CONTINUOUS_TIME, "fmi2EnterEventMode");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2EnterEventMode");
    inst->mode = EVENT_MODE;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *eventInfo) {
    REQUIRE(c, EVENT_MODE, "fmi2NewDiscreteStates");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2NewDiscreteStates");
    REQUIRE_ARRAY(eventInfo, 1, "fmi2NewDiscreteStates");
    /* The plants have no discrete states and no time events. */
    eventInfo->newDiscreteStatesNeeded = fmi2False;
    eventInfo->terminateSimulation = fmi2False;
    eventInfo->nominalsOfContinuousStatesChanged = fmi2False;
    eventInfo->valuesOfContinuousStatesChanged = fmi2False;
    eventInfo->nextEventTimeDefined = fmi2False;
    eventInfo->nextEventTime = 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    REQUIRE(c, EVENT_MODE, "fmi2EnterContinuousTimeMode");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2EnterContinuousTimeMode");
    inst->mode = CONTINUOUS_TIME;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    REQUIRE(c, CONTINUOUS_TIME, "fmi2CompletedIntegratorStep");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2CompletedIntegratorStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    if (enterEventMode == NULL || terminateSimulation == NULL)
        return fail(inst, "fmi2CompletedIntegratorStep: NULL enterEventMode or terminateSimulation");
    *enterEventMode = fmi2False;
    *terminateSimulation = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    REQUIRE(c, EVENT_MODE | CONTINUOUS_TIME, "fmi2SetTime");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2SetTime");
    if (!isfinite(time)) return fail(inst, "fmi2SetTime: time must be finite, got %g", time);
    inst->values[0] = time;
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t n) {
    REQUIRE(c, CONTINUOUS_TIME, "fmi2SetContinuousStates");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2SetContinuousStates");
    REQUIRE_ARRAY(x, n, "fmi2SetContinuousStates");
    if (n != (size_t)nx()) return fail(inst, "fmi2SetContinuousStates: nx must be %d, got %zu", nx(), n);
    for (size_t i = 0; i < n; i++)
        if (!isfinite(x[i]))
            return fail(inst, "fmi2SetContinuousStates: state %s must be finite, got %g", plant_model.state_names[i], x[i]);
    memcpy(x_of(inst), x, n * sizeof(double));
    inst->derived_valid = 0;
    if (!plant_model.linear) inst->jacobians_valid = 0;
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t n) {
    REQUIRE(c, AFTER_INSTANTIATION, "fmi2GetDerivatives");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2GetDerivatives");
    REQUIRE_ARRAY(derivatives, n, "fmi2GetDerivatives");
    if (n != (size_t)nx()) return fail(inst, "fmi2GetDerivatives: nx must be %d, got %zu", nx(), n);
    if (inst->mode != ERROR_STATE && update_derived(inst, "fmi2GetDerivatives") != fmi2OK) return fmi2Error;
    memcpy(derivatives, inst->values + off_derivative(), n * sizeof(double));
    return fmi2OK;
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    REQUIRE(c, AFTER_INSTANTIATION, "fmi2GetEventIndicators");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2GetEventIndicators");
    (void)eventIndicators;
    if (ni != 0) return fail(inst, "fmi2GetEventIndicators: the plant has no event indicators, got ni = %zu", ni);
    return fmi2OK;
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t n) {
    REQUIRE(c, AFTER_INSTANTIATION, "fmi2GetContinuousStates");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2GetContinuousStates");
    REQUIRE_ARRAY(x, n, "fmi2GetContinuousStates");
    if (n != (size_t)nx()) return fail(inst, "fmi2GetContinuousStates: nx must be %d, got %zu", nx(), n);
    memcpy(x, x_of(inst), n * sizeof(double));
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t n) {
    REQUIRE(c, ANY_MODE, "fmi2GetNominalsOfContinuousStates");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2GetNominalsOfContinuousStates");
    REQUIRE_ARRAY(x_nominal, n, "fmi2GetNominalsOfContinuousStates");
    if (n != (size_t)nx()) return fail(inst, "fmi2GetNominalsOfContinuousStates: nx must be %d, got %zu", nx(), n);
    memcpy(x_nominal, plant_model.state_nominal, n * sizeof(double));
    return fmi2OK;
}

/* ---------------------------------------------------------------- Co-Simulation */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    REQUIRE(c, ANY_MODE, "fmi2SetRealInputDerivatives");
    (void)vr; (void)order; (void)value;
    if (nvr == 0) return fmi2OK;
    return fail(inst, "fmi2SetRealInputDerivatives: the plant holds its inputs constant over a step "
                "(canInterpolateInputs=\"false\")");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    REQUIRE(c, ANY_MODE, "fmi2GetRealOutputDerivatives");
    (void)vr; (void)order; (void)value;
    if (nvr == 0) return fmi2OK;
    return fail(inst, "fmi2GetRealOutputDerivatives: the plant provides no output derivatives "
                "(maxOutputDerivativeOrder=\"0\")");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    REQUIRE(c, STEP_COMPLETE, "fmi2DoStep");
    REQUIRE_TYPE(fmi2CoSimulation, "fmi2DoStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    const double h = communicationStepSize, t = inst->values[0];
    if (!isfinite(h) || h < 0.0)
        return fail(inst, "fmi2DoStep: communicationStepSize must be finite and >= 0, got %g", h);
    if (!isfinite(currentCommunicationPoint) || fabs(currentCommunicationPoint - t) > 1e-9 * fmax(1.0, fabs(t)))
        return fail(inst, "fmi2DoStep: currentCommunicationPoint %.17g is not the FMU's time %.17g",
                    currentCommunicationPoint, t);
    if (h == 0.0) return fmi2OK;
    const fmi2Status status = plant_model.linear ? step_zoh(inst, h, "fmi2DoStep") : step_rk4(inst, h, "fmi2DoStep");
    if (status != fmi2OK) return status;
    inst->values[0] = currentCommunicationPoint + h;
    inst->derived_valid = 0;
    if (!plant_model.linear) inst->jacobians_valid = 0;
    return update_derived(inst, "fmi2DoStep");
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    REQUIRE(c, STEP_COMPLETE, "fmi2CancelStep");
    return fail(inst, "fmi2CancelStep: fmi2DoStep never returns fmi2Pending, so there is no step to cancel");
}

static fmi2Status no_status(fmi2Component c, fmi2StatusKind s, const char *function) {
    REQUIRE(c, ANY_MODE, function);
    return fail(inst, "%s: status kind %d is not provided (fmi2DoStep is synchronous)", function, (int)s);
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)value;
    return no_status(c, s, "fmi2GetStatus");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    (void)value;
    return no_status(c, s, "fmi2GetRealStatus");
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)value;
    return no_status(c, s, "fmi2GetIntegerStatus");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    REQUIRE(c, ANY_MODE, "fmi2GetBooleanStatus");
    if (value == NULL) return fail(inst, "fmi2GetBooleanStatus: value is NULL");
    if (s == fmi2Terminated) {
        /* Asked after fmi2Discard: this FMU never discards, and never asks to terminate. */
        *value = fmi2False;
        return fmi2OK;
    }
    return fail(inst, "fmi2GetBooleanStatus: status kind %d is not provided", (int)s);
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)value;
    return no_status(c, s, "fmi2GetStringStatus");
}
