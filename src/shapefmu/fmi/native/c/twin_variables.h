/* The variables of a native twin of a pythonfmu FMU (the EKF tuner, the STOS controller, the
 * profile generator), as the model.c generated for one build lists them: by value reference, in
 * the generic layer's order (Real, Integer, Boolean, String), each with its role, its meaning to
 * the model part (an enum of that part) and its start value. One table, read by the part's hooks
 * through the functions below. */
#ifndef TWIN_VARIABLES_H
#define TWIN_VARIABLES_H

#include "fmi2_model.h"

typedef struct {
    const char *name;
    Fmi2Role role;
    int meaning;               /* the model part's own enum */
    double start;              /* Real, Integer and Boolean start values */
    const char *string_start;  /* String start value, else NULL */
} TwinVariable;

typedef struct {
    const char *guid;
    size_t n_real, n_integer, n_boolean, n_string;
    const TwinVariable *variables;  /* by value reference */
} TwinVariables;

size_t twin_count(const TwinVariables *table);
void twin_describe(const TwinVariables *table, Fmi2ModelInfo *info);
Fmi2Role twin_variable(const TwinVariables *table, size_t vr, const char **name);
/* Every variable back to its start value. */
void twin_reset(const TwinVariables *table, Fmi2Instance *inst);
/* vr of each meaning (meanings below count) into vr_of. */
void twin_index(const TwinVariables *table, size_t *vr_of, int count);
/* A design parameter set to another value than its build value (given, as the user wrote it):
 * refused with a message saying why (what was made at build time) and how to rebuild. */
fmi2Status twin_refuse(Fmi2Instance *inst, const TwinVariable *v, const char *given, const char *why,
                       const char *rebuild, const char *function);

#endif
