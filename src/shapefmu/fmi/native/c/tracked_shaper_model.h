/* The contract between the native TrackedShaper's model part (tracked_shaper_part.c, written once)
 * and the model.c that shapefmu.fmi.native.tracked_shaper generates for one build: its variables
 * with their start values and what each one means. Value references follow model.h (Real,
 * Integer, Boolean, String); the names, units and start values are those of the pythonfmu
 * TrackedShaper. */
#ifndef TRACKED_SHAPER_MODEL_H
#define TRACKED_SHAPER_MODEL_H

#include "twin_variables.h"

typedef enum {
    TRACK_KIND, TRACK_ORDER, TRACK_VTOL,       /* the shaper: kind (closed-form), n of zv_dn, vtol */
    TRACK_F0, TRACK_ZETA0,                     /* the guess the shaper starts with, Hz and 1 */
    TRACK_NOISE, TRACK_AMPLITUDE, TRACK_DRIFT, /* the EKF's tuning (runtime/tracked_shaper.py, tracking_tuning) */
    TRACK_GAIN, TRACK_REST,                    /* the measurement's equilibrium: gain * (command - rest) */
    TRACK_BAND_LOW, TRACK_BAND_HIGH, TRACK_ZETA_MAX,  /* a plausible estimate */
    TRACK_OMEGA_TOL, TRACK_SIGMA_TOL,          /* when an estimate is taken */
    TRACK_RESOLUTION,                          /* when the shaper re-designs */
    TRACK_PERIOD, TRACK_REST_COMMAND,          /* Ts, s; u0 */
    TRACK_COMMAND, TRACK_MEASUREMENT,          /* inputs u, measurement */
    TRACK_OUTPUT, TRACK_FREQUENCY, TRACK_DAMPING,  /* outputs y, f (Hz), zeta */
    TRACK_MEANINGS
} TrackedMeaning;

extern const VariableTable tracked_shaper_model;

#endif
