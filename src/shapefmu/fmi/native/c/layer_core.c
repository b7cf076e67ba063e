/* The version-neutral part of shapefmu's generic FMI layers (layer_core.h): the services a model part
 * calls (model.h), an instance's buffers, the causality and variability rules of a set call, the
 * Co-Simulation step and the Model Exchange state vector. Written once for the FMI 2.0 layer
 * (fmi2_layer*.c) and the FMI 3.0 layer (fmi3_layer*.c), which only translate their API into these.
 */
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>

#include "layer_core.h"

/* ---------------------------------------------------------------- services to the model part */

const char *mode_name(InstanceMode mode) {
    switch (mode) {
    case MODE_INSTANTIATED: return "Instantiated";
    case MODE_INITIALIZATION: return "Initialization Mode";
    case MODE_EVENT: return "Event Mode";
    case MODE_CONTINUOUS_TIME: return "Continuous-Time Mode";
    case MODE_STEP_COMPLETE: return "Step Complete";
    case MODE_TERMINATED: return "Terminated";
    default: return "Error";
    }
}

static void log_message(const ModelInstance *inst, int error, const char *category, const char *format, va_list args) {
    char message[512];
    vsnprintf(message, sizeof message, format, args);
    inst->emit(inst, error, category, message);
}

ModelStatus model_fail(ModelInstance *inst, const char *format, ...) {
    va_list args;
    va_start(args, format);
    if (inst->previewing) {
        /* parameters refused while Initialization Mode's outputs are computed: the exit of
         * initialisation refuses them (core_preview_initialization) */
        if (inst->logging_on) log_message(inst, 0, "logAll", format, args);
    } else {
        log_message(inst, 1, "logStatusError", format, args); /* an error is never debug output */
        inst->mode = MODE_ERROR;
    }
    va_end(args);
    return MODEL_ERROR;
}

void model_debug(const ModelInstance *inst, const char *format, ...) {
    if (!inst->logging_on) return;
    va_list args;
    va_start(args, format);
    log_message(inst, 0, "logAll", format, args);
    va_end(args);
}

void *model_allocate(ModelInstance *inst, size_t count, size_t size) {
    return count == 0 ? NULL : inst->allocate(count, size);
}

void model_release(ModelInstance *inst, void *pointer) {
    if (pointer != NULL) inst->release(pointer);
}

size_t model_string_capacity(const ModelInstance *inst) { return inst->info.string_capacity; }

char *model_string(ModelInstance *inst, size_t vr) {
    const size_t first = inst->info.n_real + inst->info.n_integer + inst->info.n_boolean;
    return inst->strings + (vr - first) * (inst->info.string_capacity + 1);
}

/* ---------------------------------------------------------------- the model part, defaults applied */

static size_t table_count(const VariableTable *table) {
    return table->n_real + table->n_integer + table->n_boolean + table->n_string;
}

void model_describe(ModelInfo *info) {
    memset(info, 0, sizeof *info);
    if (model_part.describe != NULL) {
        model_part.describe(info);
        return;
    }
    const VariableTable *table = model_part.variables;
    info->guid = table->guid;
    info->n_real = table->n_real;
    info->n_integer = table->n_integer;
    info->n_boolean = table->n_boolean;
    info->n_string = table->n_string;
}

VariableRole model_variable(const ModelInstance *inst, ValueType type, size_t vr, const char **name) {
    if (model_part.variable != NULL) return model_part.variable(inst, type, vr, name);
    if (vr >= table_count(model_part.variables)) return ROLE_NONE;
    *name = model_part.variables->rows[vr].name;
    return model_part.variables->rows[vr].role;
}

