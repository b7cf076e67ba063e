/* The version-neutral part of shapefmu's generic FMI layers (layer_core.h): the services a model part
 * calls (fmi2_model.h), an instance's buffers, the causality and variability rules of a set call, the
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

static void log_message(const Fmi2Instance *inst, int error, const char *category, const char *format, va_list args) {
    char message[512];
    vsnprintf(message, sizeof message, format, args);
    inst->emit(inst, error, category, message);
}

fmi2Status fmi2_fail(Fmi2Instance *inst, const char *format, ...) {
    va_list args;
    va_start(args, format);
    log_message(inst, 1, "logStatusError", format, args); /* an error is never debug output */
    va_end(args);
    inst->mode = FMI2_ERROR_STATE;
    return fmi2Error;
}

void fmi2_debug(const Fmi2Instance *inst, const char *format, ...) {
    if (!inst->logging_on) return;
    va_list args;
    va_start(args, format);
    log_message(inst, 0, "logAll", format, args);
    va_end(args);
}

void *fmi2_allocate(Fmi2Instance *inst, size_t count, size_t size) {
    return count == 0 ? NULL : inst->allocate(count, size);
}

void fmi2_release(Fmi2Instance *inst, void *pointer) {
    if (pointer != NULL) inst->release(pointer);
}

size_t fmi2_string_capacity(const Fmi2Instance *inst) { return inst->info.string_capacity; }

char *fmi2_string(Fmi2Instance *inst, size_t vr) {
    const size_t first = inst->info.n_real + inst->info.n_integer + inst->info.n_boolean;
    return inst->strings + (vr - first) * (inst->info.string_capacity + 1);
}

/* ---------------------------------------------------------------- life cycle */

void core_free(Fmi2Instance *inst) {
    model_free(inst);
    void *buffers[] = {inst->name, inst->reals, inst->integers, inst->booleans, inst->strings};
    for (size_t i = 0; i < sizeof buffers / sizeof buffers[0]; i++) fmi2_release(inst, buffers[i]);
}

Fmi2Instance *core_new(const char *name, int model_exchange, int logging_on, void *(*allocate)(size_t, size_t),
                       void (*release)(void *), void (*emit)(const Fmi2Instance *, int, const char *, const char *),
                       void *layer) {
    Fmi2ModelInfo info;
    model_describe(&info);
    if (info.string_capacity == 0) info.string_capacity = FMI2_STRING_CAPACITY;
    /* The struct from calloc, not the host's allocator: it may be released after the host is gone
     * (fmu_retire), and its address must not come back soon as another instance's. */
    Fmi2Instance *inst = calloc(1, sizeof(Fmi2Instance));
    if (inst == NULL) return NULL;
    inst->info = info;
    inst->model_exchange = model_exchange;
    inst->logging_on = logging_on;
    inst->mode = FMI2_INSTANTIATED;
    inst->allocate = allocate;
    inst->release = release;
    inst->emit = emit;
    inst->layer = layer;
    inst->name = fmi2_allocate(inst, strlen(name) + 1, 1);
    inst->reals = fmi2_allocate(inst, info.n_real, sizeof(double));
    inst->integers = fmi2_allocate(inst, info.n_integer, sizeof(int));
    inst->booleans = fmi2_allocate(inst, info.n_boolean, sizeof(int));
    inst->strings = fmi2_allocate(inst, info.n_string, info.string_capacity + 1);
    if (inst->name == NULL || (info.n_real && !inst->reals) || (info.n_integer && !inst->integers)
        || (info.n_boolean && !inst->booleans) || (info.n_string && !inst->strings) || model_instantiate(inst) != 0) {
        core_free(inst);
        free(inst);
        return NULL;
    }
    strcpy(inst->name, name);
    fmu_mark_live(inst);
    fmi2_debug(inst, "instantiated: %zu Real, %zu Integer, %zu Boolean, %zu String values", info.n_real,
               info.n_integer, info.n_boolean, info.n_string);
    return inst;
}

fmi2Status core_setup(Fmi2Instance *inst, double start_time, int stop_time_defined, double stop_time,
                      const char *function) {
    if (!isfinite(start_time)) return fmi2_fail(inst, "%s: startTime must be finite, got %g", function, start_time);
    if (stop_time_defined && !(stop_time >= start_time))
        return fmi2_fail(inst, "%s: stopTime must be >= startTime = %g, got %g", function, start_time, stop_time);
    inst->time = inst->start_time = start_time;
    return fmi2OK;
}

fmi2Status core_set_debug_logging(Fmi2Instance *inst, int logging_on, size_t n_categories, const char *const categories[],
                                  const char *function) {
    if (n_categories > 0 && categories == NULL)
        return fmi2_fail(inst, "%s: categories is NULL but holds %zu values", function, n_categories);
    for (size_t i = 0; i < n_categories; i++)
        if (categories[i] == NULL || (strcmp(categories[i], "logAll") != 0 && strcmp(categories[i], "logStatusError") != 0))
            return fmi2_fail(inst, "%s: unknown log category %s (known: logAll, logStatusError)", function,
                             categories[i] == NULL ? "NULL" : categories[i]);
    inst->logging_on = logging_on;
    return fmi2OK;
}

