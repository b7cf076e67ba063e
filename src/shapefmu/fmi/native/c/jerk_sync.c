/* A profile of a prescribed duration (runtime/jerk_duration.py) and the axes ending together (runtime/jerk_sync.py).
 * Part of the C twin of the motion planner (jerk_planner.h); the order of the floating-point operations
 * follows the Python code, so that both plan the same move to rounding. */
#include "jerk_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------------
 * Step 2: a profile of a prescribed duration (profile_of_duration and its helpers) */

/* _hold_profile: 1 and error, phases; 0 when the changes outlast T */
static int hold_profile(const Problem *pr, double T, double level, double va, double *error, Ph *out) {
    const JpLimits *lim = &pr->lim;
    double tf[3], jf[3], ts[3], js[3];
    jpi_velocity_change(pr->v0, pr->a0, va, level, lim->a_max, lim->a_min, lim->j_max, tf, jf);
    double t_first = jpi_sum3(tf);
    double hold = 0.0;
    for (int it = 0; it < 100; it++) {
        jpi_velocity_change(va + level * hold, level, pr->vf, pr->af, lim->a_max, lim->a_min, lim->j_max, ts, js);
        double updated = T - t_first - jpi_sum3(ts);
        if (updated < 0.0) {
            if (updated < -pr->tol_t) return 0;
            updated = 0.0;
        }
        if (updated == hold || level == 0.0) { hold = updated; break; }
        hold = updated;
    }
    double d[7] = {tf[0], tf[1], tf[2], hold, ts[0], ts[1], ts[2]};
    double j[7] = {jf[0], jf[1], jf[2], 0.0, js[0], js[1], js[2]};
    jpi_ph_set(out, pr->p0, pr->v0, pr->a0, d, j, 7);
    *error = out->p[7] - pr->pf;
    return 1;
}

static double hold_time(const Problem *pr, double level, double va) {
    const JpLimits *lim = &pr->lim;
    double t1[3], j1[3], t2[3], j2[3];
    jpi_velocity_change(pr->v0, pr->a0, va, level, lim->a_max, lim->a_min, lim->j_max, t1, j1);
    jpi_velocity_change(va, level, pr->vf, pr->af, lim->a_max, lim->a_min, lim->j_max, t2, j2);
    return jpi_sum3(t1) + jpi_sum3(t2);
}

static double edge(const Problem *pr, double level, double T, double inside, double outside) {
    for (int it = 0; it < 100; it++) {
        double middle = 0.5 * (inside + outside);
        if (middle == inside || middle == outside) break;
        if (hold_time(pr, level, middle) <= T) inside = middle; else outside = middle;
    }
    return inside;
}

/* _hold_points: edges and points (sorted) */
static void hold_points(const Problem *pr, double T, double level, const double *seeds, int n_seeds,
                        double *edges, int *n_edges, double *points, int *n_points) {
    const JpLimits *lim = &pr->lim;
    double grid[SAMPLES + 1 + 16];
    int n = 0;
    for (int k = 0; k <= SAMPLES; k++) grid[n++] = lim->v_min + (lim->v_max - lim->v_min) * k / SAMPLES;
    for (int k = 0; k < n_seeds && n < SAMPLES + 1 + 16; k++) grid[n++] = seeds[k];
    qsort(grid, (size_t)n, sizeof(double), jpi_cmp_double);
    int m = 0;
    for (int k = 0; k < n; k++) if (m == 0 || grid[k] != grid[m - 1]) grid[m++] = grid[k];
    int spare[SAMPLES + 1 + 16];
    for (int k = 0; k < m; k++) spare[k] = hold_time(pr, level, grid[k]) <= T;
    int ne = 0, np = 0;
    for (int k = 0; k < m; k++) {
        if (spare[k]) points[np++] = grid[k];
        if (k + 1 < m && spare[k] != spare[k + 1]) {
            double inside = spare[k] ? grid[k] : grid[k + 1], outside = spare[k] ? grid[k + 1] : grid[k];
            edges[ne++] = edge(pr, level, T, inside, outside);
        }
    }
    for (int k = 0; k < ne; k++) points[np++] = edges[k];
    qsort(points, (size_t)np, sizeof(double), jpi_cmp_double);
    *n_edges = ne; *n_points = np;
}

static int passing_velocities(const Ph *ph, double level, double *out) {
    int count = 0;
    for (int k = 0; k < ph->n && count < 16; k++) {
        double t = ph->d[k], j = ph->j[k], a0 = ph->a[k], a1 = ph->a[k + 1];
        if (j != 0.0 && min2(a0, a1) <= level && level <= max2(a0, a1)) {
            double s = (level - a0) / j;
            out[count++] = ph->v[k] + s * (a0 + s * j / 2.0);
        } else if (j == 0.0 && t > 0.0 && a0 == level) {
            out[count++] = ph->v[k];
        }
    }
    return count;
}

