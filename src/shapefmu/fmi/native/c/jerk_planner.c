/* The planner: the ceiling, the search for the shortest duration that holds every limit and bound, jp_plan and jp_rigid_duration (runtime/jerk_planner.py).
 * Part of the C twin of the motion planner (jerk_planner.h); the order of the floating-point operations
 * follows the Python code, so that both plan the same move to rounding. */
#include "jerk_internal.h"
#include "jerk_planner.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------------
 * The planner (jerk_planner) */

static const double STRETCHES[] = {0.0, 0.0005, 0.001, 0.002, 0.004, 0.007, 0.01, 0.015, 0.02, 0.03, 0.045, 0.06, 0.08,
                                   0.1, 0.13, 0.16, 0.2, 0.25, 0.3, 0.4, 0.5, 0.7, 1.0};
#define HALVINGS 6
#define RETIMED 0.85

/* _within */
static int within(const Ph *ph, const JpLimits *lim, const double *target) {
    const double relative = 1e-9;
    double vl, vh, al, ah;
    jpi_ph_extrema(ph, &vl, &vh, &al, &ah);
    double a_tol = relative * max2(lim->a_max, -lim->a_min), v_tol = relative * max2(lim->v_max, -lim->v_min);
    for (int k = 0; k < ph->n; k++) if (fabs(ph->j[k]) > lim->j_max * (1.0 + relative)) return 0;
    if (ah > lim->a_max + a_tol || al < lim->a_min - a_tol) return 0;
    if (vh > lim->v_max + v_tol || vl < lim->v_min - v_tol) return 0;
    int n = ph->n;
    double p_tol = relative * max2(max2(fabs(target[0] - ph->p[0]), v_tol * jpi_ph_duration(ph)), 1e-300);
    return fabs(ph->p[n] - target[0]) <= p_tol && fabs(ph->v[n] - target[1]) <= v_tol && fabs(ph->a[n] - target[2]) <= a_tol;
}

typedef struct {
    const JpRequest *rq;
    double states[JP_MAX_AXES][3];
    Rigid rigid;
    JpWorkspace *ws;
    char *message;
    int size;
} Planner;

static int plan_rigid(Planner *pl, double (*targets)[3], const JpLimits *limits, double *T, Ph *out) {
    Rigid rg;
    int status;
    if (pl->rq->straight)
        status = jpi_straight_line(&rg, pl->rq->axes, pl->states, targets, limits, T, out, pl->ws, pl->message, pl->size);
    else
        status = jpi_synchronise(&rg, pl->rq->axes, pl->states, targets, limits, T, out, pl->ws);
    if (status == -1)
        snprintf(pl->message, (size_t)pl->size, "unreachable target: no common duration found in which every axis "
                 "reaches its target within its limits");
    return status;
}

/* _shaped_fixed_point: 1 and shaped[], 0 for None */
static int shaped_fixed_point(Planner *pl, const JpLimits *planned, const JpShaper *const *shapers, Ph *shaped) {
    const JpRequest *rq = pl->rq;
    int axes = rq->axes;
    double corrected[JP_MAX_AXES][3];
    memcpy(corrected, rq->targets, sizeof(corrected));
    Ph *rigid = pl->ws->fixed_point;
    char ignored[256];
    for (int it = 0; it < 40; it++) {
        double T;
        char *message = pl->message;
        pl->message = ignored;  /* a rigid move the narrowed limits cannot plan is a missing ceiling */
        int status = plan_rigid(pl, corrected, planned, &T, rigid);
        pl->message = message;
        if (status != 0) return 0;
        double error = 0.0;
        for (int i = 0; i < axes; i++) {
            if (shapers[i] != NULL) { if (jpi_convolve_jerk(&rigid[i], shapers[i], &shaped[i], pl->ws) != 0) return 0; }
            else shaped[i] = rigid[i];
            int n = shaped[i].n;
            double p = shaped[i].p[n], v = shaped[i].v[n];
            const double *target = rq->targets[i];
            corrected[i][0] += target[0] - p;
            corrected[i][1] += target[1] - v;
            error = max2(error, max2(fabs(target[0] - p) / max2(fabs(target[0] - pl->states[i][0]), 1e-300),
                                     fabs(target[1] - v) / max2(rq->limits[i].v_max, -rq->limits[i].v_min)));
        }
        if (error <= 1e-13) break;
    }
    return 1;
}

