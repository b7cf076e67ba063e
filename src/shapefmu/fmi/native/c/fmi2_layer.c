/* The generic FMI 2.0 layer of shapefmu's native FMUs: written once, shared by the plants and the
 * sampled filters (as src/fmi2Functions.c is shared by the FMI Reference FMUs). The model part is
 * whatever implements fmi2_model.h.
 *
 * This file: instantiation with the host's memory callbacks, logging, the life cycle of the FMI 2.0
 * state machine, get/set of Real, Integer, Boolean and String variables with the causality and
 * variability rules, and the Co-Simulation step. FMU states are in fmi2_layer_state.c, the Model
 * Exchange functions in fmi2_layer_me.c.
 *
 * Any refused call (bad argument, call out of order, a value the model refuses) logs a message
 * naming the function, the variable and the value, returns fmi2Error and puts the instance into
 * the error state, from which only getters, fmi2SetFMUstate, fmi2Reset and fmi2FreeInstance are
 * accepted (FMI 2.0, section 2.1.3).
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2_layer.h"

/* ---------------------------------------------------------------- services to the model part */

const char *fmi2_mode_name(Fmi2Mode mode) {
    switch (mode) {
    case FMI2_INSTANTIATED: return "Instantiated";
    case FMI2_INITIALIZATION: return "Initialization Mode";
    case FMI2_EVENT_MODE: return "Event Mode";
    case FMI2_CONTINUOUS_TIME: return "Continuous-Time Mode";
    case FMI2_STEP_COMPLETE: return "Step Complete";
    case FMI2_TERMINATED: return "Terminated";
    default: return "Error";
    }
}

static void log_message(const Fmi2Instance *inst, fmi2Status status, const char *category, const char *format,
                        va_list args) {
    if (inst->callbacks.logger == NULL) return;
    char message[512];
    vsnprintf(message, sizeof message, format, args);
    /* The logger takes a printf-style format: pass the message as an argument, never as format. */
    inst->callbacks.logger(inst->callbacks.componentEnvironment, inst->name, status, category, "%s", message);
}

fmi2Status fmi2_fail(Fmi2Instance *inst, const char *format, ...) {
    va_list args;
    va_start(args, format);
    log_message(inst, fmi2Error, "logStatusError", format, args); /* an error is never debug output */
    va_end(args);
    inst->mode = FMI2_ERROR_STATE;
    return fmi2Error;
}

void fmi2_debug(const Fmi2Instance *inst, const char *format, ...) {
    if (!inst->logging_on) return;
    va_list args;
    va_start(args, format);
    log_message(inst, fmi2OK, "logAll", format, args);
    va_end(args);
}

void *fmi2_allocate(Fmi2Instance *inst, size_t count, size_t size) {
    return count == 0 ? NULL : inst->callbacks.allocateMemory(count, size);
}

void fmi2_release(Fmi2Instance *inst, void *pointer) {
    if (pointer != NULL) inst->callbacks.freeMemory(pointer);
}

size_t fmi2_string_capacity(const Fmi2Instance *inst) { return inst->info.string_capacity; }

char *fmi2_string(Fmi2Instance *inst, size_t vr) {
    const size_t first = inst->info.n_real + inst->info.n_integer + inst->info.n_boolean;
    return inst->strings + (vr - first) * (inst->info.string_capacity + 1);
}

/* ---------------------------------------------------------------- life cycle */

