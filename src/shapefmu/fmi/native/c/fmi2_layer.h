/* Shared by the two files of the generic FMI 2.0 layer only (fmi2_layer.c, fmi2_layer_me.c): the
 * standard's FMI 2.0 API, the version-neutral core (whose ModelStatus has fmi2Status's values), and
 * the entry guards. Model parts include model.h, not this. */
#ifndef FMI2_LAYER_H
#define FMI2_LAYER_H

#include "fmi2Functions.h"
#include "layer_core.h"

#define REQUIRE(instance, allowed, function) GUARD(instance, allowed, function, fmi2Error)
#define REQUIRE_ARRAY(pointer, count, function) GUARD_ARRAY(pointer, count, function, fmi2Error)
#define REQUIRE_TYPE(wanted, function)                                                              \
    if (inst->model_exchange != ((wanted) == fmi2ModelExchange))                                    \
    return (fmi2Status)model_fail(inst, "%s: only for %s instances", function,                      \
                                  (wanted) == fmi2ModelExchange ? "Model Exchange" : "Co-Simulation")

#endif
