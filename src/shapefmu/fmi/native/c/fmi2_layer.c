/* The generic FMI 2.0 layer of shapefmu's native FMUs: written once, shared by the plants and every
 * sampled FMU (as src/fmi2Functions.c is shared by the FMI Reference FMUs). The model part is
 * whatever implements model.h; what FMI 2.0 and 3.0 do alike is in layer_core.c and
 * layer_state.c, this is FMI 2.0's API over it.
 *
 * This file: instantiation with the host's memory callbacks and logger, the life cycle of the FMI
 * 2.0 state machine, get/set of Real, Integer, Boolean and String variables, and the Co-Simulation
 * step. FMU states and the Model Exchange functions are in fmi2_layer_me.c.
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

/* ---------------------------------------------------------------- life cycle */

/* What an FMI 2.0 instance keeps of its host: the callbacks (logger, allocator). */
static void emit(const ModelInstance *inst, int error, const char *category, const char *message) {
    const fmi2CallbackFunctions *callbacks = inst->layer;
    if (callbacks->logger == NULL) return;
    /* The logger takes a printf-style format: pass the message as an argument, never as format. */
    callbacks->logger(callbacks->componentEnvironment, inst->name, error ? fmi2Error : fmi2OK, category, "%s", message);
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
    ModelInfo info;
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
    fmi2CallbackFunctions *callbacks = functions->allocateMemory(1, sizeof(fmi2CallbackFunctions));
    if (callbacks == NULL) {
        log_instantiation_error(functions, instanceName, "out of memory");
        return NULL;
    }
    *callbacks = *functions;
    ModelInstance *inst = core_new(instanceName, fmuType == fmi2ModelExchange, loggingOn, functions->allocateMemory,
                                  functions->freeMemory, emit, callbacks);
    if (inst == NULL) {
        log_instantiation_error(functions, instanceName, "out of memory");
        functions->freeMemory(callbacks);
        return NULL;
    }
    return inst;
}

void fmi2FreeInstance(fmi2Component c) {
    /* An instance freed already (or never made here) is not touched: see fmu_liveness.h. */
    if (!fmu_mark_freed(c)) return;
    ModelInstance *inst = c;
    core_free(inst);
    model_release(inst, inst->layer);
    fmu_retire(c);
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories, const fmi2String categories[]) {
    REQUIRE(c, ANY_MODE, "fmi2SetDebugLogging");
    return core_set_debug_logging(inst, loggingOn, nCategories, categories, "fmi2SetDebugLogging");
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    REQUIRE(c, MODE_INSTANTIATED, "fmi2SetupExperiment");
    (void)toleranceDefined;
    (void)tolerance;
    return core_setup(inst, startTime, stopTimeDefined, stopTime, "fmi2SetupExperiment");
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    REQUIRE(c, MODE_INSTANTIATED, "fmi2EnterInitializationMode");
    inst->mode = MODE_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    REQUIRE(c, MODE_INITIALIZATION, "fmi2ExitInitializationMode");
    return core_exit_initialization(inst, "fmi2ExitInitializationMode");
}

fmi2Status fmi2Terminate(fmi2Component c) {
    REQUIRE(c, RUNNING, "fmi2Terminate");
    inst->mode = MODE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    REQUIRE(c, ANY_MODE, "fmi2Reset");
    core_reset(inst);
    return fmi2OK;
}

/* ---------------------------------------------------------------- get / set */

/* Every vr is a variable of type; logs the first that is not. */
static fmi2Status check_references(ModelInstance *inst, ValueType type, const fmi2ValueReference vr[], size_t nvr,
                                   const char *function) {
    if (type == TYPE_REAL) { /* the usual call, first: Real value references start at 0 */
        size_t i = 0;
        while (i < nvr && vr[i] < inst->info.n_real) i++;
        if (i == nvr) return fmi2OK;
    }
    size_t first, count;
    core_type_range(inst, type, &first, &count);
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] >= first && vr[i] - first < count) continue;
        if (count == 0)
            return model_fail(inst, "%s: this FMU has no %s variables (value reference %u)", function,
                             CORE_TYPE_NAMES[type], (unsigned)vr[i]);
        return model_fail(inst, "%s: no %s variable has value reference %u", function, CORE_TYPE_NAMES[type],
                         (unsigned)vr[i]);
    }
    return fmi2OK;
}

#define SET_PROLOGUE(type, function)                                                                \
    REQUIRE(c, MODE_INSTANTIATED | MODE_INITIALIZATION | RUNNING, function);                        \
    REQUIRE_ARRAY(vr, nvr, function);                                                               \
    REQUIRE_ARRAY(value, nvr, function);                                                            \
    if (check_references(inst, type, vr, nvr, function) != fmi2OK) return fmi2Error

