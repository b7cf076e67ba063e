/* What the generic FMI 2.0 and FMI 3.0 layers share (layer_core.c, layer_state.c): everything about an
 * instance that does not depend on the version of the standard -- its buffers, the causality and
 * variability rules of a set call, the Co-Simulation step, the Model Exchange state vector, the
 * linearisation and FMU states. Each layer (fmi2_layer*.c, fmi3_layer*.c) is the thin API of its
 * version over these. Model parts include fmi2_model.h, not this.
 *
 * Every function takes the name of the API function it serves, for the message of a refused call,
 * and returns fmi2OK, or fmi2Error after logging (fmi2_fail: the instance is then in the error state).
 */
#ifndef LAYER_CORE_H
#define LAYER_CORE_H

#include "fmi2_model.h"
#include "fmu_liveness.h"

#define ANY_MODE (FMI2_INSTANTIATED | FMI2_INITIALIZATION | FMI2_EVENT_MODE | FMI2_CONTINUOUS_TIME \
                  | FMI2_STEP_COMPLETE | FMI2_TERMINATED | FMI2_ERROR_STATE)
#define AFTER_INSTANTIATION (ANY_MODE & ~FMI2_INSTANTIATED)
#define RUNNING (FMI2_EVENT_MODE | FMI2_CONTINUOUS_TIME | FMI2_STEP_COMPLETE)
#define BEFORE_RUNNING (FMI2_INSTANTIATED | FMI2_INITIALIZATION)

/* Guard of every entry point: a live instance (fmu_liveness.h) in one of the allowed modes; `error`
 * is the version's error status. Declares `inst`. */
#define GUARD(instance, allowed, function, error)                                                   \
    Fmi2Instance *inst = (Fmi2Instance *)(instance);                                                \
    if (!fmu_is_live(inst, function)) return error;                                                 \
    if (!(inst->mode & (allowed))) {                                                                \
        fmi2_fail(inst, "%s: not allowed in %s", function, fmi2_mode_name(inst->mode));             \
        return error;                                                                               \
    }                                                                                               \
    if (inst->logging_on) fmi2_debug(inst, "%s", function)

/* A caller's array of count values must exist: NULL with count > 0 is refused, not dereferenced. */
#define GUARD_ARRAY(pointer, count, function, error)                                                \
    if ((count) > 0 && (pointer) == NULL) {                                                         \
        fmi2_fail(inst, "%s: %s is NULL but holds %zu values", function, #pointer, (size_t)(count)); \
        return error;                                                                               \
    }

/* ---- instances */

/* A new instance of the model with the layer's allocator and logger, in the Instantiated mode;
 * NULL if memory runs out (nothing is left allocated). */
Fmi2Instance *core_new(const char *name, int model_exchange, int logging_on, void *(*allocate)(size_t, size_t),
                       void (*release)(void *), void (*emit)(const Fmi2Instance *, int, const char *, const char *),
                       void *layer);
/* Release everything an instance holds but its struct and its layer data (then fmu_retire). */
void core_free(Fmi2Instance *inst);
/* The experiment's start (and stop) time, checked, before initialisation. */
fmi2Status core_setup(Fmi2Instance *inst, double start_time, int stop_time_defined, double stop_time,
                      const char *function);
fmi2Status core_exit_initialization(Fmi2Instance *inst);
/* Logging on or off for the given categories (logAll, logStatusError; none: all of them). */
fmi2Status core_set_debug_logging(Fmi2Instance *inst, int logging_on, size_t n_categories, const char *const categories[],
                                  const char *function);
void core_reset(Fmi2Instance *inst);

/* ---- variables: value references of the contract (fmi2_model.h), "slots" to the FMI 3.0 layer */

/* The slots [first, first + count) of a type. */
void core_type_range(const Fmi2Instance *inst, Fmi2Type type, size_t *first, size_t *count);
extern const char *const CORE_TYPE_NAMES[4];
/* Whether value may be stored in slot now (the role's mode rules, then the model's check); refused
 * values log and change nothing. The store functions then store and tell the model. */
fmi2Status core_accept_real(Fmi2Instance *inst, size_t slot, double value, const char *function);
fmi2Status core_accept_integer(Fmi2Instance *inst, Fmi2Type type, size_t slot, int value, const char *function);
fmi2Status core_accept_string(Fmi2Instance *inst, size_t slot, const char *value, const char *function);
void core_store_real(Fmi2Instance *inst, size_t slot, double value);
void core_store_integer(Fmi2Instance *inst, Fmi2Type type, size_t slot, int value);
void core_store_string(Fmi2Instance *inst, size_t slot, const char *value);
int *core_integer_values(Fmi2Instance *inst, Fmi2Type type); /* the array of Integer or Boolean slots */

/* ---- Co-Simulation and Model Exchange */

/* Advance from the FMU's time by h (checked: finite, >= 0, from its own time); 0 is a no-op. */
fmi2Status core_do_step(Fmi2Instance *inst, double current_time, double h, const char *function);
fmi2Status core_set_time(Fmi2Instance *inst, double time, const char *function);
fmi2Status core_set_states(Fmi2Instance *inst, const double x[], size_t n, const char *function);
fmi2Status core_get_derivatives(Fmi2Instance *inst, double derivatives[], size_t n, const char *function);
fmi2Status core_get_states(Fmi2Instance *inst, double x[], size_t n, const char *function);
fmi2Status core_get_nominals(Fmi2Instance *inst, double nominals[], size_t n, const char *function);
/* dvUnknown = J dvKnown over slots. */
fmi2Status core_directional_derivative(Fmi2Instance *inst, const unsigned int unknown[], size_t n_unknown,
                                       const unsigned int known[], size_t n_known, const double seed[],
                                       double sensitivity[], const char *function);

/* ---- FMU states (layer_state.c); a state is a void * to the layers */

fmi2Status core_get_state(Fmi2Instance *inst, void **state, const char *function);
fmi2Status core_set_state(Fmi2Instance *inst, const void *state, const char *function);
fmi2Status core_free_state(Fmi2Instance *inst, void **state, const char *function);
fmi2Status core_serialized_size(Fmi2Instance *inst, const void *state, size_t *size, const char *function);
fmi2Status core_serialize(Fmi2Instance *inst, const void *state, unsigned char bytes[], size_t size,
                          const char *function);
fmi2Status core_deserialize(Fmi2Instance *inst, const unsigned char bytes[], size_t size, void **state,
                            const char *function);

#endif