/* Everything an instance holds but its struct (malloc'ed by the layer, released or retired apart). */
static void free_buffers(Fmi2Instance *inst) {
    model_free(inst);
    void *buffers[] = {inst->name, inst->reals, inst->integers, inst->booleans, inst->strings};
    for (size_t i = 0; i < sizeof buffers / sizeof buffers[0]; i++) fmi2_release(inst, buffers[i]);
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
    Fmi2ModelInfo info;
    model_describe(&info);
    if (functions == NULL || functions->allocateMemory == NULL || functions->freeMemory == NULL) {
        log_instantiation_error(functions, instanceName, "the callbacks allocateMemory and freeMemory are required");
        return NULL;
    }
    if (instanceName == NULL || instanceName[0] == '\0') {
        log_instantiation_error(functions, instanceName, "instanceName must be a non-empty string");
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, info.guid) != 0) {
        log_instantiation_error(functions, instanceName, "fmuGUID does not match the GUID of this FMU's modelDescription.xml");
        return NULL;
    }
    if (fmuType != fmi2CoSimulation && !(fmuType == fmi2ModelExchange && info.model_exchange)) {
        log_instantiation_error(functions, instanceName, info.model_exchange
                                ? "fmuType must be fmi2ModelExchange or fmi2CoSimulation"
                                : "fmuType must be fmi2CoSimulation (this FMU declares no Model Exchange)");
        return NULL;
    }
    /* The struct from malloc, not the host's allocator: it may be released after the host is gone
     * (fmu_retire), and its address must not come back soon as another instance's. */
    Fmi2Instance *inst = calloc(1, sizeof(Fmi2Instance));
    if (inst == NULL) return NULL;
    if (info.string_capacity == 0) info.string_capacity = FMI2_STRING_CAPACITY;
    inst->info = info;
    inst->callbacks = *functions;
    inst->type = fmuType;
    inst->logging_on = loggingOn;
    inst->mode = FMI2_INSTANTIATED;
    inst->name = fmi2_allocate(inst, strlen(instanceName) + 1, 1);
    inst->reals = fmi2_allocate(inst, info.n_real, sizeof(double));
    inst->integers = fmi2_allocate(inst, info.n_integer, sizeof(int));
    inst->booleans = fmi2_allocate(inst, info.n_boolean, sizeof(int));
    inst->strings = fmi2_allocate(inst, info.n_string, info.string_capacity + 1);
    if (inst->name == NULL || (info.n_real && !inst->reals) || (info.n_integer && !inst->integers)
        || (info.n_boolean && !inst->booleans) || (info.n_string && !inst->strings) || model_instantiate(inst) != 0) {
        log_instantiation_error(functions, instanceName, "out of memory");
        free_buffers(inst);
        free(inst);
        return NULL;
    }
    strcpy(inst->name, instanceName);
    fmu_mark_live(inst);
    fmi2_debug(inst, "fmi2Instantiate: %zu Real, %zu Integer, %zu Boolean, %zu String variables", info.n_real,
               info.n_integer, info.n_boolean, info.n_string);
    return inst;
}

void fmi2FreeInstance(fmi2Component c) {
    /* An instance freed already (or never made here) is not touched: see fmu_liveness.h. */
    if (!fmu_mark_freed(c)) return;
    free_buffers((Fmi2Instance *)c);
    fmu_retire(c);
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories, const fmi2String categories[]) {
    REQUIRE(c, ANY_MODE, "fmi2SetDebugLogging");
    REQUIRE_ARRAY(categories, nCategories, "fmi2SetDebugLogging");
    for (size_t i = 0; i < nCategories; i++)
        if (categories[i] == NULL || (strcmp(categories[i], "logAll") != 0 && strcmp(categories[i], "logStatusError") != 0))
            return fmi2_fail(inst, "fmi2SetDebugLogging: unknown log category %s (known: logAll, logStatusError)",
                             categories[i] == NULL ? "NULL" : categories[i]);
    inst->logging_on = loggingOn;
    return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    REQUIRE(c, FMI2_INSTANTIATED, "fmi2SetupExperiment");
    (void)toleranceDefined;
    (void)tolerance;
    if (!isfinite(startTime)) return fmi2_fail(inst, "fmi2SetupExperiment: startTime must be finite, got %g", startTime);
    if (stopTimeDefined && !(stopTime >= startTime))
        return fmi2_fail(inst, "fmi2SetupExperiment: stopTime must be >= startTime = %g, got %g", startTime, stopTime);
    inst->time = inst->start_time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    REQUIRE(c, FMI2_INSTANTIATED, "fmi2EnterInitializationMode");
    inst->mode = FMI2_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    REQUIRE(c, FMI2_INITIALIZATION, "fmi2ExitInitializationMode");
    if (model_exit_initialization(inst) != fmi2OK) return fmi2Error;
    inst->mode = inst->type == fmi2ModelExchange ? FMI2_EVENT_MODE : FMI2_STEP_COMPLETE;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    REQUIRE(c, RUNNING, "fmi2Terminate");
    inst->mode = FMI2_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    REQUIRE(c, ANY_MODE, "fmi2Reset");
    inst->time = inst->start_time = 0.0;
    model_reset(inst);
    inst->mode = FMI2_INSTANTIATED;
    return fmi2OK;
}

