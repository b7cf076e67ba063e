/* The types the parts of the C planner share with its interface (jerk_planner.h): the limits of
 * one axis, a mode, a shaper, the phases of one axis, the sizes, and the workspace's name (its
 * buffers: jerk_internal.h). */
#ifndef JERK_TYPES_H
#define JERK_TYPES_H

#define JP_MAX_AXES 8
#define JP_MAX_MODES 4       /* per axis */
#define JP_MAX_PHASES 256    /* per axis and move */
#define JP_MAX_IMPULSES 64   /* per ceiling shaper */
#define JP_MAX_SHAPERS 8     /* ceiling shapers per axis, shortest first */

typedef struct {
    double v_max, v_min, a_max, a_min, j_max;  /* v_min, a_min < 0 */
} JpLimits;

typedef struct {
    double omega, zeta, delta, vtol;  /* rad/s; band +- delta omega; bound vtol of the rigid residual */
} JpMode;

typedef struct {
    int count;  /* 0: no shaper (the axis has no modes) */
    double times[JP_MAX_IMPULSES], amplitudes[JP_MAX_IMPULSES];
} JpShaper;

typedef struct {
    int count;
    double start[3];  /* p, v, a */
    double durations[JP_MAX_PHASES], jerks[JP_MAX_PHASES];
} JpAxisPhases;

typedef struct JpWorkspace JpWorkspace;  /* every buffer of a plan (jerk_planner.h) */

#endif