void model_reset(ModelInstance *inst) {
    const VariableTable *table = model_part.variables;
    for (size_t vr = 0; table != NULL && vr < table_count(table); vr++) {
        const VariableRow *v = &table->rows[vr];
        const size_t n_real = table->n_real, n_integer = table->n_integer;
        if (vr < n_real) inst->reals[vr] = v->start;
        else if (vr < n_real + n_integer) inst->integers[vr - n_real] = (int)v->start;
        else if (vr < n_real + n_integer + table->n_boolean) inst->booleans[vr - n_real - n_integer] = v->start != 0.0;
        else snprintf(model_string(inst, vr), model_string_capacity(inst) + 1, "%s", v->string_start);
    }
    if (model_part.reset != NULL) model_part.reset(inst);
}

ModelStatus model_check_real(ModelInstance *inst, size_t vr, double value, const char *function) {
    if (model_part.check_real != NULL) return model_part.check_real(inst, vr, value, function);
    if (isfinite(value)) return MODEL_OK;
    const char *name = "?";
    model_variable(inst, TYPE_REAL, vr, &name);
    return model_fail(inst, "%s: %s must be finite, got %g", function, name, value);
}

ModelStatus model_check_integer(ModelInstance *inst, size_t vr, int value, const char *function) {
    return model_part.check_integer != NULL ? model_part.check_integer(inst, vr, value, function) : MODEL_OK;
}

ModelStatus model_check_string(ModelInstance *inst, size_t vr, const char *value, const char *function) {
    return model_part.check_string != NULL ? model_part.check_string(inst, vr, value, function) : MODEL_OK;
}

ModelStatus model_update(ModelInstance *inst, const char *function) {
    return model_part.update != NULL ? model_part.update(inst, function) : MODEL_OK;
}

ModelStatus core_prepare_get(ModelInstance *inst, const char *function) {
    if (inst->mode == MODE_ERROR) return MODEL_OK;
    if (core_preview_initialization(inst, function) != MODEL_OK) return MODEL_ERROR;
    return model_update(inst, function);
}

size_t model_state_size(const ModelInstance *inst) {
    return model_part.state_size != NULL ? model_part.state_size(inst) : 0;
}

void model_save_state(const ModelInstance *inst, unsigned char *bytes) {
    if (model_part.save_state != NULL) model_part.save_state(inst, bytes);
}

int model_restore_state(ModelInstance *inst, const unsigned char *bytes, size_t size, const char *function) {
    if (model_part.restore_state != NULL) return model_part.restore_state(inst, bytes, size, function);
    return size == 0 ? 0 : -1;
}

/* ---------------------------------------------------------------- life cycle */

void core_free(ModelInstance *inst) {
    if (model_part.free != NULL) model_part.free(inst);
    void *buffers[] = {inst->name, inst->reals, inst->integers, inst->booleans, inst->strings};
    for (size_t i = 0; i < sizeof buffers / sizeof buffers[0]; i++) model_release(inst, buffers[i]);
}

ModelInstance *core_new(const char *name, int model_exchange, int logging_on, void *(*allocate)(size_t, size_t),
                       void (*release)(void *), void (*emit)(const ModelInstance *, int, const char *, const char *),
                       void *layer) {
    ModelInfo info;
    model_describe(&info);
    if (info.string_capacity == 0) info.string_capacity = MODEL_STRING_CAPACITY;
    /* The struct from calloc, not the host's allocator: it may be released after the host is gone
     * (fmu_retire), and its address must not come back soon as another instance's. */
    ModelInstance *inst = calloc(1, sizeof(ModelInstance));
    if (inst == NULL) return NULL;
    inst->info = info;
    inst->model_exchange = model_exchange;
    inst->logging_on = logging_on;
    inst->mode = MODE_INSTANTIATED;
    inst->allocate = allocate;
    inst->release = release;
    inst->emit = emit;
    inst->layer = layer;
    inst->name = model_allocate(inst, strlen(name) + 1, 1);
    inst->reals = model_allocate(inst, info.n_real, sizeof(double));
    inst->integers = model_allocate(inst, info.n_integer, sizeof(int));
    inst->booleans = model_allocate(inst, info.n_boolean, sizeof(int));
    inst->strings = model_allocate(inst, info.n_string, info.string_capacity + 1);
    if (inst->name == NULL || (info.n_real && !inst->reals) || (info.n_integer && !inst->integers)
        || (info.n_boolean && !inst->booleans) || (info.n_string && !inst->strings)
        || (model_part.instantiate != NULL && model_part.instantiate(inst) != 0)) {
        core_free(inst);
        free(inst);
        return NULL;
    }
    strcpy(inst->name, name);
    model_reset(inst);
    fmu_mark_live(inst);
    model_debug(inst, "instantiated: %zu Real, %zu Integer, %zu Boolean, %zu String values", info.n_real,
               info.n_integer, info.n_boolean, info.n_string);
    return inst;
}