/* ---------------------------------------------------------------- get / set */

static const char *const TYPE_NAMES[] = {"Real", "Integer", "Boolean", "String"};

/* The value references [first, first + count) of a type. */
static void type_range(const Fmi2Instance *inst, Fmi2Type type, size_t *first, size_t *count) {
    const Fmi2ModelInfo *info = &inst->info;
    switch (type) {
    case FMI2_REAL: *first = 0, *count = info->n_real; return;
    case FMI2_INTEGER: *first = info->n_real, *count = info->n_integer; return;
    case FMI2_BOOLEAN: *first = info->n_real + info->n_integer, *count = info->n_boolean; return;
    default: *first = info->n_real + info->n_integer + info->n_boolean, *count = info->n_string; return;
    }
}

/* Every vr is a variable of type; logs the first that is not. */
static fmi2Status check_references(Fmi2Instance *inst, Fmi2Type type, const fmi2ValueReference vr[], size_t nvr,
                                   const char *function) {
    if (type == FMI2_REAL) { /* the usual call, first: Real value references start at 0 */
        size_t i = 0;
        while (i < nvr && vr[i] < inst->info.n_real) i++;
        if (i == nvr) return fmi2OK;
    }
    size_t first, count;
    type_range(inst, type, &first, &count);
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] >= first && vr[i] - first < count) continue;
        if (count == 0)
            return fmi2_fail(inst, "%s: this FMU has no %s variables (value reference %u)", function, TYPE_NAMES[type],
                             (unsigned)vr[i]);
        return fmi2_fail(inst, "%s: no %s variable has value reference %u", function, TYPE_NAMES[type], (unsigned)vr[i]);
    }
    return fmi2OK;
}

/* Whether variable vr may be set now (FMI 2.0, tables in 3.2.3 for ME and 4.2.4 for CS). */
static fmi2Status check_settable(Fmi2Instance *inst, Fmi2Type type, fmi2ValueReference vr, const char *function) {
    const char *name = "(no variable)";
    switch (model_variable(inst, type, vr, &name)) {
    case FMI2_NO_VARIABLE:
        return fmi2_fail(inst, "%s: no %s variable has value reference %u", function, TYPE_NAMES[type], (unsigned)vr);
    case FMI2_COMPUTED:
        return fmi2_fail(inst, "%s: %s is computed by the FMU and cannot be set", function, name);
    case FMI2_STATE:
        if (inst->mode & (FMI2_INSTANTIATED | FMI2_INITIALIZATION)) return fmi2OK;
        return fmi2_fail(inst, "%s: state %s can be set only before initialisation is complete "
                         "(use fmi2SetContinuousStates or an FMU state), not in %s", function, name,
                         fmi2_mode_name(inst->mode));
    case FMI2_INPUT:
        return fmi2OK;
    case FMI2_PARAMETER_FIXED:
        if (inst->mode & (FMI2_INSTANTIATED | FMI2_INITIALIZATION)) return fmi2OK;
        return fmi2_fail(inst, "%s: parameter %s is fixed and cannot be set after initialisation (in %s)", function,
                         name, fmi2_mode_name(inst->mode));
    case FMI2_PARAMETER_TUNABLE:
        if (inst->mode & (FMI2_INSTANTIATED | FMI2_INITIALIZATION | FMI2_EVENT_MODE | FMI2_STEP_COMPLETE)) return fmi2OK;
        return fmi2_fail(inst, "%s: tunable parameter %s can be set only in Event Mode or between steps, not in %s",
                         function, name, fmi2_mode_name(inst->mode));
    }
    return fmi2Error;
}

