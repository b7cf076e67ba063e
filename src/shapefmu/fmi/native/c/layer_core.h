/* What the generic FMI 2.0 and FMI 3.0 layers share (layer_core.c, layer_state.c): everything about an
 * instance that does not depend on the version of the standard -- its buffers, the causality and
 * variability rules of a set call, the Co-Simulation step, the Model Exchange state vector, the
 * linearisation and FMU states. Each layer (fmi2_layer*.c, fmi3_layer*.c) is the thin API of its
 * version over these. Model parts include model.h, not this.
 *
 * Every function takes the name of the API function it serves, for the message of a refused call,
 * and returns MODEL_OK, or MODEL_ERROR after logging (model_fail: the instance is then in the error state).
 */
#ifndef LAYER_CORE_H
#define LAYER_CORE_H

#include "model.h"
#include "fmu_liveness.h"

#define ANY_MODE (MODE_INSTANTIATED | MODE_INITIALIZATION | MODE_EVENT | MODE_CONTINUOUS_TIME \
                  | MODE_STEP_COMPLETE | MODE_TERMINATED | MODE_ERROR)
#define AFTER_INSTANTIATION (ANY_MODE & ~MODE_INSTANTIATED)
#define RUNNING (MODE_EVENT | MODE_CONTINUOUS_TIME | MODE_STEP_COMPLETE)
#define BEFORE_RUNNING (MODE_INSTANTIATED | MODE_INITIALIZATION)

/* Guard of every entry point: a live instance (fmu_liveness.h) in one of the allowed modes; `error`
 * is the version's error status. Declares `inst`. */
#define GUARD(instance, allowed, function, error)                                                   \
    ModelInstance *inst = (ModelInstance *)(instance);                                                \
    if (!fmu_is_live(inst, function)) return error;                                                 \
    if (!(inst->mode & (allowed))) {                                                                \
        model_fail(inst, "%s: not allowed in %s", function, mode_name(inst->mode));             \
        return error;                                                                               \
    }                                                                                               \
    if (inst->logging_on) model_debug(inst, "%s", function)

/* A caller's array of count values must exist: NULL with count > 0 is refused, not dereferenced. */
#define GUARD_ARRAY(pointer, count, function, error)                                                \
    if ((count) > 0 && (pointer) == NULL) {                                                         \
        model_fail(inst, "%s: %s is NULL but holds %zu values", function, #pointer, (size_t)(count)); \
        return error;                                                                               \
    }

/* ---- the model part's hooks, each with the layer's default where the part gives none (model.h) */

void model_describe(ModelInfo *info);
VariableRole model_variable(const ModelInstance *inst, ValueType type, size_t vr, const char **name);
void model_reset(ModelInstance *inst);
ModelStatus model_check_real(ModelInstance *inst, size_t vr, double value, const char *function);
ModelStatus model_check_integer(ModelInstance *inst, size_t vr, int value, const char *function);
ModelStatus model_check_string(ModelInstance *inst, size_t vr, const char *value, const char *function);
ModelStatus model_update(ModelInstance *inst, const char *function);
/* Make the values a get call reads current (none in the error state): Initialization Mode's
 * outputs (core_preview_initialization), then model_update. */
ModelStatus core_prepare_get(ModelInstance *inst, const char *function);
size_t model_state_size(const ModelInstance *inst);
void model_save_state(const ModelInstance *inst, unsigned char *bytes);
int model_restore_state(ModelInstance *inst, const unsigned char *bytes, size_t size, const char *function);

/* ---- instances */

/* A new instance of the model with the layer's allocator and logger, in the Instantiated mode;
 * NULL if memory runs out (nothing is left allocated). */
ModelInstance *core_new(const char *name, int model_exchange, int logging_on, void *(*allocate)(size_t, size_t),
                       void (*release)(void *), void (*emit)(const ModelInstance *, int, const char *, const char *),
                       void *layer);
/* Release everything an instance holds but its struct and its layer data (then fmu_retire). */
void core_free(ModelInstance *inst);
/* The experiment's start (and stop) time, checked, before initialisation. */
ModelStatus core_setup(ModelInstance *inst, double start_time, int stop_time_defined, double stop_time,
                      const char *function);
ModelStatus core_exit_initialization(ModelInstance *inst, const char *function);
/* Logging on or off for the given categories (logAll, logStatusError; none: all of them). */
ModelStatus core_set_debug_logging(ModelInstance *inst, int logging_on, size_t n_categories, const char *const categories[],
                                  const char *function);
void core_reset(ModelInstance *inst);

/* ---- variables: value references of the contract (model.h), "slots" to the FMI 3.0 layer */

/* The slots [first, first + count) of a type. */
void core_type_range(const ModelInstance *inst, ValueType type, size_t *first, size_t *count);
extern const char *const CORE_TYPE_NAMES[4];
/* Whether value may be stored in slot now (the role's mode rules, then the model's check); refused
 * values log and change nothing. The store functions then store and tell the model. */
ModelStatus core_accept_real(ModelInstance *inst, size_t slot, double value, const char *function);
ModelStatus core_accept_integer(ModelInstance *inst, ValueType type, size_t slot, int value, const char *function);
ModelStatus core_accept_string(ModelInstance *inst, size_t slot, const char *value, const char *function);
void core_store_real(ModelInstance *inst, size_t slot, double value);
void core_store_integer(ModelInstance *inst, ValueType type, size_t slot, int value);
void core_store_string(ModelInstance *inst, size_t slot, const char *value);
int *core_integer_values(ModelInstance *inst, ValueType type); /* the array of Integer or Boolean slots */

/* ---- Co-Simulation and Model Exchange */

/* Advance from the FMU's time by h (checked: finite, >= 0, from its own time); 0 is a no-op. */
ModelStatus core_do_step(ModelInstance *inst, double current_time, double h, const char *function);
ModelStatus core_set_time(ModelInstance *inst, double time, const char *function);
ModelStatus core_set_states(ModelInstance *inst, const double x[], size_t n, const char *function);
ModelStatus core_get_derivatives(ModelInstance *inst, double derivatives[], size_t n, const char *function);
ModelStatus core_get_states(ModelInstance *inst, double x[], size_t n, const char *function);
ModelStatus core_get_nominals(ModelInstance *inst, double nominals[], size_t n, const char *function);
/* dvUnknown = J dvKnown over slots. */
ModelStatus core_directional_derivative(ModelInstance *inst, const unsigned int unknown[], size_t n_unknown,
                                       const unsigned int known[], size_t n_known, const double seed[],
                                       double sensitivity[], const char *function);

/* ---- FMU states (layer_state.c); a state is a void * to the layers */

ModelStatus core_get_state(ModelInstance *inst, void **state, const char *function);
ModelStatus core_set_state(ModelInstance *inst, const void *state, const char *function);
ModelStatus core_free_state(ModelInstance *inst, void **state, const char *function);
/* In Initialization Mode, the computed values made what the exit of initialisation would make them
 * from the values set so far, nothing else changed; a no-op in any other mode. */
ModelStatus core_preview_initialization(ModelInstance *inst, const char *function);
ModelStatus core_serialized_size(ModelInstance *inst, const void *state, size_t *size, const char *function);
ModelStatus core_serialize(ModelInstance *inst, const void *state, unsigned char bytes[], size_t size,
                          const char *function);
ModelStatus core_deserialize(ModelInstance *inst, const unsigned char bytes[], size_t size, void **state,
                            const char *function);

#endif