/* _within_limits: 1 and (duration, shaped[]), 0 for None */
static int within_limits(Planner *pl, const JpShaper *const *shapers, double *duration, Ph *shaped) {
    const JpRequest *rq = pl->rq;
    int axes = rq->axes;
    JpLimits planned[JP_MAX_AXES];
    memcpy(planned, rq->limits, sizeof(JpLimits) * (size_t)axes);
    for (int round = 0; round < 4; round++) {
        if (!shaped_fixed_point(pl, planned, shapers, shaped)) return 0;
        double T = -INFINITY;
        for (int i = 0; i < axes; i++) T = max2(T, jpi_ph_duration(&shaped[i]));
        int all = 1;
        for (int i = 0; i < axes; i++) {
            Ph pad;
            if (jpi_padded(&shaped[i], T, &pad) != 0) return 0;
            shaped[i] = pad;
            if (!within(&shaped[i], &rq->limits[i], rq->targets[i])) all = 0;
        }
        if (all) { *duration = T; return 1; }
        for (int i = 0; i < axes; i++) {
            double vl, vh, al, ah;
            jpi_ph_extrema(&shaped[i], &vl, &vh, &al, &ah);
            const JpLimits *lim = &rq->limits[i];
            double high = planned[i].v_max - max2(vh - lim->v_max, 0.0) * 1.001;
            double low = planned[i].v_min + max2(lim->v_min - vl, 0.0) * 1.001;
            if (high <= 0.0 || low >= 0.0) return 0;
            planned[i].v_max = high;
            planned[i].v_min = low;
        }
    }
    return 0;
}

/* _meets */
static int meets(const Ph *phases, double T, const JpRequest *rq, double (*bounds)[JP_MAX_MODES], const History *ringing) {
    for (int i = 0; i < rq->axes; i++)
        for (int q = 0; q < rq->mode_count[i]; q++)
            if (!(jpi_worst_amplitude(&phases[i], T, &rq->modes[i][q], ringing ? &ringing[i] : NULL) <= bounds[i][q] * (1.0 + 1e-9)))
                return 0;
    return 1;
}

/* shaped_move: 1 and (duration, shaped[], choice[]), 0 for None */
static int shaped_move(Planner *pl, double (*bounds)[JP_MAX_MODES], const History *ringing, double *duration,
                       Ph *shaped, int *choice) {
    const JpRequest *rq = pl->rq;
    int axes = rq->axes, most = 1;
    for (int i = 0; i < axes; i++) {
        if (rq->mode_count[i] > 0 && rq->ceiling_count[i] == 0) return 0;
        if (rq->ceiling_count[i] > most) most = rq->ceiling_count[i];
    }
    for (int k = 0; k < most; k++) {
        const JpShaper *shapers[JP_MAX_AXES];
        for (int i = 0; i < axes; i++) {
            int count = rq->mode_count[i] > 0 ? rq->ceiling_count[i] : 0;
            choice[i] = count ? (k < count ? k : count - 1) : -1;
            shapers[i] = count ? &rq->ceiling[i][choice[i]] : NULL;
        }
        if (within_limits(pl, shapers, duration, shaped) && meets(shaped, *duration, rq, bounds, ringing)) return 1;
    }
    return 0;
}

