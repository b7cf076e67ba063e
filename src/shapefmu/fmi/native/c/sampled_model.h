/* The contract between the sampled filters' model part (sampled_part.c, written
 * once) and the model.c that shapefmu.fmi.native.sampled generates for one native Shaper or
 * ShapeFilter FMU: its variables with their start values, and what each one means.
 *
 * The design is made at build time by the design layer and stored as parameters: the impulse
 * times and amplitudes of a Shaper (mapped onto the sample grid here), or the taps of a
 * ShapeFilter. A Shaper of a closed-form kind (zv, zvd, zvdd, zv_dn, mzv) re-designs in C when its
 * kind, n, n_modes, f[i] or zeta[i] change before initialisation; every other design parameter
 * (kind of a design made only at build time, a filter's window, order, ...) keeps its build value.
 */
#ifndef SAMPLED_MODEL_H
#define SAMPLED_MODEL_H

#include "model.h"

typedef enum {
    MEANS_INPUT,             /* u */
    MEANS_OUTPUT,            /* y */
    MEANS_PERIOD_USED,       /* Ts_used: the filter's sampling period (an output) */
    MEANS_PERIOD,            /* Ts of a Shaper: the sampling period, impulses re-gridded to it */
    MEANS_REST,              /* u0 */
    MEANS_IMPULSE_TIME,      /* impulse_time[i], s */
    MEANS_IMPULSE_AMPLITUDE, /* impulse_amplitude[i] */
    MEANS_TAP,               /* tap[i] */
    MEANS_KIND,              /* kind of a Shaper */
    MEANS_ORDER,             /* n of zv_dn */
    MEANS_MODES,             /* n_modes */
    MEANS_FREQUENCY,         /* f[i], Hz */
    MEANS_DAMPING,           /* zeta[i] */
    MEANS_TOLERANCE,         /* vtol, in (0, 1) */
    MEANS_BUILD_VALUE        /* a design parameter that keeps its build value */
} SampledMeaning;

typedef struct {
    int impulses;            /* 1: a Shaper (impulses), 0: a ShapeFilter (taps) */
    int closed_form;         /* a Shaper whose kind re-designs in C */
    int feedthrough;         /* y declared to depend on u (ModelStructure) */
    int max_modes;           /* f[1..max_modes], zeta[1..max_modes] */
    int capacity;            /* impulse_time/impulse_amplitude or tap entries */
    double ts_used;          /* a ShapeFilter's sampling period */
    VariableTable variables; /* by value reference: Real, Integer, Boolean, String; meaning: a SampledMeaning */
} SampledModel;

extern const SampledModel sampled_model;

#endif
