/* The contract between the native STOS controller's model part (stos_fmi2.c, written once) and the
 * model.c that shapefmu.fmi.native.stos generates for one build: the variables of the pythonfmu
 * STOSController with their start values and meanings (StosMeaning), and the switching curves
 * designed at build time (runtime/stos.py stos_curves over the build's shaper). */
#ifndef STOS_MODEL_H
#define STOS_MODEL_H

#include "stos_law.h"
#include "twin_variables.h"

typedef enum {
    STOS_DESIGN,      /* b, U, damping, kind, n, n_modes, f[i], zeta[i]: the curves' build values */
    STOS_PERIOD,      /* Ts, s: the sampling period, also the settle law's and the sub-sample one's */
    STOS_SETTLE,      /* settle: hand over to the linear settle law near the target */
    STOS_KP, STOS_KD, STOS_KI, STOS_X_ENTER, STOS_V_ENTER, STOS_X_EXIT, STOS_V_EXIT,
    STOS_TARGET, STOS_POSITION, STOS_VELOCITY,  /* inputs target, x_r, x_r_dot */
    STOS_OUTPUT,      /* u */
    STOS_MEANINGS
} StosMeaning;

extern const TwinVariables stos_variables;
extern const StosCurves stos_curves;

#endif