/* _cancelled: 1 and *out */
static int cancelled(Planner *pl, int axis, double T, const Ph *rigid, const double *bounds, const History *ringing,
                     int doublets, Ph *out) {
    const JpRequest *rq = pl->rq;
    const JpMode *modes = rq->modes[axis];
    int n_modes = rq->mode_count[axis];
    double omegas[MAX_FREQ], zetas[MAX_FREQ];
    int freqs = 0;
    for (int q = 0; q < n_modes; q++) {
        if (modes[q].delta == 0.0) { omegas[freqs] = modes[q].omega; zetas[freqs++] = modes[q].zeta; }
        else {
            const double xs[3] = {-0.75, 0.0, 0.75};
            for (int r = 0; r < 3; r++) { omegas[freqs] = modes[q].omega * (1.0 + xs[r] * modes[q].delta); zetas[freqs++] = modes[q].zeta; }
        }
    }
    Held pins[8];
    int n_pins = 0;
    double *d = pl->ws->cancelled_d, *j = pl->ws->cancelled_j;
    for (int attempt = 0; attempt < 8; attempt++) {
        int n;
        if (!jpi_cancel(pl->states[axis], rq->targets[axis], &rq->limits[axis], T, modes, n_modes, rigid, ringing, omegas, zetas,
                    freqs, doublets, pins, n_pins, d, j, &n, pl->ws))
            return 0;
        jpi_ph_set(out, pl->states[axis][0], pl->states[axis][1], pl->states[axis][2], d, j, n);
        Held past;
        if (jpi_violation(out, &rq->limits[axis], &past)) { pins[n_pins++] = past; continue; }
        if (!within(out, &rq->limits[axis], rq->targets[axis])) return 0;
        int found = 0;
        double worst_excess = 0.0, worst_omega = 0.0, worst_zeta = 0.0;
        for (int q = 0; q < n_modes; q++) {
            int count = jpi_band_count(&modes[q], T);
            for (int k = 0; k < count; k++) {
                double omega = jpi_band_frequency(&modes[q], T, k, count);
                double excess = jpi_amplitude(out->d, out->j, out->n, T, omega, modes[q].zeta, ringing) - bounds[q];
                if (excess > 0.0 && (!found || excess > worst_excess)) {
                    worst_excess = excess; worst_omega = omega; worst_zeta = modes[q].zeta; found = 1;
                }
            }
        }
        if (!found) return 1;
        if (freqs >= MAX_FREQ) return 0;
        omegas[freqs] = worst_omega; zetas[freqs++] = worst_zeta;
        n_pins = 0;  /* another frequency inserts another doublet: the phases the pins named move */
    }
    return 0;
}

static double on_grid(double T, double ts) { return ts > 0.0 ? ceil(T / ts - 1e-9) * ts : T; }

typedef struct {
    Planner *pl;
    double T0;
    Ph *rigid, *ceiling_phases;
    double ceiling_T;
    int has_ceiling;
    double (*bounds)[JP_MAX_MODES];
    const History *ringing;  /* per axis or NULL */
} Search;

static const History *axis_ringing(const Search *s, int axis) { return s->ringing != NULL ? &s->ringing[axis] : NULL; }

static int attempt(const Search *s, double T, Ph *out) {
    Planner *pl = s->pl;
    const JpRequest *rq = pl->rq;
    if (rq->straight) return 0;
    Ph *lasting = pl->ws->lasting;
    if (T != s->T0) { if (!jpi_profiles_lasting(&pl->rigid, T, -1, lasting, pl->ws)) return 0; }
    else memcpy(lasting, s->rigid, sizeof(Ph) * (size_t)rq->axes);
    for (int i = 0; i < rq->axes; i++) {
        if (rq->mode_count[i] == 0) { out[i] = lasting[i]; continue; }
        int ok = cancelled(pl, i, T, &s->rigid[i], s->bounds[i], axis_ringing(s, i), 1, &out[i]);
        if (!ok && s->has_ceiling && T >= RETIMED * s->ceiling_T)
            ok = cancelled(pl, i, T, &s->ceiling_phases[i], s->bounds[i], axis_ringing(s, i), 0, &out[i]);
        if (!ok) return 0;
    }
    return 1;
}

