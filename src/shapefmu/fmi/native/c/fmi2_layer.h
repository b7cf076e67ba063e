/* Shared by the files of the generic FMI 2.0 layer only (fmi2_layer.c, fmi2_layer_state.c,
 * fmi2_layer_me.c): the entry guards. Model parts include fmi2_model.h, not this. */
#ifndef FMI2_LAYER_H
#define FMI2_LAYER_H

#include "fmi2_model.h"
#include "fmu_liveness.h"

#define ANY_MODE (FMI2_INSTANTIATED | FMI2_INITIALIZATION | FMI2_EVENT_MODE | FMI2_CONTINUOUS_TIME \
                  | FMI2_STEP_COMPLETE | FMI2_TERMINATED | FMI2_ERROR_STATE)
#define AFTER_INSTANTIATION (ANY_MODE & ~FMI2_INSTANTIATED)
#define RUNNING (FMI2_EVENT_MODE | FMI2_CONTINUOUS_TIME | FMI2_STEP_COMPLETE)

/* Guard of every entry point: a live instance (fmu_liveness.h) in one of the allowed modes. */
#define REQUIRE(instance, allowed, function)                                                        \
    Fmi2Instance *inst = (Fmi2Instance *)(instance);                                                \
    if (!fmu_is_live(inst, function)) return fmi2Error;                                       \
    if (!(inst->mode & (allowed)))                                                                  \
        return fmi2_fail(inst, "%s: not allowed in %s", function, fmi2_mode_name(inst->mode));      \
    if (inst->logging_on) fmi2_debug(inst, "%s", function)

#define REQUIRE_ARRAY(pointer, count, function)                                                     \
    if ((count) > 0 && (pointer) == NULL)                                                           \
    return fmi2_fail(inst, "%s: NULL array for %zu values", function, (size_t)(count))

#define REQUIRE_TYPE(wanted, function)                                                              \
    if (inst->type != (wanted))                                                                     \
    return fmi2_fail(inst, "%s: only for %s instances", function,                                   \
                     (wanted) == fmi2ModelExchange ? "Model Exchange" : "Co-Simulation")

#endif
