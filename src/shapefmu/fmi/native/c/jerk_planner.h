/* The online jerk-limited multi-axis planner with vibration bounds in C (jerk_axis.c, jerk_sync.c,
 * jerk_vibration.c, jerk_planner.c; their shared internals in jerk_internal.h, the types both
 * see in jerk_types.h): the twin of
 * runtime/jerk_profiles.py, jerk_duration.py, jerk_sync.py, jerk_vibration.py and jerk_planner.py,
 * operation for operation, so that a native FMU plans what the Python kernel plans (to rounding).
 *
 * What differs from the Python kernel: the ceiling's shapers (the catalog shapers of every axis that
 * meet its band and vtol, which depend only on its modes) are designed once by the caller and passed
 * in, shortest first, as a native FMU does at build time; the ringing a re-planned move inherits is given as
 * the jerk history (phases) since the first start rather than as a function. */
#ifndef JERK_PLANNER_H
#define JERK_PLANNER_H

#include "jerk_types.h"

typedef struct {
    int axes;
    double states[JP_MAX_AXES][3], targets[JP_MAX_AXES][3];
    JpLimits limits[JP_MAX_AXES];
    int mode_count[JP_MAX_AXES];
    JpMode modes[JP_MAX_AXES][JP_MAX_MODES];
    int ceiling_count[JP_MAX_AXES];  /* 0 for an axis without modes (or none of the catalog fits) */
    JpShaper ceiling[JP_MAX_AXES][JP_MAX_SHAPERS];
    int straight;              /* along the straight line between the positions */
    double ts;                 /* > 0: the duration a whole number of periods ts */
    const JpAxisPhases *history;  /* NULL, or per axis the jerk since the first start (a re-plan) */
} JpRequest;

typedef struct {
    double duration, rigid_duration, ceiling_duration;  /* ceiling: inf when no shaper keeps the limits and bounds */
    int method;  /* 0 rigid, 1 cancel, 2 shaped */
    int ceiling_choice[JP_MAX_AXES];  /* the index of the ceiling's shaper of every axis */
    JpAxisPhases phases[JP_MAX_AXES];
    double references[JP_MAX_AXES][JP_MAX_MODES], residuals[JP_MAX_AXES][JP_MAX_MODES];
    char message[256];  /* why, when jp_plan returns nonzero */
} JpResult;

/* Every buffer a plan works in, owned by the caller: the planner keeps nothing between calls and no
 * two workspaces share anything, so instances (an FMU's, a host's threads) plan at the same time,
 * each in its own workspace. NULL when out of memory. */
JpWorkspace *jp_workspace_new(void);
void jp_workspace_free(JpWorkspace *workspace);

/* 0 and *result filled; nonzero and result->message on an unreachable target, a start that must
 * break a limit, or a move no planner finds within the limits and bounds. */
int jp_plan(const JpRequest *request, JpResult *result, JpWorkspace *workspace);

/* The synchronised rigid duration alone (the candidate of the blocks), for the comparison with
 * Ruckig; 0 and *duration, or nonzero and message. */
int jp_rigid_duration(const JpRequest *request, double *duration, char *message, int size, JpWorkspace *workspace);

#endif