ModelStatus core_setup(ModelInstance *inst, double start_time, int stop_time_defined, double stop_time,
                      const char *function) {
    if (!isfinite(start_time)) return model_fail(inst, "%s: startTime must be finite, got %g", function, start_time);
    if (stop_time_defined && !(stop_time >= start_time))
        return model_fail(inst, "%s: stopTime must be >= startTime = %g, got %g", function, start_time, stop_time);
    inst->time = inst->start_time = start_time;
    return MODEL_OK;
}

ModelStatus core_set_debug_logging(ModelInstance *inst, int logging_on, size_t n_categories, const char *const categories[],
                                  const char *function) {
    if (n_categories > 0 && categories == NULL)
        return model_fail(inst, "%s: categories is NULL but holds %zu values", function, n_categories);
    for (size_t i = 0; i < n_categories; i++)
        if (categories[i] == NULL || (strcmp(categories[i], "logAll") != 0 && strcmp(categories[i], "logStatusError") != 0))
            return model_fail(inst, "%s: unknown log category %s (known: logAll, logStatusError)", function,
                             categories[i] == NULL ? "NULL" : categories[i]);
    inst->logging_on = logging_on;
    return MODEL_OK;
}

ModelStatus core_exit_initialization(ModelInstance *inst, const char *function) {
    if (model_part.exit_initialization != NULL && model_part.exit_initialization(inst, function) != MODEL_OK)
        return MODEL_ERROR;
    inst->clock_ticks = 0.0;
    memset(&inst->clock_position, 0, sizeof inst->clock_position);
    inst->mode = inst->model_exchange ? MODE_EVENT : MODE_STEP_COMPLETE;
    return MODEL_OK;
}

void core_reset(ModelInstance *inst) {
    inst->time = inst->start_time = inst->clock_ticks = 0.0;
    memset(&inst->clock_position, 0, sizeof inst->clock_position);
    model_reset(inst);
    inst->mode = MODE_INSTANTIATED;
}

/* ---------------------------------------------------------------- variables */

const char *const CORE_TYPE_NAMES[4] = {"Real", "Integer", "Boolean", "String"};

void core_type_range(const ModelInstance *inst, ValueType type, size_t *first, size_t *count) {
    const ModelInfo *info = &inst->info;
    switch (type) {
    case TYPE_REAL: *first = 0, *count = info->n_real; return;
    case TYPE_INTEGER: *first = info->n_real, *count = info->n_integer; return;
    case TYPE_BOOLEAN: *first = info->n_real + info->n_integer, *count = info->n_boolean; return;
    default: *first = info->n_real + info->n_integer + info->n_boolean, *count = info->n_string; return;
    }
}

int *core_integer_values(ModelInstance *inst, ValueType type) {
    return type == TYPE_BOOLEAN ? inst->booleans : inst->integers;
}

/* Whether variable slot may be set now (FMI 2.0 tables in 3.2.3 for ME and 4.2.4 for CS; FMI 3.0
 * section 2.3's state machine says the same for these causalities and variabilities). */
