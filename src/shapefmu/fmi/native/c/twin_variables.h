/* What the twins' model parts (the EKF tuner, the STOS controller, the profile generator, the
 * ScheduledShaper, the TrackedShaper) do with the variable table their generated model.c lists (model.h's VariableTable,
 * which the layer describes, looks up and resets): find each meaning's value reference, refuse a value
 * out of a variable's range or a design parameter set to another value than the one the design was
 * made for at build time, and take a step of the sample clock with their inputs. */
#ifndef TWIN_VARIABLES_H
#define TWIN_VARIABLES_H

#include "model.h"

/* vr of each meaning (meanings below count) into vr_of. */
void twin_index(const VariableTable *table, size_t *vr_of, int count);
/* A design parameter set to another value than its build value (given, as the user wrote it):
 * refused with a message saying why (what was made at build time) and how to rebuild. */
ModelStatus twin_refuse(ModelInstance *inst, const VariableRow *v, const char *given, const char *why,
                        const char *rebuild, const char *function);
/* MODEL_OK if ok and value is finite, else refused: "<function>: <name> must be <valid>, got <value>". */
ModelStatus twin_range(ModelInstance *inst, const char *name, double value, int ok, const char *valid,
                       const char *function);
/* The step (t, t + h] of clock with the n inputs held over it: refused (nothing changed) if it spans
 * more than MAX_SAMPLES_PER_STEP samples, else taken (clock_take: commit(context, inputs) per sample). */
ModelStatus twin_clock_step(ModelInstance *inst, SampleClock *clock, double t, double h, const double *inputs, int n,
                            void (*commit)(void *context, const double *inputs), void *context, const char *function);

#endif