#define SET_PROLOGUE(type, function)                                                                \
    REQUIRE(c, FMI2_INSTANTIATED | FMI2_INITIALIZATION | RUNNING, function);                        \
    REQUIRE_ARRAY(vr, nvr, function);                                                               \
    REQUIRE_ARRAY(value, nvr, function);                                                            \
    if (check_references(inst, type, vr, nvr, function) != fmi2OK) return fmi2Error

#define GET_PROLOGUE(type, function)                                                                \
    REQUIRE(c, AFTER_INSTANTIATION, function);                                                      \
    REQUIRE_ARRAY(vr, nvr, function);                                                               \
    REQUIRE_ARRAY(value, nvr, function);                                                            \
    if (check_references(inst, type, vr, nvr, function) != fmi2OK) return fmi2Error;               \
    if (inst->mode != FMI2_ERROR_STATE && model_update(inst, function) != fmi2OK) return fmi2Error

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    GET_PROLOGUE(FMI2_REAL, "fmi2GetReal");
    for (size_t i = 0; i < nvr; i++) value[i] = inst->reals[vr[i]];
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    GET_PROLOGUE(FMI2_INTEGER, "fmi2GetInteger");
    for (size_t i = 0; i < nvr; i++) value[i] = inst->integers[vr[i] - inst->info.n_real];
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    GET_PROLOGUE(FMI2_BOOLEAN, "fmi2GetBoolean");
    for (size_t i = 0; i < nvr; i++) value[i] = inst->booleans[vr[i] - inst->info.n_real - inst->info.n_integer];
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    GET_PROLOGUE(FMI2_STRING, "fmi2GetString");
    for (size_t i = 0; i < nvr; i++) value[i] = fmi2_string(inst, vr[i]);
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    SET_PROLOGUE(FMI2_REAL, "fmi2SetReal");
    /* Check every value first, so that a refused call changes nothing. */
    for (size_t i = 0; i < nvr; i++)
        if (check_settable(inst, FMI2_REAL, vr[i], "fmi2SetReal") != fmi2OK
            || model_check_real(inst, vr[i], value[i], "fmi2SetReal") != fmi2OK)
            return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        if (inst->reals[vr[i]] == value[i]) continue;
        inst->reals[vr[i]] = value[i];
        model_changed(inst, vr[i]);
    }
    return fmi2OK;
}