static void copy_out(const Ph *ph, JpAxisPhases *out) {
    out->count = ph->n;
    out->start[0] = ph->p[0]; out->start[1] = ph->v[0]; out->start[2] = ph->a[0];
    memcpy(out->durations, ph->d, sizeof(double) * (size_t)ph->n);
    memcpy(out->jerks, ph->j, sizeof(double) * (size_t)ph->n);
}

static int plan(const JpRequest *rq, JpResult *result, JpWorkspace *ws) {
    Planner pl = {rq, {{0}}, {0}, ws, result->message, (int)sizeof(result->message)};
    int axes = rq->axes;
    if (axes < 1 || axes > JP_MAX_AXES) {
        snprintf(result->message, sizeof(result->message), "the number of axes must be in [1, %d], got %d", JP_MAX_AXES, axes);
        return -1;
    }
    for (int i = 0; i < axes; i++) {
        memcpy(pl.states[i], rq->states[i], sizeof(pl.states[i]));
        if (jpi_check_start_within(pl.states[i], &rq->limits[i], result->message, (int)sizeof(result->message), i) != 0) return -1;
    }
    History histories[JP_MAX_AXES];
    const History *ringing = NULL;
    if (rq->history != NULL) {
        for (int i = 0; i < axes; i++) {
            histories[i].d = rq->history[i].durations; histories[i].j = rq->history[i].jerks;
            histories[i].n = rq->history[i].count;
            double total = 0.0;
            for (int k = 0; k < rq->history[i].count; k++) total += rq->history[i].durations[k];
            histories[i].T = total;
        }
        ringing = histories;
    }
    Ph *rigid = ws->rigid, *ceiling_phases = ws->ceiling_phases, *best = ws->best, *found = ws->found;
    double T0;
    double targets[JP_MAX_AXES][3];
    memcpy(targets, rq->targets, sizeof(targets));
    if (plan_rigid(&pl, targets, rq->limits, &T0, rigid) != 0) return -1;
    if (jpi_rigid_blocks(&pl.rigid, axes, pl.states, targets, rq->limits, ws) != 0) {
        snprintf(result->message, sizeof(result->message), "unreachable target: no jerk-limited profile reaches it within the limits");
        return -1;
    }
    if (rq->ts > 0.0) {
        if (rq->straight) {
            snprintf(result->message, sizeof(result->message), "a straight-line move cannot be snapped to the sampling period");
            return -1;
        }
        double T = on_grid(T0, rq->ts);
        int ok = 0;
        for (int it = 0; it < 10000; it++) {
            if (jpi_profiles_lasting(&pl.rigid, T, -1, rigid, ws)) { ok = 1; break; }
            T += rq->ts;
        }
        if (!ok) {
            snprintf(result->message, sizeof(result->message), "no multiple of ts = %.12g s near the move's duration %.12g s "
                     "is possible for every axis", rq->ts, T0);
            return -1;
        }
        T0 = T;
    }
    double bounds[JP_MAX_AXES][JP_MAX_MODES];
    int any_modes = 0;
    for (int i = 0; i < axes; i++) {
        for (int q = 0; q < rq->mode_count[i]; q++) {
            result->references[i][q] = jpi_worst_amplitude(&rigid[i], T0, &rq->modes[i][q], ringing ? &ringing[i] : NULL);
            bounds[i][q] = rq->modes[i][q].vtol * result->references[i][q];
            any_modes = 1;
        }
    }
    result->rigid_duration = T0;
    if (!any_modes) {
        result->duration = T0;
        result->method = 0;
        result->ceiling_duration = T0;
        for (int i = 0; i < axes; i++) {
            copy_out(&rigid[i], &result->phases[i]);
            for (int q = 0; q < rq->mode_count[i]; q++) result->residuals[i][q] = result->references[i][q];
        }
        return 0;
    }
    double ceiling_T = INFINITY;
    int ceiling = shaped_move(&pl, bounds, ringing, &ceiling_T, ceiling_phases, result->ceiling_choice);
    if (ceiling == 0) ceiling_T = INFINITY;
    Search s = {&pl, T0, rigid, ceiling_phases, ceiling_T, ceiling == 1, bounds, ringing};
    int have = 0;
    double best_T = 0.0, failed = T0;
    for (size_t k = 0; k < sizeof(STRETCHES) / sizeof(STRETCHES[0]); k++) {
        double T = on_grid(T0 * (1.0 + STRETCHES[k]), rq->ts);
        if (T >= ceiling_T) break;
        if (attempt(&s, T, found)) { have = 1; best_T = T; memcpy(best, found, sizeof(Ph) * (size_t)axes); break; }
        failed = T;
    }
    if (have) {
        for (int h = 0; h < HALVINGS; h++) {
            double T = on_grid(0.5 * (failed + best_T), rq->ts);
            if (!(failed < T && T < best_T)) break;
            if (attempt(&s, T, found)) { best_T = T; memcpy(best, found, sizeof(Ph) * (size_t)axes); }
            else failed = T;
        }
    }
    double T;
    if (!have) {
        if (ceiling != 1) {
            snprintf(result->message, sizeof(result->message), "no move meets the vibration bounds within the limits from "
                     "this state: neither the planner's nor the rigid move followed by a catalog shaper (the shaped move "
                     "would leave the limits, or no shaper of the catalog meets a band); widen vtol or the limits");
            return -1;
        }
        T = ceiling_T;
        memcpy(best, ceiling_phases, sizeof(Ph) * (size_t)axes);
        result->method = 2;
    } else {
        T = best_T;
        result->method = 1;
    }
    result->duration = T;
    result->ceiling_duration = ceiling_T;
    for (int i = 0; i < axes; i++) {
        for (int q = 0; q < rq->mode_count[i]; q++)
            result->residuals[i][q] = jpi_worst_amplitude(&best[i], T, &rq->modes[i][q], ringing ? &ringing[i] : NULL);
        Ph pad;
        if (jpi_padded(&best[i], T, &pad) != 0) {
            snprintf(result->message, sizeof(result->message), "more than %d phases", MAXP);
            return -1;
        }
        copy_out(&pad, &result->phases[i]);
    }
    return 0;
}

