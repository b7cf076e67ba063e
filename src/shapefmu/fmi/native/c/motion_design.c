/* The shaped bang-bang move (motion_design.h), as runtime/shaped_bang_bang.py designs it. */
#include <math.h>
#include <stdlib.h>

#include "exact_sum.h"
#include "motion_design.h"

#define MERGE 1e-12 /* breaks closer than this fraction of the move are one (shaped_bang_bang._MERGE) */
#define SNAP 1e-12  /* PiecewiseAcceleration's snap tolerance, relative */

static int ascending(const void *x, const void *y) {
    const double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* The bang-bang's level at t: 0 before the first and after the last break, right-continuous. */
static double level_at(const double *breaks, const double *levels, int n_levels, double t) {
    if (t < breaks[0] || t >= breaks[n_levels]) return 0.0;
    int k = 0;
    for (int j = 0; j < n_levels; j++)
        if (breaks[j] <= t) k = j;
    return levels[k];
}

void motion_shaped_bang_bang(MotionPath *path, double *storage, double *scratch, double distance, double acceleration,
                             double speed, const double *times, const double *amplitudes, int count) {
    /* bang_bang: +a, -a; or +a, coast, -a under the speed limit (speed 0: none) */
    double breaks[4], levels[3];
    int n_levels;
    if (speed == 0.0 || speed * speed >= distance * acceleration) {
        const double half = sqrt(distance / acceleration);
        breaks[0] = 0.0, breaks[1] = half, breaks[2] = 2.0 * half;
        levels[0] = acceleration, levels[1] = -acceleration;
        n_levels = 2;
    } else {
        const double ramp = speed / acceleration, coast = distance / speed - ramp;
        breaks[0] = 0.0, breaks[1] = ramp, breaks[2] = ramp + coast, breaks[3] = 2.0 * ramp + coast;
        levels[0] = acceleration, levels[1] = 0.0, levels[2] = -acceleration;
        n_levels = 3;
    }
    /* shape: the distinct sums break + t, sorted, merged within MERGE of the move */
    int n_candidates = 0;
    for (int i = 0; i <= n_levels; i++)
        for (int j = 0; j < count; j++) scratch[n_candidates++] = breaks[i] + times[j];
    qsort(scratch, (size_t)n_candidates, sizeof(double), ascending);
    const double span = scratch[n_candidates - 1] - scratch[0], tolerance = MERGE * (span > 1e-300 ? span : 1e-300);
    double *merged = storage;
    int n_merged = 1;
    merged[0] = scratch[0];
    for (int i = 1; i < n_candidates; i++)
        if (scratch[i] - merged[n_merged - 1] > tolerance) merged[n_merged++] = scratch[i];
    double *shaped = merged + n_merged, *terms = scratch;
    for (int i = 0; i + 1 < n_merged; i++) {
        const double middle = 0.5 * (merged[i] + merged[i + 1]);
        for (int j = 0; j < count; j++) terms[j] = amplitudes[j] * level_at(breaks, levels, n_levels, middle - times[j]);
        shaped[i] = exact_sum(terms, count);
    }
    /* PiecewiseAcceleration: velocity and position at every break */
    const int n = n_merged - 1;
    double *velocity = shaped + n, *position = velocity + n_merged;
    velocity[0] = 0.0, position[0] = 0.0;
    for (int k = 0; k < n; k++) {
        const double s = merged[k + 1] - merged[k], v = velocity[k], p = position[k], a = shaped[k];
        velocity[k + 1] = v + a * s;
        position[k + 1] = p + v * s + 0.5 * a * s * s;
    }
    const double first = fabs(merged[0]), last = fabs(merged[n]), width = merged[n] - merged[0];
    const double scale = first > last ? first : last;
    path->n_levels = (size_t)n;
    path->breaks = merged, path->levels = shaped, path->velocity = velocity, path->position = position;
    path->tolerance = SNAP * (scale > width ? scale : width);
}
