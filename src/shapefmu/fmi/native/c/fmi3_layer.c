/* The generic FMI 3.0 layer of shapefmu's native FMUs: FMI 3.0's API over the same model parts
 * (model.h) and the same version-neutral core (layer_core.c, layer_state.c) as the FMI 2.0
 * layer, so an FMI 3.0 FMU and its FMI 2.0 twin compute the same numbers in the same order.
 *
 * This file: instantiation (Model Exchange and Co-Simulation; Scheduled Execution is refused), the
 * life cycle of FMI 3.0's state machine (section 2.3), the value references and arrays of
 * fmi3_layer.h, get/set of Float64, Int32, Boolean and String variables, and the Co-Simulation step.
 * Model Exchange, FMU states, directional derivatives and what the FMUs do not provide are in
 * fmi3_layer_me.c.
 *
 * Any refused call (bad argument, call out of order, a value the model refuses) logs a message
 * naming the function, the variable and the value, returns fmi3Error and puts the instance into
 * the error state.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3_layer.h"

/* ---------------------------------------------------------------- value references */

/* The length of base in name = "base[digits]", or 0 if name is not an array element. */
static size_t element_base(const char *name) {
    const size_t n = strlen(name);
    if (n < 4 || name[n - 1] != ']') return 0;
    size_t i = n - 1;
    while (i > 0 && name[i - 1] >= '0' && name[i - 1] <= '9') i--;
    if (i == n - 1 || i < 2 || name[i - 1] != '[') return 0;
    return i - 1;
}

/* The variable table of fmi3_layer.h, from the model's slots; 0 on success. */
static int build_table(ModelInstance *inst, Fmi3Layer *layer) {
    const ModelInfo *info = &inst->info;
    const size_t n_slots = info->n_real + info->n_integer + info->n_boolean + info->n_string;
    size_t *group = calloc(n_slots + 1, sizeof(size_t));        /* each slot's variable, 0: none */
    const char **base = calloc(n_slots + 1, sizeof(char *));    /* each variable's name (or base) */
    size_t *base_length = calloc(n_slots + 1, sizeof(size_t));  /* 0 for a scalar */
    layer->first = calloc(n_slots + 2, sizeof(size_t));
    layer->slots = calloc(n_slots + 1, sizeof(size_t));
    layer->types = calloc(n_slots + 1, sizeof(ValueType));
    layer->scalar = calloc(n_slots + 1, sizeof(size_t));
    if (!group || !base || !base_length || !layer->first || !layer->slots || !layer->types || !layer->scalar) {
        free(group), free(base), free(base_length);
        return -1;
    }
    size_t n = 0, last_array = 0;
    layer->period_slot = SIZE_MAX;
    for (int type = TYPE_REAL; type <= TYPE_STRING; type++) {
        size_t first, count;
        core_type_range(inst, (ValueType)type, &first, &count);
        for (size_t slot = first; slot < first + count; slot++) {
            const char *name = NULL;
            const VariableRole role = model_variable(inst, (ValueType)type, slot, &name);
            if (role == ROLE_NONE || (role == ROLE_COMPUTED && type == TYPE_REAL && strcmp(name, "time") == 0))
                continue;
            if (type == TYPE_REAL && (strcmp(name, "Ts_used") == 0
                                      || (strcmp(name, "Ts") == 0 && layer->period_slot == SIZE_MAX)))
                layer->period_slot = slot;  /* a ShapeFilter's Ts_used (Ts adjusted) before Ts */
            /* parameters only: the quantities that are one (impulse times, taps, mode frequencies) */
            const int parameter = role == ROLE_PARAMETER_FIXED || role == ROLE_PARAMETER_TUNABLE;
            const size_t length = parameter ? element_base(name) : 0;
            size_t k = 0;
            if (length > 0) {  /* the array this element belongs to: usually the last one */
                if (last_array && layer->types[last_array] == (ValueType)type && base_length[last_array] == length
                    && strncmp(base[last_array], name, length) == 0)
                    k = last_array;
                for (size_t j = 1; k == 0 && j <= n; j++)
                    if (layer->types[j] == (ValueType)type && base_length[j] == length && strncmp(base[j], name, length) == 0)
                        k = j;
            }
            if (k == 0) {
                k = ++n;
                base[k] = name;
                base_length[k] = length;
                layer->types[k] = (ValueType)type;
            }
            if (length > 0) last_array = k;
            group[slot] = k;
            layer->first[k]++;  /* counted here, turned into offsets below */
        }
    }
    /* first[k] = elements of variables 1 .. k - 1, then slots in order */
    size_t total = 0;
    for (size_t k = 1; k <= n; k++) {
        const size_t elements = layer->first[k];
        layer->first[k] = total;
        total += elements;
    }
    layer->first[n + 1] = total;
    size_t *fill = calloc(n + 2, sizeof(size_t));
    if (fill == NULL) {
        free(group), free(base), free(base_length);
        return -1;
    }
    for (size_t slot = 0; slot < n_slots; slot++)
        if (group[slot]) layer->slots[layer->first[group[slot]] + fill[group[slot]]++] = slot;
    /* shift: variable k (1-based) is first[k] .. first[k + 1] - 1 of slots */
    for (size_t k = 0; k <= n; k++) layer->first[k] = layer->first[k + 1];
    layer->n_variables = n;
    layer->scalar[0] = SIZE_MAX;  /* time */
    for (size_t k = 1; k <= n; k++)
        layer->scalar[k] = layer->first[k] - layer->first[k - 1] == 1 ? layer->slots[layer->first[k - 1]] : SIZE_MAX;
    free(fill), free(group), free(base), free(base_length);
    return 0;
}