/* _refine_hold: 1 and *out, 0 for None */
static int refine_hold(const Problem *pr, double T, double level, double low, double high, double error_low,
                       const Ph *phases_low, Ph *out) {
    *out = *phases_low;
    for (int it = 0; it < 200; it++) {
        double middle = 0.5 * (low + high);
        if (middle == low || middle == high || error_low == 0.0) break;
        double error;
        if (!hold_profile(pr, T, level, middle, &error, out)) return 0;
        if ((error < 0.0) == (error_low < 0.0)) { low = middle; error_low = error; } else high = middle;
    }
    return 1;
}

static int bisect_meeting(const Problem *pr, double T, double low_level, double low_va, double high_level,
                          double high_va, Ph *out, Ph *tmp) {
    double e1, e2;
    if (!hold_profile(pr, T, low_level, low_va, &e1, out) || !hold_profile(pr, T, high_level, high_va, &e2, tmp)
        || e1 * e2 > 0.0)
        return 0;
    double error_low = e1;
    double edges[MAX_POINTS], points[MAX_POINTS];
    for (int it = 0; it < 100; it++) {
        double level = 0.5 * (low_level + high_level);
        if (level == low_level || level == high_level) break;
        double guess = 0.5 * (low_va + high_va);
        int ne, np;
        hold_points(pr, T, level, NULL, 0, edges, &ne, points, &np);
        if (ne == 0) return 0;
        double va = edges[0];
        for (int k = 1; k < ne; k++) if (fabs(edges[k] - guess) < fabs(va - guess)) va = edges[k];
        double error;
        if (!hold_profile(pr, T, level, va, &error, out)) return 0;
        if ((error < 0.0) == (error_low < 0.0)) { low_level = level; low_va = va; error_low = error; }
        else { high_level = level; high_va = va; }
    }
    return 1;
}

static int meeting_profile(const Problem *pr, double T, Ph *out, Ph *tmp, JpWorkspace *ws) {
    const JpLimits *lim = &pr->lim;
    double span = lim->v_max - lim->v_min;
    enum { LEVELS = 2 * SAMPLES - 1 };
    double (*table)[MAX_POINTS] = ws->table;
    int counts[LEVELS];
    double levels[LEVELS], points[MAX_POINTS];
    for (int k = 1; k < 2 * SAMPLES; k++) levels[k - 1] = lim->a_min + (lim->a_max - lim->a_min) * k / (2 * SAMPLES);
    for (int k = 0; k < LEVELS; k++) {
        int np;
        hold_points(pr, T, levels[k], NULL, 0, table[k], &counts[k], points, &np);
    }
    for (int k = 0; k + 1 < LEVELS; k++) {
        for (int i = 0; i < counts[k]; i++) {
            double va = table[k][i];
            if (counts[k + 1] == 0) continue;
            double nearest = table[k + 1][0];
            for (int q = 1; q < counts[k + 1]; q++)
                if (fabs(table[k + 1][q] - va) < fabs(nearest - va)) nearest = table[k + 1][q];
            if (fabs(nearest - va) > 0.1 * span) continue;
            if (bisect_meeting(pr, T, levels[k], va, levels[k + 1], nearest, out, tmp)
                && jpi_accept(pr, out->d, out->j, out->n, tmp)) {
                *out = *tmp;
                return 1;
            }
        }
    }
    return 0;
}

/* _with_hold: 1 and *out, 0 for None */
static int with_hold(const Problem *pr, double T, double level, const Ph *near, Ph *out, JpWorkspace *ws) {
    const JpLimits *lim = &pr->lim;
    if (!(lim->a_min < level && level < lim->a_max) && level != 0.0) return 0;
    Ph *first = &ws->first, *second = &ws->second, *refined = &ws->refined;
    double edges[MAX_POINTS], points[MAX_POINTS], seeds[16];
    int n_seeds = near != NULL ? passing_velocities(near, level, seeds) : 0;
    int ne, np;
    hold_points(pr, T, level, seeds, n_seeds, edges, &ne, points, &np);
    double e_prev = 0.0;
    int ok_prev = 0;
    for (int k = 0; k < np; k++) {
        double e_now;
        int ok_now = hold_profile(pr, T, level, points[k], &e_now, second);
        if (k > 0 && ok_prev && ok_now && !(e_prev * e_now > 0.0)) {
            if (refine_hold(pr, T, level, points[k - 1], points[k], e_prev, first, refined)
                && jpi_accept(pr, refined->d, refined->j, refined->n, out))
                return 1;
        }
        e_prev = e_now; ok_prev = ok_now; *first = *second;
    }
    return 0;
}

