/* The shaped bang-bang move of paper 002 in C (motion_design.c): runtime/shaped_bang_bang.py and
 * runtime/motion.py's PiecewiseAcceleration, operation for operation, so that the native profile
 * generator re-designs a bang-bang move from its parameters as the pythonfmu one does. */
#ifndef MOTION_DESIGN_H
#define MOTION_DESIGN_H

#include <stddef.h>

/* The move: acceleration levels[k] on [breaks[k], breaks[k + 1]), the velocity and position
 * accumulated at every break, times within tolerance of a break at it. */
typedef struct {
    size_t n_levels;
    const double *breaks, *velocity, *position;  /* n_levels + 1 each */
    const double *levels;                        /* n_levels */
    double tolerance;
} MotionPath;

/* Doubles motion_shaped_bang_bang stores for a shaper of count impulses. */
#define MOTION_DOUBLES(count) (4 * (4 * (size_t)(count) + 1))

/* The rigid-body bang-bang over distance at |a| <= acceleration (bang-coast-bang when speed > 0
 * limits it) convolved with the impulses: path's arrays in storage (MOTION_DOUBLES(count) doubles);
 * scratch holds 4 count doubles. */
void motion_shaped_bang_bang(MotionPath *path, double *storage, double *scratch, double distance, double acceleration,
                             double speed, const double *times, const double *amplitudes, int count);

#endif