static size_t elements_of(const Fmi3Layer *layer, size_t vr) { return layer->first[vr] - layer->first[vr - 1]; }
static const size_t *slots_of(const Fmi3Layer *layer, size_t vr) { return layer->slots + layer->first[vr - 1]; }

static const char *const FMI3_TYPE_NAMES[4] = {"Float64", "Int32", "Boolean", "String"};

/* Every vr names a variable of type (time counts as a Float64 one where time_allowed) and the values
 * are as many as their elements; logs the first that is not. */
static fmi3Status check_request(ModelInstance *inst, ValueType type, const fmi3ValueReference vr[], size_t nvr,
                                size_t n_values, int time_allowed, const char *function) {
    const Fmi3Layer *layer = layer_of(inst);
    size_t total = 0;
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] == 0 && type == TYPE_REAL) {
            if (!time_allowed) return FAIL("%s: time (value reference 0) is the independent variable and cannot be set", function);
            total++;
            continue;
        }
        if (vr[i] == 0 || vr[i] > layer->n_variables)
            return FAIL("%s: no variable has value reference %u", function, (unsigned)vr[i]);
        if (layer->types[vr[i]] != type) {
            const char *name = "?";
            model_variable(inst, layer->types[vr[i]], slots_of(layer, vr[i])[0], &name);
            return FAIL("%s: value reference %u (%s) is a %s variable, not %s", function, (unsigned)vr[i], name,
                        FMI3_TYPE_NAMES[layer->types[vr[i]]], FMI3_TYPE_NAMES[type]);
        }
        total += elements_of(layer, vr[i]);
    }
    if (total != n_values)
        return FAIL("%s: the %zu value references have %zu values (array elements counted), got nValues = %zu",
                    function, nvr, total, n_values);
    return fmi3OK;
}

int fmi3_scalar_slot(ModelInstance *inst, fmi3ValueReference vr, ValueType type, size_t *slot, const char *function) {
    const Fmi3Layer *layer = layer_of(inst);
    if (vr == 0 || vr > layer->n_variables || layer->types[vr] != type || elements_of(layer, vr) != 1) {
        model_fail(inst, "%s: value reference %u is no scalar %s variable", function, (unsigned)vr, FMI3_TYPE_NAMES[type]);
        return 0;
    }
    *slot = slots_of(layer, vr)[0];
    return 1;
}

/* ---------------------------------------------------------------- life cycle */

static void emit(const ModelInstance *inst, int error, const char *category, const char *message) {
    const Fmi3Layer *layer = layer_of(inst);
    if (layer->log != NULL) layer->log(layer->environment, error ? fmi3Error : fmi3OK, category, message);
}

static void *allocate(size_t count, size_t size) { return calloc(count, size); }

static void free_layer(Fmi3Layer *layer) {
    free(layer->first), free(layer->slots), free(layer->types), free(layer->scalar), free(layer);
}

