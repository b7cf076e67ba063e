/* The contract between the native EKF tuner's model part (ekf_tuner_part.c, written once) and the
 * model.c that shapefmu.fmi.native.ekf_tuner generates for one build: its variables with their
 * start values and what each one means. Value references follow model.h (Real, Integer,
 * Boolean, String); the names, units and start values are those of the pythonfmu EKFTuner. */
#ifndef EKF_TUNER_MODEL_H
#define EKF_TUNER_MODEL_H

#include "twin_variables.h"

typedef enum {
    EKF_KIND,          /* kind: the closed-form shaper designed for the estimate */
    EKF_ORDER,         /* n of zv_dn */
    EKF_PERIOD,        /* Ts, s */
    EKF_OMEGA0,        /* omega0, rad/s: the EKF's first guess */
    EKF_AMPLITUDE,     /* amplitude: the vibration scale the tuning is relative to */
    EKF_RETUNE,        /* retune_fraction */
    EKF_COMMAND,       /* u */
    EKF_VIBRATION,     /* vibration */
    EKF_OUTPUT,        /* y */
    EKF_OMEGA_EST,     /* omega_est, rad/s */
    EKF_ZETA_EST,      /* zeta_est */
    EKF_CONVERGED,     /* converged, 0 or 1 */
    EKF_MEANINGS
} EkfMeaning;


extern const VariableTable ekf_tuner_model;

#endif
