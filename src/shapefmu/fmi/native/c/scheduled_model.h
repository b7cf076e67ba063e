/* The contract between the native ScheduledShaper's model part (scheduled_part.c, written once) and
 * the model.c that shapefmu.fmi.native.scheduled_shaper generates for one build: the variables of the
 * pythonfmu ScheduledShaper with their start values and what each one means. Value references follow
 * model.h (Real, Integer, Boolean, String); an array's elements (values[i], f[i], zeta[i]) share a
 * meaning and are told apart by their index in the name. */
#ifndef SCHEDULED_MODEL_H
#define SCHEDULED_MODEL_H

#include "twin_variables.h"

/* Rows of the schedule (kinds/scheduled_shaper.py MAX_ROWS). */
#define SCHEDULED_MAX_ROWS 8

typedef enum {
    SCHEDULED_KIND,        /* kind: a closed-form single-mode shaper, re-designed in C */
    SCHEDULED_ORDER,       /* n of zv_dn */
    SCHEDULED_TOLERANCE,   /* vtol: checked as the pythonfmu FMU does; no closed-form kind uses it */
    SCHEDULED_ROWS,        /* n_rows */
    SCHEDULED_VALUE,       /* values[i]: the scheduling value of row i */
    SCHEDULED_FREQUENCY,   /* f[i], Hz */
    SCHEDULED_DAMPING,     /* zeta[i] */
    SCHEDULED_EXTRAPOLATE, /* extrapolate: continue the end rows (a law) instead of holding them */
    SCHEDULED_RESOLUTION,  /* resolution: how far the mode moves before a re-design */
    SCHEDULED_PERIOD,      /* Ts, s */
    SCHEDULED_REST,        /* u0 */
    SCHEDULED_COMMAND,     /* u */
    SCHEDULED_SCHEDULING,  /* scheduling */
    SCHEDULED_OUTPUT,      /* y */
    SCHEDULED_MEANINGS
} ScheduledMeaning;

extern const VariableTable scheduled_model;

#endif
