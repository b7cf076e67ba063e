/* What the twins' model parts (the EKF tuner, the STOS controller, the profile generator) do with the
 * variable table their generated model.c lists (model.h's VariableTable, which the layer describes,
 * looks up and resets): find each meaning's value reference, and refuse a design parameter set to
 * another value than the one the design was made for at build time. */
#ifndef TWIN_VARIABLES_H
#define TWIN_VARIABLES_H

#include "model.h"

/* vr of each meaning (meanings below count) into vr_of. */
void twin_index(const VariableTable *table, size_t *vr_of, int count);
/* A design parameter set to another value than its build value (given, as the user wrote it):
 * refused with a message saying why (what was made at build time) and how to rebuild. */
ModelStatus twin_refuse(ModelInstance *inst, const VariableRow *v, const char *given, const char *why,
                        const char *rebuild, const char *function);

#endif