#define GET_PROLOGUE(type, function)                                                                \
    REQUIRE(c, AFTER_INSTANTIATION, function);                                                      \
    REQUIRE_ARRAY(vr, nvr, function);                                                               \
    REQUIRE_ARRAY(value, nvr, function);                                                            \
    if (check_references(inst, type, vr, nvr, function) != fmi2OK) return fmi2Error;               \
    if (core_prepare_get(inst, function) != MODEL_OK) return fmi2Error

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    GET_PROLOGUE(TYPE_REAL, "fmi2GetReal");
    for (size_t i = 0; i < nvr; i++) value[i] = inst->reals[vr[i]];
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    GET_PROLOGUE(TYPE_INTEGER, "fmi2GetInteger");
    for (size_t i = 0; i < nvr; i++) value[i] = inst->integers[vr[i] - inst->info.n_real];
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    GET_PROLOGUE(TYPE_BOOLEAN, "fmi2GetBoolean");
    for (size_t i = 0; i < nvr; i++) value[i] = inst->booleans[vr[i] - inst->info.n_real - inst->info.n_integer];
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    GET_PROLOGUE(TYPE_STRING, "fmi2GetString");
    for (size_t i = 0; i < nvr; i++) value[i] = model_string(inst, vr[i]);
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    SET_PROLOGUE(TYPE_REAL, "fmi2SetReal");
    /* Check every value first, so that a refused call changes nothing. */
    for (size_t i = 0; i < nvr; i++)
        if (core_accept_real(inst, vr[i], value[i], "fmi2SetReal") != MODEL_OK) return fmi2Error;
    for (size_t i = 0; i < nvr; i++) core_store_real(inst, vr[i], value[i]);
    return fmi2OK;
}

static fmi2Status set_integers(ModelInstance *inst, ValueType type, const fmi2ValueReference vr[], size_t nvr,
                               const fmi2Integer value[], const char *function) {
    for (size_t i = 0; i < nvr; i++)
        if (core_accept_integer(inst, type, vr[i], type == TYPE_BOOLEAN ? value[i] != fmi2False : value[i], function)
            != MODEL_OK)
            return fmi2Error;
    for (size_t i = 0; i < nvr; i++)
        core_store_integer(inst, type, vr[i], type == TYPE_BOOLEAN ? value[i] != fmi2False : value[i]);
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    SET_PROLOGUE(TYPE_INTEGER, "fmi2SetInteger");
    return set_integers(inst, TYPE_INTEGER, vr, nvr, value, "fmi2SetInteger");
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    SET_PROLOGUE(TYPE_BOOLEAN, "fmi2SetBoolean");
    return set_integers(inst, TYPE_BOOLEAN, vr, nvr, value, "fmi2SetBoolean");
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    SET_PROLOGUE(TYPE_STRING, "fmi2SetString");
    for (size_t i = 0; i < nvr; i++)
        if (core_accept_string(inst, vr[i], value[i], "fmi2SetString") != MODEL_OK) return fmi2Error;
    for (size_t i = 0; i < nvr; i++) core_store_string(inst, vr[i], value[i]);
    return fmi2OK;
}

/* ---------------------------------------------------------------- Co-Simulation */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    REQUIRE(c, ANY_MODE, "fmi2SetRealInputDerivatives");
    (void)vr; (void)order; (void)value;
    if (nvr == 0) return fmi2OK;
    return model_fail(inst, "fmi2SetRealInputDerivatives: the FMU holds its inputs constant over a step "
                     "(canInterpolateInputs=\"false\")");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    REQUIRE(c, ANY_MODE, "fmi2GetRealOutputDerivatives");
    (void)vr; (void)order; (void)value;
    if (nvr == 0) return fmi2OK;
    return model_fail(inst, "fmi2GetRealOutputDerivatives: the FMU provides no output derivatives "
                     "(maxOutputDerivativeOrder=\"0\")");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    REQUIRE(c, MODE_STEP_COMPLETE, "fmi2DoStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    return core_do_step(inst, currentCommunicationPoint, communicationStepSize, "fmi2DoStep");
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    REQUIRE(c, MODE_STEP_COMPLETE, "fmi2CancelStep");
    return model_fail(inst, "fmi2CancelStep: fmi2DoStep never returns fmi2Pending, so there is no step to cancel");
}

static fmi2Status no_status(fmi2Component c, fmi2StatusKind s, const char *function) {
    REQUIRE(c, ANY_MODE, function);
    return model_fail(inst, "%s: status kind %d is not provided (fmi2DoStep is synchronous)", function, (int)s);
}

/* The status getters this FMU does not provide: one refusal each. */
#define NO_STATUS(function, type)                                                                    \
    fmi2Status function(fmi2Component c, const fmi2StatusKind s, type *value) {                    \
        (void)value;                                                                                \
        return no_status(c, s, #function);                                                          \
    }
NO_STATUS(fmi2GetStatus, fmi2Status)
NO_STATUS(fmi2GetRealStatus, fmi2Real)
NO_STATUS(fmi2GetIntegerStatus, fmi2Integer)
NO_STATUS(fmi2GetStringStatus, fmi2String)

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    REQUIRE(c, ANY_MODE, "fmi2GetBooleanStatus");
    if (value == NULL) return model_fail(inst, "fmi2GetBooleanStatus: value is NULL");
    if (s == fmi2Terminated) {
        /* Asked after fmi2Discard: this FMU never discards, and never asks to terminate. */
        *value = fmi2False;
        return fmi2OK;
    }
    return model_fail(inst, "fmi2GetBooleanStatus: status kind %d is not provided", (int)s);
}
