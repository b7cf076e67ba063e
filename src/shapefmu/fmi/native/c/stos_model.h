/* The contract between the native STOS controller's model part (stos_part.c, written once) and the
 * model.c that shapefmu.fmi.native.stos generates for one build: the variables of the pythonfmu
 * STOSController with their start values and meanings (StosMeaning), and the build's shaper (the
 * switching curves are designed from it in C, stos_law.c). */
#ifndef STOS_MODEL_H
#define STOS_MODEL_H

#include "stos_law.h"
#include "twin_variables.h"

#define STOS_MAX_MODES 4

typedef enum {
    STOS_B, STOS_U, STOS_DAMPING,       /* the rigid body: the curves are redesigned from them */
    STOS_KIND, STOS_ORDER, STOS_MODES,  /* the shaper: redesigned in C if its build kind is closed-form */
    STOS_F1, STOS_F2, STOS_F3, STOS_F4, STOS_ZETA1, STOS_ZETA2, STOS_ZETA3, STOS_ZETA4,
    STOS_PERIOD,      /* Ts, s: the sampling period, also the settle law's and the sub-sample one's */
    STOS_SETTLE,      /* settle: hand over to the linear settle law near the target */
    STOS_KP, STOS_KD, STOS_KI, STOS_X_ENTER, STOS_V_ENTER, STOS_X_EXIT, STOS_V_EXIT,
    STOS_TARGET, STOS_POSITION, STOS_VELOCITY,  /* inputs target, x_r, x_r_dot */
    STOS_OUTPUT,      /* u */
    STOS_MEANINGS
} StosMeaning;

/* The shaper of the build: its impulses (the design layer's, for any kind), and whether its kind is
 * one shaper_designs.c designs, so that kind, n, n_modes, f[i] and zeta[i] may change. */
typedef struct {
    int count, closed_form;
    const double *times, *amplitudes;
} StosShaper;

extern const VariableTable stos_variables;
extern const StosShaper stos_shaper;

#endif