static ModelStatus check_settable(ModelInstance *inst, ValueType type, size_t slot, const char *function) {
    const char *name = "(no variable)";
    switch (model_variable(inst, type, slot, &name)) {
    case ROLE_NONE:
        return model_fail(inst, "%s: no %s variable has value reference %zu", function, CORE_TYPE_NAMES[type], slot);
    case ROLE_COMPUTED:
        return model_fail(inst, "%s: %s is computed by the FMU and cannot be set", function, name);
    case ROLE_STATE:
        if (inst->mode & BEFORE_RUNNING) return MODEL_OK;
        return model_fail(inst, "%s: state %s can be set only before initialisation is complete "
                         "(use the continuous-state setter or an FMU state), not in %s", function, name,
                         mode_name(inst->mode));
    case ROLE_INPUT:
        return MODEL_OK;
    case ROLE_PARAMETER_FIXED:
        if (inst->mode & BEFORE_RUNNING) return MODEL_OK;
        return model_fail(inst, "%s: parameter %s is fixed and cannot be set after initialisation (in %s)", function,
                         name, mode_name(inst->mode));
    case ROLE_PARAMETER_TUNABLE:
        if (inst->mode & (BEFORE_RUNNING | MODE_EVENT | MODE_STEP_COMPLETE)) return MODEL_OK;
        return model_fail(inst, "%s: tunable parameter %s can be set only in Event Mode or between steps, not in %s",
                         function, name, mode_name(inst->mode));
    }
    return MODEL_ERROR;
}

ModelStatus core_accept_real(ModelInstance *inst, size_t slot, double value, const char *function) {
    if (check_settable(inst, TYPE_REAL, slot, function) != MODEL_OK) return MODEL_ERROR;
    return model_check_real(inst, slot, value, function);
}

ModelStatus core_accept_integer(ModelInstance *inst, ValueType type, size_t slot, int value, const char *function) {
    if (check_settable(inst, type, slot, function) != MODEL_OK) return MODEL_ERROR;
    return model_check_integer(inst, slot, value, function);
}

ModelStatus core_accept_string(ModelInstance *inst, size_t slot, const char *value, const char *function) {
    if (check_settable(inst, TYPE_STRING, slot, function) != MODEL_OK) return MODEL_ERROR;
    if (value == NULL) return model_fail(inst, "%s: a value is NULL", function);
    if (strlen(value) > inst->info.string_capacity)
        return model_fail(inst, "%s: a value of %zu characters is longer than the %zu this FMU holds", function,
                         strlen(value), inst->info.string_capacity);
    return model_check_string(inst, slot, value, function);
}

void core_store_real(ModelInstance *inst, size_t slot, double value) {
    if (inst->reals[slot] == value) return;
    inst->reals[slot] = value;
    if (model_part.changed != NULL) model_part.changed(inst, slot);
}

void core_store_integer(ModelInstance *inst, ValueType type, size_t slot, int value) {
    size_t first, count;
    core_type_range(inst, type, &first, &count);
    int *values = core_integer_values(inst, type);
    if (values[slot - first] == value) return;
    values[slot - first] = value;
    if (model_part.changed != NULL) model_part.changed(inst, slot);
}

void core_store_string(ModelInstance *inst, size_t slot, const char *value) {
    char *held = model_string(inst, slot);
    if (strcmp(held, value) == 0) return;
    strcpy(held, value);
    if (model_part.changed != NULL) model_part.changed(inst, slot);
}

/* ---------------------------------------------------------------- Co-Simulation */

