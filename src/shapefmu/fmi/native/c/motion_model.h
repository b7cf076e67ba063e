/* The contract between the native profile generator's model part (motion_part.c, written once) and
 * the model.c that shapefmu.fmi.native.profiles generates for one build: the variables of the
 * pythonfmu ProfileGenerator with their start values and meanings, the move designed at build time
 * (runtime/motion.py's PiecewiseAcceleration: breaks, levels, the velocity and position accumulated
 * at every break, the snap tolerance) and, for a shaped bang-bang, its shaper. */
#ifndef MOTION_MODEL_H
#define MOTION_MODEL_H

#include "motion_design.h"
#include "twin_variables.h"

#define MOTION_MAX_MODES 4

typedef enum {
    MOTION_DESIGN,        /* a parameter of the twin-pulse and time-frequency designs: keeps its build value */
    MOTION_PROFILE,       /* profile: keeps its build value */
    MOTION_DISTANCE, MOTION_SPEED, MOTION_ACCELERATION_LIMIT,  /* the bang-bang, re-designed in C */
    MOTION_SHAPER, MOTION_ORDER, MOTION_MODES,                 /* its shaper, re-designed if closed-form */
    MOTION_OMEGA1, MOTION_OMEGA2, MOTION_OMEGA3, MOTION_OMEGA4, MOTION_ZETA1, MOTION_ZETA2, MOTION_ZETA3, MOTION_ZETA4,
    MOTION_T_START,       /* t_start, s; negative: wait for the start input */
    MOTION_START,         /* input start: the move starts where it is >= 0.5 */
    MOTION_POSITION, MOTION_VELOCITY, MOTION_ACCELERATION,
    MOTION_MEANINGS
} MotionMeaning;

/* A bang-bang build: its shaper's impulses (the design layer's, for any kind), and whether the
 * shaper is none or a kind shaper_designs.c designs, so that it may change with its modes. */
typedef struct {
    int bang_bang, closed_form, count;
    const double *times, *amplitudes;
} MotionShaper;

extern const VariableTable motion_variables;
extern const MotionPath motion_path;      /* the build's move */
extern const MotionShaper motion_shaper;

#endif