static fmi2Status set_integers(Fmi2Instance *inst, Fmi2Type type, int *values, const fmi2ValueReference vr[],
                               size_t nvr, const fmi2Integer value[], const char *function) {
    size_t first, count;
    type_range(inst, type, &first, &count);
    for (size_t i = 0; i < nvr; i++) {
        const int v = type == FMI2_BOOLEAN ? value[i] != fmi2False : value[i];
        if (check_settable(inst, type, vr[i], function) != fmi2OK || model_check_integer(inst, vr[i], v, function) != fmi2OK)
            return fmi2Error;
    }
    for (size_t i = 0; i < nvr; i++) {
        const int v = type == FMI2_BOOLEAN ? value[i] != fmi2False : value[i];
        if (values[vr[i] - first] == v) continue;
        values[vr[i] - first] = v;
        model_changed(inst, vr[i]);
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    SET_PROLOGUE(FMI2_INTEGER, "fmi2SetInteger");
    return set_integers(inst, FMI2_INTEGER, inst->integers, vr, nvr, value, "fmi2SetInteger");
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    SET_PROLOGUE(FMI2_BOOLEAN, "fmi2SetBoolean");
    return set_integers(inst, FMI2_BOOLEAN, inst->booleans, vr, nvr, value, "fmi2SetBoolean");
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    SET_PROLOGUE(FMI2_STRING, "fmi2SetString");
    for (size_t i = 0; i < nvr; i++) {
        if (check_settable(inst, FMI2_STRING, vr[i], "fmi2SetString") != fmi2OK) return fmi2Error;
        if (value[i] == NULL) return fmi2_fail(inst, "fmi2SetString: value %zu is NULL", i);
        if (strlen(value[i]) > inst->info.string_capacity)
            return fmi2_fail(inst, "fmi2SetString: a value of %zu characters is longer than the %zu this FMU holds",
                             strlen(value[i]), inst->info.string_capacity);
        if (model_check_string(inst, vr[i], value[i], "fmi2SetString") != fmi2OK) return fmi2Error;
    }
    for (size_t i = 0; i < nvr; i++) {
        char *slot = fmi2_string(inst, vr[i]);
        if (strcmp(slot, value[i]) == 0) continue;
        strcpy(slot, value[i]);
        model_changed(inst, vr[i]);
    }
    return fmi2OK;
}

/* ---------------------------------------------------------------- Co-Simulation */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    REQUIRE(c, ANY_MODE, "fmi2SetRealInputDerivatives");
    (void)vr; (void)order; (void)value;
    if (nvr == 0) return fmi2OK;
    return fmi2_fail(inst, "fmi2SetRealInputDerivatives: the FMU holds its inputs constant over a step "
                     "(canInterpolateInputs=\"false\")");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    REQUIRE(c, ANY_MODE, "fmi2GetRealOutputDerivatives");
    (void)vr; (void)order; (void)value;
    if (nvr == 0) return fmi2OK;
    return fmi2_fail(inst, "fmi2GetRealOutputDerivatives: the FMU provides no output derivatives "
                     "(maxOutputDerivativeOrder=\"0\")");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    REQUIRE(c, FMI2_STEP_COMPLETE, "fmi2DoStep");
    REQUIRE_TYPE(fmi2CoSimulation, "fmi2DoStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    const double h = communicationStepSize, t = inst->time;
    if (!isfinite(h) || h < 0.0)
        return fmi2_fail(inst, "fmi2DoStep: communicationStepSize must be finite and >= 0, got %g", h);
    if (!isfinite(currentCommunicationPoint) || fabs(currentCommunicationPoint - t) > 1e-9 * fmax(1.0, fabs(t)))
        return fmi2_fail(inst, "fmi2DoStep: currentCommunicationPoint %.17g is not the FMU's time %.17g",
                         currentCommunicationPoint, t);
    if (h == 0.0) return fmi2OK;
    if (model_do_step(inst, currentCommunicationPoint, h) != fmi2OK) return fmi2Error;
    inst->time = currentCommunicationPoint + h;
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    REQUIRE(c, FMI2_STEP_COMPLETE, "fmi2CancelStep");
    return fmi2_fail(inst, "fmi2CancelStep: fmi2DoStep never returns fmi2Pending, so there is no step to cancel");
}

static fmi2Status no_status(fmi2Component c, fmi2StatusKind s, const char *function) {
    REQUIRE(c, ANY_MODE, function);
    return fmi2_fail(inst, "%s: status kind %d is not provided (fmi2DoStep is synchronous)", function, (int)s);
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
    if (value == NULL) return fmi2_fail(inst, "fmi2GetBooleanStatus: value is NULL");
    if (s == fmi2Terminated) {
        /* Asked after fmi2Discard: this FMU never discards, and never asks to terminate. */
        *value = fmi2False;
        return fmi2OK;
    }
    return fmi2_fail(inst, "fmi2GetBooleanStatus: status kind %d is not provided", (int)s);
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)value;
    return no_status(c, s, "fmi2GetStringStatus");
}