/* profile_of_duration: 1 and *out, 0 for None */
static int profile_of_duration(const Problem *pr, double T, const Ph *near, Ph *out, JpWorkspace *ws) {
    const JpLimits *lim = &pr->lim;
    double levels[64];
    int nl = 0;
    levels[nl++] = 0.0; levels[nl++] = pr->af; levels[nl++] = pr->a0; levels[nl++] = 0.5 * (pr->a0 + pr->af);
    if (near != NULL) {  /* Python: [a for a in near.a[1:-1] if a not in levels], levels as they were */
        for (int k = 1; k < near->n; k++) {
            int seen = 0;
            for (int i = 0; i < 4; i++) if (levels[i] == near->a[k]) seen = 1;
            if (!seen) levels[nl++] = near->a[k];
        }
    }
    for (int k = 1; k < 2 * SAMPLES; k++) levels[nl++] = lim->a_min + (lim->a_max - lim->a_min) * k / (2 * SAMPLES);
    for (int l = 0; l < nl; l++) if (with_hold(pr, T, levels[l], near, out, ws)) return 1;
    if (meeting_profile(pr, T, out, &ws->meeting, ws)) return 1;
    for (int k = 1; k < 8 * SAMPLES; k++) {
        if (k % 4 == 0) continue;
        if (with_hold(pr, T, lim->a_min + (lim->a_max - lim->a_min) * k / (8 * SAMPLES), near, out, ws)) return 1;
    }
    return 0;
}

/* ------------------------------------------------------------------------------------------------
 * Axes together (jerk_sync) */


int jpi_check_start_within(double *state, const JpLimits *lim, char *message, int size, int axis) {
    double p = state[0], v = state[1], a = state[2];
    double a_tol = 1e-9 * max2(lim->a_max, -lim->a_min), v_tol = 1e-9 * max2(lim->v_max, -lim->v_min);
    (void)p;
    if (!(lim->a_min - a_tol <= a && a <= lim->a_max + a_tol)) {
        snprintf(message, (size_t)size, "axis %d: initial acceleration must be in [%.12g, %.12g], got %.12g", axis,
                 lim->a_min, lim->a_max, a);
        return -1;
    }
    a = min2(max2(a, lim->a_min), lim->a_max);
    double reach = v + a * fabs(a) / (2.0 * lim->j_max);
    if (!(lim->v_min - v_tol <= reach && reach <= lim->v_max + v_tol)) {
        snprintf(message, (size_t)size, "axis %d: initial velocity %.12g with acceleration %.12g reaches %.12g before "
                 "the acceleration can be brought to zero; it must stay in [%.12g, %.12g]", axis, v, a, reach,
                 lim->v_min, lim->v_max);
        return -1;
    }
    state[1] = min2(max2(v, lim->v_min), lim->v_max);
    state[2] = a;
    return 0;
}

int jpi_rigid_blocks(Rigid *rg, int axes, double (*states)[3], double (*targets)[3], const JpLimits *limits,
                        JpWorkspace *ws) {
    rg->axes = axes;
    for (int i = 0; i < axes; i++) {
        jpi_problem_set(&rg->problems[i], states[i], targets[i], &limits[i]);
        if (jpi_block_of(&rg->problems[i], &rg->blocks[i], ws->extremal) != 0) return -1;
    }
    return 0;
}

/* profiles_lasting: 1 and out[axes], 0 for None */
int jpi_profiles_lasting(const Rigid *rg, double T, int owner, Ph *out, JpWorkspace *ws) {
    for (int i = 0; i < rg->axes; i++) if (jpi_blocked(&rg->blocks[i], T)) return 0;
    for (int i = 0; i < rg->axes; i++) {
        const Block *b = &rg->blocks[i];
        if (i == owner) {
            if (T == jpi_t_min(b)) out[i] = b->fastest;
            else {
                int hit = 0;
                for (int q = 0; q < b->intervals; q++) if (T == b->right[q]) { out[i] = b->at_right[q]; hit = 1; break; }
                if (!hit) return 0;
            }
        } else if (T - jpi_t_min(b) <= rg->problems[i].tol_t) {
            out[i] = b->fastest;
        } else if (!profile_of_duration(&rg->problems[i], T, &b->fastest, &out[i], ws)) {
            return 0;
        }
    }
    return 1;
}


static int cmp_candidate(const void *x, const void *y) {
    const Candidate *a = (const Candidate *)x, *b = (const Candidate *)y;
    if (a->t != b->t) return (a->t > b->t) - (a->t < b->t);
    return a->axis - b->axis;
}