static fmi3Instance instantiate(fmi3String name, fmi3String token, int model_exchange, int event_mode_used,
                                fmi3Boolean logging_on, fmi3InstanceEnvironment environment, fmi3LogMessageCallback log,
                                const char *function) {
    ModelInfo info;
    model_describe(&info);
    const char *why = NULL;
    if (name == NULL || name[0] == '\0') why = "instanceName must be a non-empty string";
    else if (token == NULL || strcmp(token, info.guid) != 0)
        why = "instantiationToken does not match the one in this FMU's modelDescription.xml";
    else if (model_exchange && !info.model_exchange) why = "this FMU declares no Model Exchange";
    else if (!model_exchange && fmi3_clocked() && !event_mode_used)
        why = "this FMU takes its samples at the ticks of its input clock 'sample' (built with --clock): instantiate it "
              "with eventModeUsed = fmi3True and tick the clock in Event Mode, or use the FMU built without --clock";
    /* FMI 3.0 (fmi3InstantiateCoSimulation): eventModeUsed may be fmi3True only if hasEventMode is, else the
     * FMU must fail; accepted, the host's first fmi3UpdateDiscreteStates would fail later, far from the cause. */
    else if (!model_exchange && !fmi3_clocked() && event_mode_used)
        why = "eventModeUsed = fmi3True, but this FMU has no Event Mode in Co-Simulation (hasEventMode=\"false\" in its "
              "modelDescription.xml): instantiate it with eventModeUsed = fmi3False, or build it with --clock";
    Fmi3Layer *layer = why == NULL ? calloc(1, sizeof(Fmi3Layer)) : NULL;
    if (why == NULL && layer == NULL) why = "out of memory";
    ModelInstance *inst = NULL;
    if (why == NULL) {
        layer->environment = environment;
        layer->log = log;
        layer->clocked = fmi3_clocked() && !model_exchange;
        inst = core_new(name, model_exchange, logging_on, allocate, free, emit, layer);
        if (inst == NULL || build_table(inst, layer) != 0) {
            if (inst != NULL) fmu_mark_freed(inst), core_free(inst), free(inst);
            free_layer(layer);
            inst = NULL;
            why = "out of memory";
        } else if (layer->clocked && layer->period_slot == SIZE_MAX) {
            fmu_mark_freed(inst), core_free(inst), free(inst);
            free_layer(layer);
            inst = NULL;
            why = "this FMU declares a clock but has no sample period Ts";
        }
    }
    if (why != NULL && log != NULL) {
        char message[300];
        snprintf(message, sizeof message, "%s: %s", function, why);
        log(environment, fmi3Error, "logStatusError", message);
    }
    return inst;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage) {
    (void)resourcePath, (void)visible;
    return instantiate(instanceName, instantiationToken, 1, 0, loggingOn, instanceEnvironment, logMessage,
                       "fmi3InstantiateModelExchange");
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
                                         fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate) {
    /* No early return, no intermediate variables: those requests are ignored; Event Mode is used only by
     * an FMU built with --clock (hasEventMode="true"), which needs it. */
    (void)resourcePath, (void)visible, (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables, (void)nRequiredIntermediateVariables, (void)intermediateUpdate;
    return instantiate(instanceName, instantiationToken, 0, eventModeUsed, loggingOn, instanceEnvironment, logMessage,
                       "fmi3InstantiateCoSimulation");
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn;
    (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    if (logMessage != NULL)
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "fmi3InstantiateScheduledExecution: this FMU has no Scheduled Execution interface");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) {
    /* An instance freed already (or never made here) is not touched: see fmu_liveness.h. */
    if (!fmu_mark_freed(instance)) return;
    ModelInstance *inst = instance;
    core_free(inst);
    free_layer(layer_of(inst));
    fmu_retire(instance);
}

const char *fmi3GetVersion(void) { return fmi3Version; }

/* Back to the start values and the Instantiated mode (fmi3Reset: as if instantiated anew). */
fmi3Status fmi3Reset(fmi3Instance instance) {
    ENTER(instance, ANY_MODE, "fmi3Reset");
    core_reset(inst);
    return fmi3OK;
}

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories, const fmi3String categories[]) {
    ENTER(instance, ANY_MODE, "fmi3SetDebugLogging");
    return (fmi3Status)core_set_debug_logging(inst, loggingOn, nCategories, categories, "fmi3SetDebugLogging");
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    ENTER(instance, MODE_INSTANTIATED, "fmi3EnterInitializationMode");
    (void)toleranceDefined, (void)tolerance;
    if (core_setup(inst, startTime, stopTimeDefined, stopTime, "fmi3EnterInitializationMode") != MODEL_OK) return fmi3Error;
    inst->mode = MODE_INITIALIZATION;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    ENTER(instance, MODE_INITIALIZATION, "fmi3ExitInitializationMode");
    if (core_exit_initialization(inst, "fmi3ExitInitializationMode") != MODEL_OK) return fmi3Error;
    return fmi3_clock_start(inst, "fmi3ExitInitializationMode");
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    ENTER(instance, RUNNING, "fmi3Terminate");
    inst->mode = MODE_TERMINATED;
    return fmi3OK;
}