fmi2Status core_exit_initialization(Fmi2Instance *inst) {
    if (model_exit_initialization(inst) != fmi2OK) return fmi2Error;
    inst->clock_ticks = 0.0;
    memset(&inst->clock_position, 0, sizeof inst->clock_position);
    inst->mode = inst->model_exchange ? FMI2_EVENT_MODE : FMI2_STEP_COMPLETE;
    return fmi2OK;
}

void core_reset(Fmi2Instance *inst) {
    inst->time = inst->start_time = inst->clock_ticks = 0.0;
    memset(&inst->clock_position, 0, sizeof inst->clock_position);
    model_reset(inst);
    inst->mode = FMI2_INSTANTIATED;
}

/* ---------------------------------------------------------------- variables */

const char *const CORE_TYPE_NAMES[4] = {"Real", "Integer", "Boolean", "String"};

void core_type_range(const Fmi2Instance *inst, Fmi2Type type, size_t *first, size_t *count) {
    const Fmi2ModelInfo *info = &inst->info;
    switch (type) {
    case FMI2_REAL: *first = 0, *count = info->n_real; return;
    case FMI2_INTEGER: *first = info->n_real, *count = info->n_integer; return;
    case FMI2_BOOLEAN: *first = info->n_real + info->n_integer, *count = info->n_boolean; return;
    default: *first = info->n_real + info->n_integer + info->n_boolean, *count = info->n_string; return;
    }
}

int *core_integer_values(Fmi2Instance *inst, Fmi2Type type) {
    return type == FMI2_BOOLEAN ? inst->booleans : inst->integers;
}

/* Whether variable slot may be set now (FMI 2.0 tables in 3.2.3 for ME and 4.2.4 for CS; FMI 3.0
 * section 2.3's state machine says the same for these causalities and variabilities). */
static fmi2Status check_settable(Fmi2Instance *inst, Fmi2Type type, size_t slot, const char *function) {
    const char *name = "(no variable)";
    switch (model_variable(inst, type, slot, &name)) {
    case FMI2_NO_VARIABLE:
        return fmi2_fail(inst, "%s: no %s variable has value reference %zu", function, CORE_TYPE_NAMES[type], slot);
    case FMI2_COMPUTED:
        return fmi2_fail(inst, "%s: %s is computed by the FMU and cannot be set", function, name);
    case FMI2_STATE:
        if (inst->mode & BEFORE_RUNNING) return fmi2OK;
        return fmi2_fail(inst, "%s: state %s can be set only before initialisation is complete "
                         "(use the continuous-state setter or an FMU state), not in %s", function, name,
                         fmi2_mode_name(inst->mode));
    case FMI2_INPUT:
        return fmi2OK;
    case FMI2_PARAMETER_FIXED:
        if (inst->mode & BEFORE_RUNNING) return fmi2OK;
        return fmi2_fail(inst, "%s: parameter %s is fixed and cannot be set after initialisation (in %s)", function,
                         name, fmi2_mode_name(inst->mode));
    case FMI2_PARAMETER_TUNABLE:
        if (inst->mode & (BEFORE_RUNNING | FMI2_EVENT_MODE | FMI2_STEP_COMPLETE)) return fmi2OK;
        return fmi2_fail(inst, "%s: tunable parameter %s can be set only in Event Mode or between steps, not in %s",
                         function, name, fmi2_mode_name(inst->mode));
    }
    return fmi2Error;
}

fmi2Status core_accept_real(Fmi2Instance *inst, size_t slot, double value, const char *function) {
    if (check_settable(inst, FMI2_REAL, slot, function) != fmi2OK) return fmi2Error;
    return model_check_real(inst, slot, value, function);
}

fmi2Status core_accept_integer(Fmi2Instance *inst, Fmi2Type type, size_t slot, int value, const char *function) {
    if (check_settable(inst, type, slot, function) != fmi2OK) return fmi2Error;
    return model_check_integer(inst, slot, value, function);
}

fmi2Status core_accept_string(Fmi2Instance *inst, size_t slot, const char *value, const char *function) {
    if (check_settable(inst, FMI2_STRING, slot, function) != fmi2OK) return fmi2Error;
    if (value == NULL) return fmi2_fail(inst, "%s: a value is NULL", function);
    if (strlen(value) > inst->info.string_capacity)
        return fmi2_fail(inst, "%s: a value of %zu characters is longer than the %zu this FMU holds", function,
                         strlen(value), inst->info.string_capacity);
    return model_check_string(inst, slot, value, function);
}