int jpi_candidates(const Rigid *rg, Candidate *out) {
    double floor = 0.0;
    for (int i = 0; i < rg->axes; i++) floor = max2(floor, jpi_t_min(&rg->blocks[i]));
    Candidate all[3 * JP_MAX_AXES];
    int n = 0;
    for (int i = 0; i < rg->axes; i++) {
        all[n].t = jpi_t_min(&rg->blocks[i]); all[n++].axis = i;
        for (int q = 0; q < rg->blocks[i].intervals; q++) { all[n].t = rg->blocks[i].right[q]; all[n++].axis = i; }
    }
    qsort(all, (size_t)n, sizeof(Candidate), cmp_candidate);
    int count = 0;
    for (int k = 0; k < n; k++) {
        if (all[k].t < floor) continue;
        int any = 0;
        for (int i = 0; i < rg->axes; i++) if (jpi_blocked(&rg->blocks[i], all[k].t)) any = 1;
        if (!any) out[count++] = all[k];
    }
    return count;
}

int jpi_synchronise(Rigid *rg, int axes, double (*states)[3], double (*targets)[3], const JpLimits *limits,
                       double *T, Ph *out, JpWorkspace *ws) {
    if (jpi_rigid_blocks(rg, axes, states, targets, limits, ws) != 0) return -1;
    Candidate list[3 * JP_MAX_AXES];
    int n = jpi_candidates(rg, list);
    for (int k = 0; k < n; k++) {
        if (jpi_profiles_lasting(rg, list[k].t, list[k].axis, out, ws)) { *T = list[k].t; return 0; }
    }
    return -1;
}

static int along(const double *values, const double *direction, int n, double *c) {
    int k = 0;
    for (int i = 1; i < n; i++) if (fabs(direction[i]) > fabs(direction[k])) k = i;
    *c = values[k] / direction[k];
    double scale = 0.0;
    for (int i = 0; i < n; i++) scale = max2(scale, fabs(values[i]));
    scale = max2(scale, 1e-300);
    for (int i = 0; i < n; i++) if (fabs(values[i] - *c * direction[i]) > 1e-12 * scale) return 0;
    return 1;
}

int jpi_straight_line(Rigid *rg, int axes, double (*states)[3], double (*targets)[3], const JpLimits *limits,
                         double *T, Ph *out, JpWorkspace *ws, char *message, int size) {
    double d[JP_MAX_AXES], direction[JP_MAX_AXES], length = 0.0;
    for (int i = 0; i < axes; i++) { d[i] = targets[i][0] - states[i][0]; length = max2(length, fabs(d[i])); }
    if (length == 0.0) return jpi_synchronise(rg, axes, states, targets, limits, T, out, ws);
    for (int i = 0; i < axes; i++) direction[i] = d[i] / length;
    double path[4], values[JP_MAX_AXES];
    int slot = 0;
    for (int kind = 1; kind <= 2; kind++) {
        for (int which = 0; which < 2; which++) {
            for (int i = 0; i < axes; i++) values[i] = which == 0 ? states[i][kind] : targets[i][kind];
            if (!along(values, direction, axes, &path[slot++])) {
                snprintf(message, (size_t)size, "a straight-line move needs every initial and target velocity and "
                         "acceleration along the line between the positions");
                return -2;
            }
        }
    }
    double v_max = INFINITY, a_max = INFINITY, v_min_n = INFINITY, a_min_n = INFINITY, j_max = INFINITY;
    for (int i = 0; i < axes; i++) {
        double x = direction[i];
        if (x == 0.0) continue;
        double m = fabs(x);
        const JpLimits *lim = &limits[i];
        double up0, up1, up2, up3;
        if (x > 0) { up0 = lim->v_max / m; up1 = lim->a_max / m; up2 = -lim->v_min / m; up3 = -lim->a_min / m; }
        else { up0 = -lim->v_min / m; up1 = -lim->a_min / m; up2 = lim->v_max / m; up3 = lim->a_max / m; }
        v_max = min2(v_max, up0); a_max = min2(a_max, up1); v_min_n = min2(v_min_n, up2); a_min_n = min2(a_min_n, up3);
        j_max = min2(j_max, lim->j_max / m);
    }
    JpLimits path_limits = {v_max, -v_min_n, a_max, -a_min_n, j_max};
    double start[1][3] = {{0.0, path[0], path[2]}}, end[1][3] = {{length, path[1], path[3]}};
    if (jpi_check_start_within(start[0], &path_limits, message, size, 0) != 0) return -2;
    Ph line;
    Rigid single;
    if (jpi_synchronise(&single, 1, start, end, &path_limits, T, &line, ws) != 0) return -1;
    for (int i = 0; i < axes; i++) {
        double jerks[MAXP];
        for (int k = 0; k < line.n; k++) jerks[k] = line.j[k] * direction[i];
        jpi_ph_set(&out[i], states[i][0], states[i][1], states[i][2], line.d, jerks, line.n);
    }
    (void)rg;
    return 0;
}