JpWorkspace *jp_workspace_new(void) { return malloc(sizeof(JpWorkspace)); }

void jp_workspace_free(JpWorkspace *workspace) { free(workspace); }

int jp_plan(const JpRequest *request, JpResult *result, JpWorkspace *workspace) {
    memset(result, 0, sizeof(*result));
    if (workspace == NULL) {
        snprintf(result->message, sizeof(result->message), "no workspace (jp_workspace_new ran out of memory)");
        return -1;
    }
    return plan(request, result, workspace);
}

int jp_rigid_duration(const JpRequest *request, double *duration, char *message, int size, JpWorkspace *workspace) {
    int status = -1;
    if (workspace == NULL) {
        snprintf(message, (size_t)size, "no workspace (jp_workspace_new ran out of memory)");
    } else {
        Rigid *rg = &workspace->rigid_blocks;
        double states[JP_MAX_AXES][3], targets[JP_MAX_AXES][3];
        memcpy(states, request->states, sizeof(states));
        memcpy(targets, request->targets, sizeof(targets));
        status = 0;
        for (int i = 0; i < request->axes && status == 0; i++)
            status = jpi_check_start_within(states[i], &request->limits[i], message, size, i);
        if (status == 0 && jpi_rigid_blocks(rg, request->axes, states, targets, request->limits, workspace) == 0) {
            Candidate list[3 * JP_MAX_AXES];
            if (jpi_candidates(rg, list) > 0) *duration = list[0].t;
            else status = -1;
        } else if (status == 0) {
            status = -1;
        }
        if (status == -1) snprintf(message, (size_t)size, "unreachable target: no jerk-limited profile reaches it within the limits");
    }
    return status;
}
