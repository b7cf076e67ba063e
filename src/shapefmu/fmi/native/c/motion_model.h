/* The contract between the native profile generator's model part (motion_fmi2.c, written once) and
 * the model.c that shapefmu.fmi.native.profiles generates for one build: the variables of the
 * pythonfmu ProfileGenerator with their start values and meanings, and the move designed at build
 * time (runtime/motion.py's PiecewiseAcceleration: breaks, levels, the velocity and position
 * accumulated at every break, the snap tolerance). */
#ifndef MOTION_MODEL_H
#define MOTION_MODEL_H

#include "fmi2_model.h"

typedef enum {
    MOTION_DESIGN,        /* every parameter the move is designed from: keeps its build value */
    MOTION_T_START,       /* t_start, s; negative: wait for the start input */
    MOTION_START,         /* input start: the move starts where it is >= 0.5 */
    MOTION_POSITION, MOTION_VELOCITY, MOTION_ACCELERATION,
    MOTION_MEANINGS
} MotionMeaning;

typedef struct {
    const char *name;
    Fmi2Role role;
    MotionMeaning meaning;
    double start;              /* Real, Integer and Boolean start values */
    const char *string_start;  /* String start value, else NULL */
} MotionVariable;

typedef struct {
    const char *guid;
    size_t n_real, n_integer, n_boolean, n_string;
    const MotionVariable *variables;  /* by value reference */
    size_t n_levels;
    const double *breaks, *velocity, *position;  /* n_levels + 1 each */
    const double *levels;                        /* n_levels */
    double tolerance;
} MotionModel;

extern const MotionModel motion_model;

#endif