ModelStatus core_do_step(ModelInstance *inst, double current_time, double h, const char *function) {
    const double t = inst->time;
    if (inst->model_exchange) return model_fail(inst, "%s: only for Co-Simulation instances", function);
    if (!isfinite(h) || h < 0.0)
        return model_fail(inst, "%s: communicationStepSize must be finite and >= 0, got %g", function, h);
    if (!isfinite(current_time) || fabs(current_time - t) > 1e-9 * fmax(1.0, fabs(t)))
        return model_fail(inst, "%s: currentCommunicationPoint %.17g is not the FMU's time %.17g", function,
                         current_time, t);
    if (h == 0.0) return MODEL_OK;
    if (model_part.do_step(inst, current_time, h, function) != MODEL_OK) return MODEL_ERROR;
    inst->time = current_time + h;
    return MODEL_OK;
}

/* ---------------------------------------------------------------- Model Exchange */

ModelStatus core_set_time(ModelInstance *inst, double time, const char *function) {
    if (!isfinite(time)) return model_fail(inst, "%s: time must be finite, got %g", function, time);
    inst->time = time;
    return MODEL_OK;
}

/* The call's state count n is the model's (and the instance is one of Model Exchange). */
static ModelStatus check_states(ModelInstance *inst, const void *array, const char *array_name, size_t n,
                               const char *function) {
    if (!inst->model_exchange) return model_fail(inst, "%s: only for Model Exchange instances", function);
    if (n > 0 && array == NULL) return model_fail(inst, "%s: %s is NULL but holds %zu values", function, array_name, n);
    if (n != (size_t)inst->info.n_states)
        return model_fail(inst, "%s: nx must be %d, got %zu", function, inst->info.n_states, n);
    return MODEL_OK;
}

ModelStatus core_set_states(ModelInstance *inst, const double x[], size_t n, const char *function) {
    if (check_states(inst, x, "x", n, function) != MODEL_OK) return MODEL_ERROR;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(x[i])) {
            const char *name = "?";
            model_variable(inst, TYPE_REAL, inst->info.state_vr + i, &name);
            return model_fail(inst, "%s: state %s must be finite, got %g", function, name, x[i]);
        }
    memcpy(inst->reals + inst->info.state_vr, x, n * sizeof(double));
    if (model_part.states_changed != NULL) model_part.states_changed(inst);
    return MODEL_OK;
}

ModelStatus core_get_derivatives(ModelInstance *inst, double derivatives[], size_t n, const char *function) {
    if (check_states(inst, derivatives, "derivatives", n, function) != MODEL_OK) return MODEL_ERROR;
    if (inst->mode != MODE_ERROR && model_update(inst, function) != MODEL_OK) return MODEL_ERROR;
    if (n) memcpy(derivatives, inst->reals + inst->info.derivative_vr, n * sizeof(double));
    return MODEL_OK;
}

ModelStatus core_get_states(ModelInstance *inst, double x[], size_t n, const char *function) {
    if (check_states(inst, x, "x", n, function) != MODEL_OK) return MODEL_ERROR;
    if (n) memcpy(x, inst->reals + inst->info.state_vr, n * sizeof(double));
    return MODEL_OK;
}

ModelStatus core_get_nominals(ModelInstance *inst, double nominals[], size_t n, const char *function) {
    if (check_states(inst, nominals, "nominals", n, function) != MODEL_OK) return MODEL_ERROR;
    if (n) memcpy(nominals, inst->info.state_nominal, n * sizeof(double));
    return MODEL_OK;
}

ModelStatus core_directional_derivative(ModelInstance *inst, const unsigned int unknown[], size_t n_unknown,
                                       const unsigned int known[], size_t n_known, const double seed[],
                                       double sensitivity[], const char *function) {
    for (size_t i = 0; i < n_unknown; i++) {
        double sum = 0.0;
        for (size_t j = 0; j < n_known; j++) {
            double entry;
            if (model_part.partial_derivative == NULL)
                return model_fail(inst, "%s: this FMU provides no directional derivatives", function);
            if (model_part.partial_derivative(inst, unknown[i], known[j], &entry, function) != MODEL_OK) return MODEL_ERROR;
            sum += entry * seed[j];
        }
        sensitivity[i] = sum;
    }
    return MODEL_OK;
}