void core_store_real(Fmi2Instance *inst, size_t slot, double value) {
    if (inst->reals[slot] == value) return;
    inst->reals[slot] = value;
    model_changed(inst, slot);
}

void core_store_integer(Fmi2Instance *inst, Fmi2Type type, size_t slot, int value) {
    size_t first, count;
    core_type_range(inst, type, &first, &count);
    int *values = core_integer_values(inst, type);
    if (values[slot - first] == value) return;
    values[slot - first] = value;
    model_changed(inst, slot);
}

void core_store_string(Fmi2Instance *inst, size_t slot, const char *value) {
    char *held = fmi2_string(inst, slot);
    if (strcmp(held, value) == 0) return;
    strcpy(held, value);
    model_changed(inst, slot);
}

/* ---------------------------------------------------------------- Co-Simulation */

fmi2Status core_do_step(Fmi2Instance *inst, double current_time, double h, const char *function) {
    const double t = inst->time;
    if (inst->model_exchange) return fmi2_fail(inst, "%s: only for Co-Simulation instances", function);
    if (!isfinite(h) || h < 0.0)
        return fmi2_fail(inst, "%s: communicationStepSize must be finite and >= 0, got %g", function, h);
    if (!isfinite(current_time) || fabs(current_time - t) > 1e-9 * fmax(1.0, fabs(t)))
        return fmi2_fail(inst, "%s: currentCommunicationPoint %.17g is not the FMU's time %.17g", function,
                         current_time, t);
    if (h == 0.0) return fmi2OK;
    if (model_do_step(inst, current_time, h) != fmi2OK) return fmi2Error;
    inst->time = current_time + h;
    return fmi2OK;
}

/* ---------------------------------------------------------------- Model Exchange */

fmi2Status core_set_time(Fmi2Instance *inst, double time, const char *function) {
    if (!isfinite(time)) return fmi2_fail(inst, "%s: time must be finite, got %g", function, time);
    inst->time = time;
    return fmi2OK;
}

/* The call's state count n is the model's (and the instance is one of Model Exchange). */
static fmi2Status check_states(Fmi2Instance *inst, const void *array, const char *array_name, size_t n,
                               const char *function) {
    if (!inst->model_exchange) return fmi2_fail(inst, "%s: only for Model Exchange instances", function);
    if (n > 0 && array == NULL) return fmi2_fail(inst, "%s: %s is NULL but holds %zu values", function, array_name, n);
    if (n != (size_t)inst->info.n_states)
        return fmi2_fail(inst, "%s: nx must be %d, got %zu", function, inst->info.n_states, n);
    return fmi2OK;
}

fmi2Status core_set_states(Fmi2Instance *inst, const double x[], size_t n, const char *function) {
    if (check_states(inst, x, "x", n, function) != fmi2OK) return fmi2Error;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(x[i])) {
            const char *name = "?";
            model_variable(inst, FMI2_REAL, inst->info.state_vr + i, &name);
            return fmi2_fail(inst, "%s: state %s must be finite, got %g", function, name, x[i]);
        }
    memcpy(inst->reals + inst->info.state_vr, x, n * sizeof(double));
    model_states_changed(inst);
    return fmi2OK;
}

fmi2Status core_get_derivatives(Fmi2Instance *inst, double derivatives[], size_t n, const char *function) {
    if (check_states(inst, derivatives, "derivatives", n, function) != fmi2OK) return fmi2Error;
    if (inst->mode != FMI2_ERROR_STATE && model_update(inst, function) != fmi2OK) return fmi2Error;
    if (n) memcpy(derivatives, inst->reals + inst->info.derivative_vr, n * sizeof(double));
    return fmi2OK;
}

fmi2Status core_get_states(Fmi2Instance *inst, double x[], size_t n, const char *function) {
    if (check_states(inst, x, "x", n, function) != fmi2OK) return fmi2Error;
    if (n) memcpy(x, inst->reals + inst->info.state_vr, n * sizeof(double));
    return fmi2OK;
}

fmi2Status core_get_nominals(Fmi2Instance *inst, double nominals[], size_t n, const char *function) {
    if (check_states(inst, nominals, "nominals", n, function) != fmi2OK) return fmi2Error;
    if (n) memcpy(nominals, inst->info.state_nominal, n * sizeof(double));
    return fmi2OK;
}

fmi2Status core_directional_derivative(Fmi2Instance *inst, const unsigned int unknown[], size_t n_unknown,
                                       const unsigned int known[], size_t n_known, const double seed[],
                                       double sensitivity[], const char *function) {
    for (size_t i = 0; i < n_unknown; i++) {
        double sum = 0.0;
        for (size_t j = 0; j < n_known; j++) {
            double entry;
            if (model_partial_derivative(inst, unknown[i], known[j], &entry, function) != fmi2OK) return fmi2Error;
            sum += entry * seed[j];
        }
        sensitivity[i] = sum;
    }
    return fmi2OK;
}
