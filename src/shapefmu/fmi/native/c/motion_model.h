/* The contract between the native profile generator's model part (motion_fmi2.c, written once) and
 * the model.c that shapefmu.fmi.native.profiles generates for one build: the variables of the
 * pythonfmu ProfileGenerator with their start values and meanings, and the move designed at build
 * time (runtime/motion.py's PiecewiseAcceleration: breaks, levels, the velocity and position
 * accumulated at every break, the snap tolerance). */
#ifndef MOTION_MODEL_H
#define MOTION_MODEL_H

#include "twin_variables.h"

typedef enum {
    MOTION_DESIGN,        /* every parameter the move is designed from: keeps its build value */
    MOTION_T_START,       /* t_start, s; negative: wait for the start input */
    MOTION_START,         /* input start: the move starts where it is >= 0.5 */
    MOTION_POSITION, MOTION_VELOCITY, MOTION_ACCELERATION,
    MOTION_MEANINGS
} MotionMeaning;

/* The move: acceleration levels[k] on [breaks[k], breaks[k + 1]), the velocity and position
 * accumulated at every break, times within tolerance of a break at it. */
typedef struct {
    size_t n_levels;
    const double *breaks, *velocity, *position;  /* n_levels + 1 each */
    const double *levels;                        /* n_levels */
    double tolerance;
} MotionPath;

extern const TwinVariables motion_variables;
extern const MotionPath motion_path;

#endif