/* ---------------------------------------------------------------- get / set */

/* Whether the request is scalar variables of type only, one value each (the usual call: no time, no
 * array), which every get and set checks first: then value i's slot is layer->scalar[vr[i]]. */
static int scalars_only(const Fmi3Layer *layer, ValueType type, const fmi3ValueReference vr[], size_t nvr,
                        size_t n_values) {
    if (nvr != n_values) return 0;
    for (size_t i = 0; i < nvr; i++)  /* vr 0 wraps to the largest value: not a scalar here */
        if (vr[i] - 1u >= layer->n_variables || layer->types[vr[i]] != type || layer->scalar[vr[i]] == SIZE_MAX)
            return 0;
    return 1;
}

#define GET_PROLOGUE(type, function)                                                                \
    ENTER(instance, AFTER_INSTANTIATION, function);                                                 \
    ENTER_ARRAY(vr, nvr, function);                                                                 \
    ENTER_ARRAY(values, nValues, function);                                                         \
    const Fmi3Layer *layer = layer_of(inst);                                                        \
    const int fast = scalars_only(layer, type, vr, nvr, nValues);                                   \
    if (!fast && check_request(inst, type, vr, nvr, nValues, 1, function) != fmi3OK) return fmi3Error; \
    if (core_prepare_get(inst, function) != MODEL_OK) return fmi3Error; \
    size_t next = 0

#define SET_PROLOGUE(type, function)                                                                \
    ENTER(instance, BEFORE_RUNNING | RUNNING, function);                                            \
    ENTER_ARRAY(vr, nvr, function);                                                                 \
    ENTER_ARRAY(values, nValues, function);                                                         \
    const Fmi3Layer *layer = layer_of(inst);                                                        \
    const int fast = scalars_only(layer, type, vr, nvr, nValues);                                   \
    if (!fast && check_request(inst, type, vr, nvr, nValues, 0, function) != fmi3OK) return fmi3Error

/* Each element of the request: vr[i]'s slots in order, value index `at`. */
#define FOR_ELEMENTS(body)                                                                          \
    for (size_t i = 0, at = 0; i < nvr; i++)                                                        \
        for (size_t e = 0; e < elements_of(layer, vr[i]); e++, at++) {                              \
            const size_t slot = slots_of(layer, vr[i])[e];                                          \
            body;                                                                                   \
        }

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[], size_t nValues) {
    GET_PROLOGUE(TYPE_REAL, "fmi3GetFloat64");
    if (fast) {
        for (size_t i = 0; i < nvr; i++) values[i] = inst->reals[layer->scalar[vr[i]]];
        return fmi3OK;
    }
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] == 0) {
            values[next++] = inst->time;
            continue;
        }
        for (size_t e = 0; e < elements_of(layer, vr[i]); e++) values[next++] = inst->reals[slots_of(layer, vr[i])[e]];
    }
    return fmi3OK;
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Int32 values[], size_t nValues) {
    GET_PROLOGUE(TYPE_INTEGER, "fmi3GetInt32");
    for (size_t i = 0; i < nvr; i++)
        for (size_t e = 0; e < elements_of(layer, vr[i]); e++)
            values[next++] = inst->integers[slots_of(layer, vr[i])[e] - inst->info.n_real];
    return fmi3OK;
}

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Boolean values[], size_t nValues) {
    GET_PROLOGUE(TYPE_BOOLEAN, "fmi3GetBoolean");
    for (size_t i = 0; i < nvr; i++)
        for (size_t e = 0; e < elements_of(layer, vr[i]); e++)
            values[next++] = inst->booleans[slots_of(layer, vr[i])[e] - inst->info.n_real - inst->info.n_integer] != 0;
    return fmi3OK;
}

fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3String values[], size_t nValues) {
    GET_PROLOGUE(TYPE_STRING, "fmi3GetString");
    for (size_t i = 0; i < nvr; i++)
        for (size_t e = 0; e < elements_of(layer, vr[i]); e++) values[next++] = model_string(inst, slots_of(layer, vr[i])[e]);
    return fmi3OK;
}

/* Every value is checked before any is stored, so that a refused call changes nothing. */
fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Float64 values[], size_t nValues) {
    SET_PROLOGUE(TYPE_REAL, "fmi3SetFloat64");
    if (fast) {
        for (size_t i = 0; i < nvr; i++)
            if (core_accept_real(inst, layer->scalar[vr[i]], values[i], "fmi3SetFloat64") != MODEL_OK) return fmi3Error;
        for (size_t i = 0; i < nvr; i++) core_store_real(inst, layer->scalar[vr[i]], values[i]);
        return fmi3OK;
    }
    FOR_ELEMENTS(if (core_accept_real(inst, slot, values[at], "fmi3SetFloat64") != MODEL_OK) return fmi3Error)
    FOR_ELEMENTS(core_store_real(inst, slot, values[at]))
    return fmi3OK;
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Int32 values[], size_t nValues) {
    SET_PROLOGUE(TYPE_INTEGER, "fmi3SetInt32");
    FOR_ELEMENTS(if (core_accept_integer(inst, TYPE_INTEGER, slot, values[at], "fmi3SetInt32") != MODEL_OK) return fmi3Error)
    FOR_ELEMENTS(core_store_integer(inst, TYPE_INTEGER, slot, values[at]))
    return fmi3OK;
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Boolean values[], size_t nValues) {
    SET_PROLOGUE(TYPE_BOOLEAN, "fmi3SetBoolean");
    FOR_ELEMENTS(if (core_accept_integer(inst, TYPE_BOOLEAN, slot, values[at] != 0, "fmi3SetBoolean") != MODEL_OK) return fmi3Error)
    FOR_ELEMENTS(core_store_integer(inst, TYPE_BOOLEAN, slot, values[at] != 0))
    return fmi3OK;
}

fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3String values[], size_t nValues) {
    SET_PROLOGUE(TYPE_STRING, "fmi3SetString");
    FOR_ELEMENTS(if (core_accept_string(inst, slot, values[at], "fmi3SetString") != MODEL_OK) return fmi3Error)
    FOR_ELEMENTS(core_store_string(inst, slot, values[at]))
    return fmi3OK;
}

/* ---------------------------------------------------------------- Co-Simulation */

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    ENTER(instance, MODE_EVENT | MODE_STEP_COMPLETE, "fmi3EnterStepMode");
    if (inst->model_exchange) return FAIL("fmi3EnterStepMode: only for Co-Simulation instances");
    if (fmi3_clock_before_step_mode(inst) != fmi3OK) return fmi3Error;
    inst->mode = MODE_STEP_COMPLETE;
    return fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean *eventHandlingNeeded,
                      fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    ENTER(instance, MODE_STEP_COMPLETE, "fmi3DoStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!eventHandlingNeeded || !terminateSimulation || !earlyReturn || !lastSuccessfulTime)
        return FAIL("fmi3DoStep: NULL eventHandlingNeeded, terminateSimulation, earlyReturn or lastSuccessfulTime");
    *eventHandlingNeeded = *terminateSimulation = *earlyReturn = fmi3False;
    *lastSuccessfulTime = inst->time;
    if (layer_of(inst)->clocked && fmi3_clock_before_step(inst, currentCommunicationPoint, communicationStepSize) != fmi3OK)
        return fmi3Error;
    if (core_do_step(inst, currentCommunicationPoint, communicationStepSize, "fmi3DoStep") != MODEL_OK) return fmi3Error;
    fmi3_clock_after_step(inst, currentCommunicationPoint, communicationStepSize);
    *lastSuccessfulTime = inst->time;
    return fmi3OK;
}
