/* The variable table of a native twin (twin_variables.h). */
#include <stdio.h>

#include "twin_variables.h"

size_t twin_count(const TwinVariables *table) {
    return table->n_real + table->n_integer + table->n_boolean + table->n_string;
}

void twin_describe(const TwinVariables *table, Fmi2ModelInfo *info) {
    info->guid = table->guid;
    info->n_real = table->n_real;
    info->n_integer = table->n_integer;
    info->n_boolean = table->n_boolean;
    info->n_string = table->n_string;
}

Fmi2Role twin_variable(const TwinVariables *table, size_t vr, const char **name) {
    if (vr >= twin_count(table)) return FMI2_NO_VARIABLE;
    *name = table->variables[vr].name;
    return table->variables[vr].role;
}

void twin_reset(const TwinVariables *table, Fmi2Instance *inst) {
    const size_t n_real = table->n_real, n_integer = table->n_integer, n_boolean = table->n_boolean;
    for (size_t vr = 0; vr < twin_count(table); vr++) {
        const TwinVariable *v = &table->variables[vr];
        if (vr < n_real) inst->reals[vr] = v->start;
        else if (vr < n_real + n_integer) inst->integers[vr - n_real] = (int)v->start;
        else if (vr < n_real + n_integer + n_boolean) inst->booleans[vr - n_real - n_integer] = v->start != 0.0;
        else snprintf(fmi2_string(inst, vr), fmi2_string_capacity(inst) + 1, "%s", v->string_start);
    }
}

void twin_index(const TwinVariables *table, size_t *vr_of, int count) {
    for (size_t vr = 0; vr < twin_count(table); vr++)
        if (table->variables[vr].meaning >= 0 && table->variables[vr].meaning < count) vr_of[table->variables[vr].meaning] = vr;
}

fmi2Status twin_refuse(Fmi2Instance *inst, const TwinVariable *v, const char *given, const char *why,
                       const char *rebuild, const char *function) {
    char start[64];
    if (v->string_start != NULL) snprintf(start, sizeof start, "%s", v->string_start);
    else snprintf(start, sizeof start, "%.17g", v->start);
    return fmi2_fail(inst, "%s: %s is %s in this native FMU, whose %s designed at build time; got %s (rebuild it with "
                     "%s for another value)", function, v->name, start, why, given, rebuild);
}
