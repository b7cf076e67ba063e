/* The twins' use of their variable tables (twin_variables.h). */
#include <math.h>
#include <stdio.h>

#include "twin_variables.h"

void twin_index(const VariableTable *table, size_t *vr_of, int count) {
    const size_t n = table->n_real + table->n_integer + table->n_boolean + table->n_string;
    for (size_t vr = 0; vr < n; vr++)
        if (table->rows[vr].meaning >= 0 && table->rows[vr].meaning < count) vr_of[table->rows[vr].meaning] = vr;
}

ModelStatus twin_refuse(ModelInstance *inst, const VariableRow *v, const char *given, const char *why,
                        const char *rebuild, const char *function) {
    char start[64];
    if (v->string_start != NULL) snprintf(start, sizeof start, "%s", v->string_start);
    else snprintf(start, sizeof start, "%.17g", v->start);
    return model_fail(inst, "%s: %s is %s in this native FMU, whose %s designed at build time; got %s (rebuild it with "
                      "%s for another value)", function, v->name, start, why, given, rebuild);
}

ModelStatus twin_range(ModelInstance *inst, const char *name, double value, int ok, const char *valid,
                       const char *function) {
    if (ok && isfinite(value)) return MODEL_OK;
    return model_fail(inst, "%s: %s must be %s, got %g", function, name, valid, value);
}

ModelStatus twin_clock_step(ModelInstance *inst, SampleClock *clock, double t, double h, const double *inputs, int n,
                            void (*commit)(void *context, const double *inputs), void *context, const char *function) {
    const GridStep step = grid_step(&clock->at, clock->ts, t, h);
    if (step.count > (double)MAX_SAMPLES_PER_STEP)
        return model_fail(inst, "%s: communication step h = %g s spans %.0f samples of Ts = %g s; at most %lld "
                          "per step", function, h, step.count, clock->ts, MAX_SAMPLES_PER_STEP);
    clock_take(clock, &step, inputs, n, commit, context);
    return MODEL_OK;
}
