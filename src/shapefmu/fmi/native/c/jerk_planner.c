/* The online jerk-limited multi-axis planner with vibration bounds: the C twin of runtime/jerk_profiles.py,
 * jerk_sync.py, jerk_vibration.py and jerk_planner.py (see jerk_planner.h). Each function names the
 * Python function it repeats; the docstrings there carry the mathematics (Berscheid & Kroeger, RSS 2021,
 * for the rigid core; the residual as the sum of the jerk steps for the modes). The order of the
 * floating-point operations follows the Python code, so that both plan the same move to rounding. */
#include "jerk_planner.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAXP JP_MAX_PHASES
#define EPS_T 1e-12

/* ------------------------------------------------------------------------------------------------
 * Phases (jerk_profiles.Phases) */

typedef struct {
    int n;
    double d[MAXP], j[MAXP];
    double p[MAXP + 1], v[MAXP + 1], a[MAXP + 1], e[MAXP + 1];
} Ph;

static int ph_set(Ph *ph, double p0, double v0, double a0, const double *d, const double *j, int n) {
    if (n > MAXP) return -1;
    ph->n = n;
    ph->p[0] = p0; ph->v[0] = v0; ph->a[0] = a0; ph->e[0] = 0.0;
    for (int k = 0; k < n; k++) {
        double t = d[k], jk = j[k];
        ph->d[k] = t; ph->j[k] = jk;
        ph->p[k + 1] = ph->p[k] + t * (ph->v[k] + t * (ph->a[k] / 2.0 + t * jk / 6.0));
        ph->v[k + 1] = ph->v[k] + t * (ph->a[k] + t * jk / 2.0);
        ph->a[k + 1] = ph->a[k] + t * jk;
        ph->e[k + 1] = ph->e[k] + t;
    }
    return 0;
}

static double ph_duration(const Ph *ph) { return ph->e[ph->n]; }

static void ph_extrema(const Ph *ph, double *v_low, double *v_high, double *a_low, double *a_high) {
    double al = ph->a[0], ah = ph->a[0], vl = ph->v[0], vh = ph->v[0];
    for (int k = 1; k <= ph->n; k++) {
        if (ph->a[k] < al) al = ph->a[k];
        if (ph->a[k] > ah) ah = ph->a[k];
        if (ph->v[k] < vl) vl = ph->v[k];
        if (ph->v[k] > vh) vh = ph->v[k];
    }
    for (int k = 0; k < ph->n; k++) {
        double a0 = ph->a[k], a1 = ph->a[k + 1], jk = ph->j[k];
        if (jk != 0.0 && a0 * a1 < 0.0) {
            double turn = ph->v[k] - a0 * a0 / (2.0 * jk);
            if (turn < vl) vl = turn;
            if (turn > vh) vh = turn;
        }
    }
    *v_low = vl; *v_high = vh; *a_low = al; *a_high = ah;
}

/* ------------------------------------------------------------------------------------------------
 * Polynomial roots (jerk_profiles.real_roots) */

static double poly_eval(const double *c, int len, double x) {
    double value = 0.0;
    for (int k = 0; k < len; k++) value = value * x + c[k];
    return value;
}

static double poly_bisect(const double *c, int len, double x0, double x1, double f0) {
    for (int it = 0; it < 200; it++) {
        double middle = 0.5 * (x0 + x1);
        if (middle == x0 || middle == x1) break;
        double f = poly_eval(c, len, middle);
        if (f == 0.0) return middle;
        if ((f < 0.0) == (f0 < 0.0)) { x0 = middle; f0 = f; } else x1 = middle;
    }
    return 0.5 * (x0 + x1);
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Real roots of c (len coefficients, highest first) in [low, high], sorted; returns their count. */
static int real_roots(const double *coefficients, int len, double low, double high, double *roots) {
    double scale = 0.0;
    for (int k = 0; k < len; k++) if (fabs(coefficients[k]) > scale) scale = fabs(coefficients[k]);
    const double *c = coefficients;
    while (len > 0 && fabs(c[0]) <= 1e-14 * scale) { c++; len--; }
    if (len < 2 || scale == 0.0) return 0;
    if (len == 2) {
        double x = -c[1] / c[0];
        if (low <= x && x <= high) { roots[0] = x; return 1; }
        return 0;
    }
    double derivative[8], turns[8];
    int n = len - 1;
    for (int k = 0; k < len - 1; k++) derivative[k] = c[k] * (n - k);
    int count_turns = real_roots(derivative, len - 1, low, high, turns);
    double points[10], values[10];
    int np = 0;
    points[np++] = low;
    for (int k = 0; k < count_turns; k++) points[np++] = turns[k];
    points[np++] = high;
    for (int k = 0; k < np; k++) values[k] = poly_eval(c, len, points[k]);
    double bound = fabs(low) > fabs(high) ? fabs(low) : fabs(high);
    if (bound < 1.0) bound = 1.0;
    double size = 0.0;
    for (int k = 0; k < len; k++) {
        double term = fabs(c[k]) * pow(bound, (double)(len - 1 - k));
        if (term > size) size = term;
    }
    int count = 0;
    for (int k = 0; k + 1 < np; k++) {
        if (values[k] == 0.0) roots[count++] = points[k];
        else if (values[k] * values[k + 1] < 0.0) roots[count++] = poly_bisect(c, len, points[k], points[k + 1], values[k]);
    }
    if (values[np - 1] == 0.0) roots[count++] = points[np - 1];
    for (int k = 0; k < count_turns; k++) {
        double f = values[k + 1];
        if (f != 0.0 && fabs(f) <= 1e-13 * size) roots[count++] = turns[k];
    }
    qsort(roots, (size_t)count, sizeof(double), cmp_double);
    return count;
}

/* ------------------------------------------------------------------------------------------------
 * One axis's problem (jerk_profiles.Problem) and its extremal profiles */

typedef struct {
    double p0, v0, a0, pf, vf, af, pd;
    JpLimits lim;
    double tol_p, tol_v, tol_a, tol_t;
} Problem;

static double max2(double a, double b) { return a > b ? a : b; }
static double min2(double a, double b) { return a < b ? a : b; }

static void problem_set(Problem *pr, const double *state, const double *target, const JpLimits *lim) {
    pr->p0 = state[0]; pr->v0 = state[1]; pr->a0 = state[2];
    pr->pf = target[0]; pr->vf = target[1]; pr->af = target[2];
    pr->lim = *lim;
    pr->pd = pr->pf - pr->p0;
    double v_scale = max2(max2(max2(lim->v_max, -lim->v_min), fabs(pr->v0)), fabs(pr->vf));
    double a_scale = max2(max2(max2(lim->a_max, -lim->a_min), fabs(pr->a0)), fabs(pr->af));
    double t_scale = max2(max2(a_scale / lim->j_max, v_scale / a_scale), sqrt(fabs(pr->pd) / a_scale));
    pr->tol_t = 1e-12 * t_scale;
    pr->tol_a = 1e-10 * a_scale;
    pr->tol_v = 1e-9 * v_scale;
    pr->tol_p = 1e-9 * max2(max2(max2(fabs(pr->pd), v_scale * t_scale), fabs(pr->p0)), fabs(pr->pf));
}

/* Problem.accept: 1 and *out when the durations reach the target within the limits. */
static int accept(const Problem *pr, const double *durations, const double *jerks, int n, Ph *out) {
    double clipped[MAXP];
    if (n > MAXP) return 0;
    for (int k = 0; k < n; k++) {
        if (durations[k] < -pr->tol_t || durations[k] != durations[k]) return 0;
        clipped[k] = durations[k] > 0.0 ? durations[k] : 0.0;
    }
    ph_set(out, pr->p0, pr->v0, pr->a0, clipped, jerks, n);
    if (fabs(out->p[n] - pr->pf) > pr->tol_p || fabs(out->v[n] - pr->vf) > pr->tol_v || fabs(out->a[n] - pr->af) > pr->tol_a)
        return 0;
    double vl, vh, al, ah;
    ph_extrema(out, &vl, &vh, &al, &ah);
    const JpLimits *lim = &pr->lim;
    if (ah > lim->a_max + pr->tol_a || al < lim->a_min - pr->tol_a || vh > lim->v_max + pr->tol_v || vl < lim->v_min - pr->tol_v)
        return 0;
    return 1;
}

/* velocity_change: three phases (durations t[3], jerks j[3]) from (v0, a0) to (v1, a1). */
static void velocity_change(double v0, double a0, double v1, double a1, double a_max, double a_min, double j_max,
                            double *t, double *j) {
    double direct = a1 == a0 ? 0.0 : (a1 * a1 - a0 * a0) / (2.0 * copysign(j_max, a1 - a0));
    int up = fabs(v1 - v0 - direct) <= 1e-12 * (fabs(v0) + fabs(v1) + (a0 * a0 + a1 * a1) / j_max) ? a1 < a0
                                                                                                : v1 - v0 > direct;
    double J = up ? j_max : -j_max;
    double limit = up ? a_max : a_min;
    double square = J * (v1 - v0) + 0.5 * (a0 * a0 + a1 * a1);
    double peak = copysign(sqrt(max2(square, 0.0)), J);
    double hold = 0.0;
    if ((peak - limit) * J > 0.0) {
        peak = limit;
        hold = (v1 - v0 - (2.0 * peak * peak - a0 * a0 - a1 * a1) / (2.0 * J)) / peak;
    }
    t[0] = (peak - a0) / J; j[0] = J;
    t[1] = hold; j[1] = 0.0;
    t[2] = (peak - a1) / J; j[2] = -J;
}

static double sum3(const double *t) { return ((0.0 + t[0]) + t[1]) + t[2]; }

static void oriented(const JpLimits *lim, int up, double *vU, double *aU, double *aL, double *J) {
    if (up) { *vU = lim->v_max; *aU = lim->a_max; *aL = lim->a_min; *J = lim->j_max; }
    else { *vU = lim->v_min; *aU = lim->a_min; *aL = lim->a_max; *J = -lim->j_max; }
}

/* _with_cruise */
static int with_cruise(const Problem *pr, int up, Ph *out) {
    const JpLimits *lim = &pr->lim;
    double vU, aU, aL, J, ta[3], ja[3], td[3], jd[3];
    oriented(lim, up, &vU, &aU, &aL, &J);
    velocity_change(pr->v0, pr->a0, vU, 0.0, lim->a_max, lim->a_min, lim->j_max, ta, ja);
    velocity_change(vU, 0.0, pr->vf, pr->af, lim->a_max, lim->a_min, lim->j_max, td, jd);
    if ((ja[0] != J && ta[0] > pr->tol_t) || (jd[0] != -J && td[0] > pr->tol_t)) return 0;
    double durations[7] = {ta[0], ta[1], ta[2], 0.0, td[0], td[1], td[2]};
    double jerks[7] = {J, 0.0, -J, 0.0, -J, 0.0, J};
    Ph without;
    ph_set(&without, pr->p0, pr->v0, pr->a0, durations, jerks, 7);
    durations[3] = (pr->pf - without.p[7]) / vU;
    if (durations[3] <= pr->tol_t) return 0;
    return accept(pr, durations, jerks, 7, out);
}

/* _through_zero: phases 3, 4, 5 of the ramp a1 -> a5 at jerk -J */
static void through_zero(double a1, double a5, double J, double *t3, double *t4, double *t5) {
    if (a1 * J > 0.0 && a5 * J < 0.0) { *t3 = a1 / J; *t4 = 0.0; *t5 = -a5 / J; }
    else { *t3 = (a1 - a5) / J; *t4 = 0.0; *t5 = 0.0; }
}

static int quadratic_roots(double a, double b, double c, double *roots) {
    if (a == 0.0) {
        if (b == 0.0) return 0;
        roots[0] = -c / b;
        return 1;
    }
    double discriminant = b * b - 4.0 * a * c;
    if (discriminant < 0.0) return 0;
    double q = -0.5 * (b + copysign(sqrt(discriminant), b));
    if (q == 0.0) { roots[0] = q / a; return 1; }
    roots[0] = q / a; roots[1] = c / q;
    return 2;
}

/* _without_cruise: appends accepted profiles to list (count in *found) */
static void without_cruise(const Problem *pr, int up, Ph *list, int *found, int capacity) {
    const JpLimits *lim = &pr->lim;
    double vU, aU, aL, J;
    oriented(lim, up, &vU, &aU, &aL, &J);
    double a0 = pr->a0, v0 = pr->v0, af = pr->af, vf = pr->vf, pd = pr->pd;
    double J2 = J * J, J3 = J * J * J, J4 = pow(J, 4);
    double jerks[7] = {J, 0.0, -J, 0.0, -J, 0.0, J};
    double u_high = (aU - aL) / J;
    double roots[8], d[7];
    int count;
    double K = J * (vf - v0) + 0.5 * (a0 * a0 - af * af);
    double quartic[5] = {1.0, 0.0, 2.0 * (2.0 * J * (v0 + vf) - a0 * a0 - af * af) / J2,
                         -4.0 * (3.0 * J2 * pd + 3.0 * J * (a0 * v0 - af * vf) - pow(a0, 3) + pow(af, 3)) / (3.0 * J3),
                         -pow(2.0 * J * (v0 - vf) - a0 * a0 + af * af, 2) / (4.0 * J4)};
    count = real_roots(quartic, 5, 0.0, u_high, roots);
    for (int r = 0; r < count; r++) {
        double u = roots[r];
        if (u <= 0.0) continue;
        double a1 = 0.5 * (J * u + K / (J * u));
        double a5 = a1 - J * u;
        d[0] = (a1 - a0) / J; d[1] = 0.0;
        through_zero(a1, a5, J, &d[2], &d[3], &d[4]);
        d[5] = 0.0; d[6] = (af - a5) / J;
        if (*found < capacity && accept(pr, d, jerks, 7, &list[*found])) (*found)++;
    }
    double c0 = (-24 * J2 * aU * pd - 12 * J2 * v0 * v0 + 12 * J2 * vf * vf + 12 * J * a0 * a0 * v0 - 24 * J * a0 * aU * v0
                 + 12 * J * aU * aU * v0 - 12 * J * aU * aU * vf + 24 * J * aU * af * vf - 12 * J * af * af * vf - 3 * pow(a0, 4)
                 + 8 * pow(a0, 3) * aU - 6 * a0 * a0 * aU * aU + 6 * aU * aU * af * af - 8 * aU * pow(af, 3) + 3 * pow(af, 4));
    double q0[5] = {12 * J4, -24 * J3 * aU, 12 * J2 * (2 * J * vf + aU * aU - af * af), 0.0, c0};
    count = real_roots(q0, 5, 0.0, u_high, roots);
    for (int r = 0; r < count; r++) {
        double u = roots[r];
        double t2 = (2 * J2 * u * u - 4 * J * aU * u - 2 * J * v0 + 2 * J * vf + a0 * a0 - af * af) / (2 * J * aU);
        double a5 = aU - J * u;
        d[0] = (aU - a0) / J; d[1] = t2;
        through_zero(aU, a5, J, &d[2], &d[3], &d[4]);
        d[5] = 0.0; d[6] = (af - a5) / J;
        if (*found < capacity && accept(pr, d, jerks, 7, &list[*found])) (*found)++;
    }
    c0 = (-24 * J2 * aL * pd - 12 * J2 * v0 * v0 + 12 * J2 * vf * vf + 12 * J * a0 * a0 * v0 - 24 * J * a0 * aL * v0
          + 12 * J * aL * aL * v0 - 12 * J * aL * aL * vf + 24 * J * aL * af * vf - 12 * J * af * af * vf - 3 * pow(a0, 4)
          + 8 * pow(a0, 3) * aL - 6 * a0 * a0 * aL * aL + 6 * aL * aL * af * af - 8 * aL * pow(af, 3) + 3 * pow(af, 4));
    double q1[5] = {-12 * J4, -24 * J3 * aL, -12 * J2 * (2 * J * v0 - a0 * a0 + aL * aL), 0.0, c0};
    count = real_roots(q1, 5, 0.0, u_high, roots);
    for (int r = 0; r < count; r++) {
        double u = roots[r];
        double t6 = -(2 * J2 * u * u + 4 * J * aL * u + 2 * J * v0 - 2 * J * vf - a0 * a0 + af * af) / (2 * J * aL);
        double a1 = aL + J * u;
        d[0] = (a1 - a0) / J; d[1] = 0.0;
        through_zero(a1, aL, J, &d[2], &d[3], &d[4]);
        d[5] = t6; d[6] = (af - aL) / J;
        if (*found < capacity && accept(pr, d, jerks, 7, &list[*found])) (*found)++;
    }
    double a2q = 12 * J2 * aU * (aL - aU);
    double a1q = 12 * J * (aL - aU) * (2 * J * v0 - a0 * a0 - aL * aU + 2 * aU * aU);
    double a0q = (-24 * J2 * aL * pd - 12 * J2 * v0 * v0 + 12 * J2 * vf * vf + 12 * J * a0 * a0 * v0 - 24 * J * a0 * aL * v0
                  - 12 * J * aL * aL * v0 - 12 * J * aL * aL * vf + 48 * J * aL * aU * v0 + 24 * J * aL * af * vf
                  - 24 * J * aU * aU * v0 - 12 * J * af * af * vf - 3 * pow(a0, 4) + 8 * pow(a0, 3) * aL + 6 * a0 * a0 * aL * aL
                  - 24 * a0 * a0 * aL * aU + 12 * a0 * a0 * aU * aU - 12 * aL * aL * aU * aU + 6 * aL * aL * af * af
                  + 24 * aL * pow(aU, 3) - 8 * aL * pow(af, 3) - 12 * pow(aU, 4) + 3 * pow(af, 4));
    count = quadratic_roots(a2q, a1q, a0q, roots);
    for (int r = 0; r < count; r++) {
        double t2 = roots[r];
        double t6 = -(2 * J * aU * t2 + 2 * J * v0 - 2 * J * vf - a0 * a0 - 2 * aL * aL + 2 * aU * aU + af * af) / (2 * J * aL);
        d[0] = (aU - a0) / J; d[1] = t2;
        through_zero(aU, aL, J, &d[2], &d[3], &d[4]);
        d[5] = t6; d[6] = (af - aL) / J;
        if (*found < capacity && accept(pr, d, jerks, 7, &list[*found])) (*found)++;
    }
}

#define MAX_EXTREMAL 24

typedef struct {
    Ph fastest;
    int intervals;
    double left[2], right[2];
    Ph at_right[2];
} Block;

/* extremal_profiles + block: 0, or -1 when no profile reaches the target */
static int block_of(const Problem *pr, Block *b, Ph *scratch /* MAX_EXTREMAL */) {
    int found = 0;
    for (int up = 1; up >= 0; up--) {
        if (found < MAX_EXTREMAL && with_cruise(pr, up, &scratch[found])) found++;
        without_cruise(pr, up, scratch, &found, MAX_EXTREMAL);
    }
    if (pr->pd == 0.0 && pr->v0 == 0.0 && pr->vf == 0.0 && pr->a0 == 0.0 && pr->af == 0.0 && found < MAX_EXTREMAL) {
        double zeros[7] = {0, 0, 0, 0, 0, 0, 0};
        ph_set(&scratch[found++], pr->p0, 0.0, 0.0, zeros, zeros, 7);
    }
    /* stable insertion sort by duration (Python's list.sort) */
    int order[MAX_EXTREMAL];
    for (int k = 0; k < found; k++) order[k] = k;
    for (int k = 1; k < found; k++) {
        int x = order[k], i = k - 1;
        while (i >= 0 && ph_duration(&scratch[order[i]]) > ph_duration(&scratch[x])) { order[i + 1] = order[i]; i--; }
        order[i + 1] = x;
    }
    int distinct[MAX_EXTREMAL], count = 0;
    for (int k = 0; k < found; k++) {
        const Ph *ph = &scratch[order[k]];
        if (count == 0 || ph_duration(ph) - ph_duration(&scratch[distinct[count - 1]]) > 1e3 * pr->tol_t)
            distinct[count++] = order[k];
    }
    if (count == 0) return -1;
    b->fastest = scratch[distinct[0]];
    int rest = count - 1;
    b->intervals = 0;
    if (rest == 1) {
        b->intervals = 1;
        b->left[0] = ph_duration(&b->fastest); b->right[0] = ph_duration(&scratch[distinct[1]]);
        b->at_right[0] = scratch[distinct[1]];
    } else if (rest == 2 || rest == 3) {
        int last = rest == 2 ? 2 : 3;
        b->intervals = 1;
        b->left[0] = ph_duration(&scratch[distinct[1]]); b->right[0] = ph_duration(&scratch[distinct[last]]);
        b->at_right[0] = scratch[distinct[last]];
    } else if (rest == 4) {
        b->intervals = 2;
        for (int i = 0; i < 2; i++) {
            b->left[i] = ph_duration(&scratch[distinct[1 + 2 * i]]);
            b->right[i] = ph_duration(&scratch[distinct[2 + 2 * i]]);
            b->at_right[i] = scratch[distinct[2 + 2 * i]];
        }
    }
    return 0;
}

static double t_min(const Block *b) { return ph_duration(&b->fastest); }

static int blocked(const Block *b, double t) {
    if (t < t_min(b)) return 1;
    for (int i = 0; i < b->intervals; i++) if (b->left[i] < t && t < b->right[i]) return 1;
    return 0;
}

/* ------------------------------------------------------------------------------------------------
 * Step 2: a profile of a prescribed duration (profile_of_duration and its helpers) */

#define SAMPLES 24
#define MAX_POINTS 128

/* _hold_profile: 1 and error, phases; 0 when the changes outlast T */
static int hold_profile(const Problem *pr, double T, double level, double va, double *error, Ph *out) {
    const JpLimits *lim = &pr->lim;
    double tf[3], jf[3], ts[3], js[3];
    velocity_change(pr->v0, pr->a0, va, level, lim->a_max, lim->a_min, lim->j_max, tf, jf);
    double t_first = sum3(tf);
    double hold = 0.0;
    for (int it = 0; it < 100; it++) {
        velocity_change(va + level * hold, level, pr->vf, pr->af, lim->a_max, lim->a_min, lim->j_max, ts, js);
        double updated = T - t_first - sum3(ts);
        if (updated < 0.0) {
            if (updated < -pr->tol_t) return 0;
            updated = 0.0;
        }
        if (updated == hold || level == 0.0) { hold = updated; break; }
        hold = updated;
    }
    double d[7] = {tf[0], tf[1], tf[2], hold, ts[0], ts[1], ts[2]};
    double j[7] = {jf[0], jf[1], jf[2], 0.0, js[0], js[1], js[2]};
    ph_set(out, pr->p0, pr->v0, pr->a0, d, j, 7);
    *error = out->p[7] - pr->pf;
    return 1;
}

static double hold_time(const Problem *pr, double level, double va) {
    const JpLimits *lim = &pr->lim;
    double t1[3], j1[3], t2[3], j2[3];
    velocity_change(pr->v0, pr->a0, va, level, lim->a_max, lim->a_min, lim->j_max, t1, j1);
    velocity_change(va, level, pr->vf, pr->af, lim->a_max, lim->a_min, lim->j_max, t2, j2);
    return sum3(t1) + sum3(t2);
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
    qsort(grid, (size_t)n, sizeof(double), cmp_double);
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
    qsort(points, (size_t)np, sizeof(double), cmp_double);
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

static int meeting_profile(const Problem *pr, double T, Ph *out, Ph *tmp) {
    const JpLimits *lim = &pr->lim;
    double span = lim->v_max - lim->v_min;
    enum { LEVELS = 2 * SAMPLES - 1 };
    static double table[LEVELS][MAX_POINTS];
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
                && accept(pr, out->d, out->j, out->n, tmp)) {
                *out = *tmp;
                return 1;
            }
        }
    }
    return 0;
}

/* _with_hold: 1 and *out, 0 for None */
static int with_hold(const Problem *pr, double T, double level, const Ph *near, Ph *out) {
    const JpLimits *lim = &pr->lim;
    if (!(lim->a_min < level && level < lim->a_max) && level != 0.0) return 0;
    static Ph first, second, refined;
    double edges[MAX_POINTS], points[MAX_POINTS], seeds[16];
    int n_seeds = near != NULL ? passing_velocities(near, level, seeds) : 0;
    int ne, np;
    hold_points(pr, T, level, seeds, n_seeds, edges, &ne, points, &np);
    double e_prev = 0.0;
    int ok_prev = 0;
    for (int k = 0; k < np; k++) {
        double e_now;
        int ok_now = hold_profile(pr, T, level, points[k], &e_now, &second);
        if (k > 0 && ok_prev && ok_now && !(e_prev * e_now > 0.0)) {
            if (refine_hold(pr, T, level, points[k - 1], points[k], e_prev, &first, &refined)
                && accept(pr, refined.d, refined.j, refined.n, out))
                return 1;
        }
        e_prev = e_now; ok_prev = ok_now; first = second;
    }
    return 0;
}

/* profile_of_duration: 1 and *out, 0 for None */
static int profile_of_duration(const Problem *pr, double T, const Ph *near, Ph *out) {
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
    for (int l = 0; l < nl; l++) if (with_hold(pr, T, levels[l], near, out)) return 1;
    static Ph tmp;
    if (meeting_profile(pr, T, out, &tmp)) return 1;
    for (int k = 1; k < 8 * SAMPLES; k++) {
        if (k % 4 == 0) continue;
        if (with_hold(pr, T, lim->a_min + (lim->a_max - lim->a_min) * k / (8 * SAMPLES), near, out)) return 1;
    }
    return 0;
}

/* ------------------------------------------------------------------------------------------------
 * Axes together (jerk_sync) */

typedef struct {
    int axes;
    Problem problems[JP_MAX_AXES];
    Block blocks[JP_MAX_AXES];
} Rigid;

static int check_start_within(double *state, const JpLimits *lim, char *message, int size, int axis) {
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

static int rigid_blocks(Rigid *rg, int axes, double (*states)[3], double (*targets)[3], const JpLimits *limits,
                        Ph *scratch) {
    rg->axes = axes;
    for (int i = 0; i < axes; i++) {
        problem_set(&rg->problems[i], states[i], targets[i], &limits[i]);
        if (block_of(&rg->problems[i], &rg->blocks[i], scratch) != 0) return -1;
    }
    return 0;
}

/* profiles_lasting: 1 and out[axes], 0 for None */
static int profiles_lasting(const Rigid *rg, double T, int owner, Ph *out) {
    for (int i = 0; i < rg->axes; i++) if (blocked(&rg->blocks[i], T)) return 0;
    for (int i = 0; i < rg->axes; i++) {
        const Block *b = &rg->blocks[i];
        if (i == owner) {
            if (T == t_min(b)) out[i] = b->fastest;
            else {
                int hit = 0;
                for (int q = 0; q < b->intervals; q++) if (T == b->right[q]) { out[i] = b->at_right[q]; hit = 1; break; }
                if (!hit) return 0;
            }
        } else if (T - t_min(b) <= rg->problems[i].tol_t) {
            out[i] = b->fastest;
        } else if (!profile_of_duration(&rg->problems[i], T, &b->fastest, &out[i])) {
            return 0;
        }
    }
    return 1;
}

typedef struct { double t; int axis; } Candidate;

static int cmp_candidate(const void *x, const void *y) {
    const Candidate *a = (const Candidate *)x, *b = (const Candidate *)y;
    if (a->t != b->t) return (a->t > b->t) - (a->t < b->t);
    return a->axis - b->axis;
}

static int candidates(const Rigid *rg, Candidate *out) {
    double floor = 0.0;
    for (int i = 0; i < rg->axes; i++) floor = max2(floor, t_min(&rg->blocks[i]));
    Candidate all[3 * JP_MAX_AXES];
    int n = 0;
    for (int i = 0; i < rg->axes; i++) {
        all[n].t = t_min(&rg->blocks[i]); all[n++].axis = i;
        for (int q = 0; q < rg->blocks[i].intervals; q++) { all[n].t = rg->blocks[i].right[q]; all[n++].axis = i; }
    }
    qsort(all, (size_t)n, sizeof(Candidate), cmp_candidate);
    int count = 0;
    for (int k = 0; k < n; k++) {
        if (all[k].t < floor) continue;
        int any = 0;
        for (int i = 0; i < rg->axes; i++) if (blocked(&rg->blocks[i], all[k].t)) any = 1;
        if (!any) out[count++] = all[k];
    }
    return count;
}

static int synchronise(Rigid *rg, int axes, double (*states)[3], double (*targets)[3], const JpLimits *limits,
                       double *T, Ph *out, Ph *scratch) {
    if (rigid_blocks(rg, axes, states, targets, limits, scratch) != 0) return -1;
    Candidate list[3 * JP_MAX_AXES];
    int n = candidates(rg, list);
    for (int k = 0; k < n; k++) {
        if (profiles_lasting(rg, list[k].t, list[k].axis, out)) { *T = list[k].t; return 0; }
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

static int straight_line(Rigid *rg, int axes, double (*states)[3], double (*targets)[3], const JpLimits *limits,
                         double *T, Ph *out, Ph *scratch, char *message, int size) {
    double d[JP_MAX_AXES], direction[JP_MAX_AXES], length = 0.0;
    for (int i = 0; i < axes; i++) { d[i] = targets[i][0] - states[i][0]; length = max2(length, fabs(d[i])); }
    if (length == 0.0) return synchronise(rg, axes, states, targets, limits, T, out, scratch);
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
    if (check_start_within(start[0], &path_limits, message, size, 0) != 0) return -2;
    Ph line;
    Rigid single;
    if (synchronise(&single, 1, start, end, &path_limits, T, &line, scratch) != 0) return -1;
    for (int i = 0; i < axes; i++) {
        double jerks[MAXP];
        for (int k = 0; k < line.n; k++) jerks[k] = line.j[k] * direction[i];
        ph_set(&out[i], states[i][0], states[i][1], states[i][2], line.d, jerks, line.n);
    }
    (void)rg;
    return 0;
}

/* ------------------------------------------------------------------------------------------------
 * Residual vibration (jerk_vibration) */

typedef struct { double re, im; } Cx;

static Cx cx_exp(double re, double im) {
    double scale = exp(re);
    Cx r = {scale * cos(im), scale * sin(im)};
    return r;
}

static Cx cx_mul(Cx a, Cx b) {
    Cx r = {a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re};
    return r;
}

/* e^{s x} with s = (-sigma, omega_d): Python's _exp(s * x) */
static Cx exp_s(double sigma_neg, double omega_d, double x) { return cx_exp(sigma_neg * x, omega_d * x); }

typedef struct {
    const double *d, *j;
    int n;
    double T;
} History;

static Cx jerk_sum(const double *d, const double *j, int n, double T, double omega, double zeta, const History *ringing);

/* ringing(omega, zeta): S of the history's jerk at its end */
static Cx ringing_at(const History *h, double omega, double zeta) {
    return jerk_sum(h->d, h->j, h->n, h->T, omega, zeta, NULL);
}

static Cx jerk_sum(const double *d, const double *j, int n, double T, double omega, double zeta, const History *ringing) {
    double sigma = zeta * omega, omega_d = omega * sqrt(1.0 - zeta * zeta);
    Cx total = {0.0, 0.0};
    if (ringing != NULL) total = cx_mul(ringing_at(ringing, omega, zeta), exp_s(-sigma, omega_d, T));
    double previous = 0.0, t = 0.0;
    for (int k = 0; k < n; k++) {
        if (j[k] != previous) {
            Cx e = exp_s(-sigma, omega_d, T - t);
            double step = j[k] - previous;
            total.re += step * e.re; total.im += step * e.im;
            previous = j[k];
        }
        t += d[k];
    }
    if (previous != 0.0) {
        Cx e = exp_s(-sigma, omega_d, T - t);
        total.re -= previous * e.re; total.im -= previous * e.im;
    }
    return total;
}

static double amplitude(const double *d, const double *j, int n, double T, double omega, double zeta,
                        const History *ringing) {
    double omega_d = omega * sqrt(1.0 - zeta * zeta);
    Cx S = jerk_sum(d, j, n, T, omega, zeta, ringing);
    return hypot(S.re, S.im) / (omega * omega * omega_d);
}

static int band_count(const JpMode *m, double duration) {
    if (m->delta == 0.0) return 1;
    double width = 2.0 * m->delta * m->omega;
    int count = (int)ceil(width * duration * 20.0) + 1;
    if (count < 9) count = 9;
    if (count > 401) count = 401;
    return count;
}

static double band_frequency(const JpMode *m, double duration, int k, int count) {
    if (m->delta == 0.0) return m->omega;
    (void)duration;
    double width = 2.0 * m->delta * m->omega;
    double low = m->omega * (1.0 - m->delta);
    return low + width * k / (count - 1);
}

static double worst_amplitude(const Ph *ph, double T, const JpMode *m, const History *ringing) {
    int count = band_count(m, T);
    double worst = -INFINITY;
    for (int k = 0; k < count; k++) {
        double a = amplitude(ph->d, ph->j, ph->n, T, band_frequency(m, T, k, count), m->zeta, ringing);
        if (a > worst) worst = a;
    }
    return worst;
}

static int padded(const Ph *ph, double T, Ph *out) {
    double rest = T - ph_duration(ph);
    if (rest <= 0.0) { *out = *ph; return 0; }
    if (ph->n + 1 > MAXP) return -1;
    double d[MAXP], j[MAXP];
    memcpy(d, ph->d, sizeof(double) * (size_t)ph->n);
    memcpy(j, ph->j, sizeof(double) * (size_t)ph->n);
    d[ph->n] = rest; j[ph->n] = 0.0;
    return ph_set(out, ph->p[0], ph->v[0], ph->a[0], d, j, ph->n + 1);
}

static int phase_index(const double *edges, int count, double t) {
    int low = 0, high = count - 2;
    while (low < high) {
        int middle = (low + high + 1) / 2;
        if (edges[middle] <= t) low = middle; else high = middle - 1;
    }
    return low;
}

/* convolve_jerk */
static int convolve_jerk(const Ph *ph, const JpShaper *shaper, Ph *out) {
    static double cuts[(MAXP + 1) * JP_MAX_IMPULSES];
    double edges[MAXP + 1];
    edges[0] = 0.0;
    for (int k = 0; k < ph->n; k++) edges[k + 1] = edges[k] + ph->d[k];
    int n = 0;
    for (int k = 0; k <= ph->n; k++)
        for (int i = 0; i < shaper->count; i++) cuts[n++] = edges[k] + shaper->times[i];
    qsort(cuts, (size_t)n, sizeof(double), cmp_double);
    int m = 0;
    for (int k = 0; k < n; k++) if (m == 0 || cuts[k] != cuts[m - 1]) cuts[m++] = cuts[k];
    double span = max2(cuts[m - 1] - cuts[0], 1e-300);
    int merged = 1;
    for (int k = 1; k < m; k++) if (cuts[k] - cuts[merged - 1] > 1e-13 * span) cuts[merged++] = cuts[k];
    if (merged - 1 > MAXP) return -1;
    double d[MAXP], j[MAXP];
    for (int k = 0; k + 1 < merged; k++) {
        double left = cuts[k], right = cuts[k + 1], middle = 0.5 * (left + right), value = 0.0;
        for (int i = 0; i < shaper->count; i++) {
            double local = middle - shaper->times[i];
            if (0.0 <= local && local < edges[ph->n]) value += shaper->amplitudes[i] * ph->j[phase_index(edges, ph->n + 1, local)];
        }
        d[k] = right - left; j[k] = value;
    }
    return ph_set(out, ph->p[0], ph->v[0], ph->a[0], d, j, merged - 1);
}

/* _with_doublets: the durations and jerks with count doublets */
static int with_doublets(const Ph *ph, int count, double j_max, double tau, double *d, double *j, int *n_out) {
    int n = ph->n;
    double acc[MAXP + 1], vel[MAXP + 1];
    memcpy(d, ph->d, sizeof(double) * (size_t)n);
    memcpy(j, ph->j, sizeof(double) * (size_t)n);
    memcpy(acc, ph->a, sizeof(double) * (size_t)(n + 1));
    memcpy(vel, ph->v, sizeof(double) * (size_t)(n + 1));
    for (int c = 0; c < count; c++) {
        if (n + 4 > MAXP) return -1;
        int k = -1;
        for (int i = 0; i < n; i++) if (j[i] == 0.0 && (k < 0 || d[i] > d[k])) k = i;
        if (k < 0) {
            int longest = 0;
            for (int i = 1; i < n; i++) if (d[i] > d[longest]) longest = i;
            k = longest + 1;
            memmove(&d[k + 1], &d[k], sizeof(double) * (size_t)(n - k));
            memmove(&j[k + 1], &j[k], sizeof(double) * (size_t)(n - k));
            memmove(&acc[k + 1], &acc[k], sizeof(double) * (size_t)(n + 1 - k));
            memmove(&vel[k + 1], &vel[k], sizeof(double) * (size_t)(n + 1 - k));
            d[k] = 0.0; j[k] = 0.0;
            n++;
        }
        double a = acc[k], v = vel[k];
        double sign = (a > 0.0 || (a == 0.0 && v >= 0.0)) ? 1.0 : -1.0;
        double half = 0.5 * d[k];
        memmove(&d[k + 4], &d[k + 1], sizeof(double) * (size_t)(n - k - 1));
        memmove(&j[k + 4], &j[k + 1], sizeof(double) * (size_t)(n - k - 1));
        memmove(&acc[k + 4], &acc[k + 1], sizeof(double) * (size_t)(n - k));
        memmove(&vel[k + 4], &vel[k + 1], sizeof(double) * (size_t)(n - k));
        d[k] = half; d[k + 1] = tau; d[k + 2] = tau; d[k + 3] = half;
        j[k] = 0.0; j[k + 1] = -sign * j_max; j[k + 2] = sign * j_max; j[k + 3] = 0.0;
        acc[k] = a; acc[k + 1] = a; acc[k + 2] = a - sign * j_max * tau; acc[k + 3] = a;
        vel[k] = v; vel[k + 1] = v; vel[k + 2] = v; vel[k + 3] = v;
        n += 3;
    }
    *n_out = n;
    return 0;
}

typedef struct { int m; int kind; double level; } Held;  /* kind 0 a, 1 v, 2 turn */
#define MAX_HELD 64
#define MAX_FREQ 64
#define MAX_EQ (4 + MAX_HELD + 2 * MAX_FREQ)

static int held_limits(const double *d, const double *j, int n, const double *start, const JpLimits *lim, Held *held) {
    Ph ph;
    ph_set(&ph, start[0], start[1], start[2], d, j, n);
    double tol_a = 1e-9 * max2(lim->a_max, -lim->a_min), tol_v = 1e-9 * max2(lim->v_max, -lim->v_min);
    int count = 0;
    for (int k = 0; k < n; k++) {
        if (j[k] != 0.0) continue;
        double levels_a[2] = {lim->a_max, lim->a_min}, levels_v[2] = {lim->v_max, lim->v_min};
        for (int q = 0; q < 2; q++)
            if (fabs(ph.a[k] - levels_a[q]) <= tol_a && count < MAX_HELD) { held[count].m = k; held[count].kind = 0; held[count++].level = levels_a[q]; }
        for (int q = 0; q < 2; q++)
            if (fabs(ph.a[k]) <= tol_a && fabs(ph.v[k] - levels_v[q]) <= tol_v && count < MAX_HELD) {
                held[count].m = k; held[count].kind = 1; held[count++].level = levels_v[q];
            }
    }
    return count;
}

typedef struct {
    const double *start, *target;
    double T;
    const double *omegas, *zetas;
    int freqs;
    double scales[5];
    const Held *held;
    int n_held;
    const History *ringing;
} System;

/* _equations: F (m) and columns (n x m, column k at C[k * m]) ; returns m */
static int equations(const System *sys, const double *d, const double *j, int n, double *F, double *C) {
    static Ph ph;
    ph_set(&ph, sys->start[0], sys->start[1], sys->start[2], d, j, n);
    const double *sc = sys->scales;
    int m = 4 + sys->n_held + 2 * sys->freqs;
    double total = ph.e[n];
    F[0] = (ph.a[n] - sys->target[2]) / sc[0];
    F[1] = (ph.v[n] - sys->target[1]) / sc[1];
    F[2] = (ph.p[n] - sys->target[0]) / sc[2];
    F[3] = (total - sys->T) / sc[3];
    for (int k = 0; k < n; k++) {
        double R = total - ph.e[k + 1];
        double dv = ph.v[k + 1], da = ph.a[k + 1], dj = j[k];
        double *col = &C[(size_t)k * m];
        col[0] = dj / sc[0];
        col[1] = (da + dj * R) / sc[1];
        col[2] = (dv + da * R + dj * R * R / 2.0) / sc[2];
        col[3] = 1.0 / sc[3];
    }
    for (int h = 0; h < sys->n_held; h++) {
        int mm = sys->held[h].m, kind = sys->held[h].kind;
        double level = sys->held[h].level;
        int row = 4 + h;
        if (kind == 0) F[row] = (ph.a[mm] - level) / sc[0];
        else if (kind == 1) F[row] = (ph.v[mm] - level) / sc[1];
        else F[row] = (ph.v[mm] - ph.a[mm] * ph.a[mm] / (2.0 * j[mm]) - level) / sc[1];
        for (int k = 0; k < n; k++) {
            double value;
            if (k >= mm) value = 0.0;
            else if (kind == 0) value = j[k] / sc[0];
            else {
                double dv = ph.a[k + 1] + j[k] * (ph.e[mm] - ph.e[k + 1]);
                if (kind == 2) dv -= ph.a[mm] / j[mm] * j[k];
                value = dv / sc[1];
            }
            C[(size_t)k * m + row] = value;
        }
    }
    static Cx steps[MAXP + 1];
    for (int f = 0; f < sys->freqs; f++) {
        double omega = sys->omegas[f], zeta = sys->zetas[f];
        double sre = -zeta * omega, sim = omega * sqrt(1.0 - zeta * zeta);
        double previous = 0.0;
        for (int k = 0; k <= n; k++) {
            double level = k < n ? j[k] : 0.0;
            Cx e = cx_exp(sre * (sys->T - ph.e[k]), sim * (sys->T - ph.e[k]));
            double step = level - previous;
            steps[k].re = step * e.re; steps[k].im = step * e.im;
            previous = level;
        }
        Cx value = {0.0, 0.0};
        for (int k = 0; k <= n; k++) { value.re += steps[k].re; value.im += steps[k].im; }
        if (sys->ringing != NULL) {
            Cx r = cx_mul(ringing_at(sys->ringing, omega, zeta), cx_exp(sre * sys->T, sim * sys->T));
            value.re += r.re; value.im += r.im;
        }
        int row = 4 + sys->n_held + 2 * f;
        F[row] = value.re / sc[4];
        F[row + 1] = value.im / sc[4];
        Cx tail = {0.0, 0.0};
        Cx minus_s = {-sre, -sim};
        for (int k = n - 1; k >= 0; k--) {
            Cx shifted = cx_mul(minus_s, steps[k + 1]);
            tail.re += shifted.re; tail.im += shifted.im;
            C[(size_t)k * m + row] = tail.re / sc[4];
            C[(size_t)k * m + row + 1] = tail.im / sc[4];
        }
    }
    return m;
}

/* _least_norm_step: 0 and dx, or -1 */
static int least_norm_step(const double *C, const int *frozen, int n, int m, const double *F, double *dx) {
    static double M[MAX_EQ * MAX_EQ], L[MAX_EQ * MAX_EQ];
    double y[MAX_EQ];
    for (int i = 0; i < m; i++)
        for (int q = 0; q <= i; q++) {
            double s = 0.0;
            for (int k = 0; k < n; k++) if (!frozen[k]) s += C[(size_t)k * m + i] * C[(size_t)k * m + q];
                else s += 0.0 * 0.0;
            M[i * m + q] = s;
        }
    double trace = 0.0;
    for (int i = 0; i < m; i++) trace += M[i * m + i];
    double mu = 1e-13 * max2(trace, 1e-300);
    for (int i = 0; i < m; i++)
        for (int q = 0; q <= i; q++) {
            double s = 0.0;
            for (int k = 0; k < q; k++) s += L[i * m + k] * L[q * m + k];
            double value = M[i * m + q] + (i == q ? mu : 0.0) - s;
            if (i == q) {
                if (value <= 0.0) return -1;
                L[i * m + i] = sqrt(value);
            } else {
                L[i * m + q] = value / L[q * m + q];
            }
        }
    for (int i = 0; i < m; i++) {
        double s = 0.0;
        for (int k = 0; k < i; k++) s += L[i * m + k] * y[k];
        y[i] = (-F[i] - s) / L[i * m + i];
    }
    for (int i = m - 1; i >= 0; i--) {
        double s = 0.0;
        for (int k = i + 1; k < m; k++) s += L[k * m + i] * y[k];
        y[i] = (y[i] - s) / L[i * m + i];
    }
    for (int k = 0; k < n; k++) {
        double s = 0.0;
        for (int i = 0; i < m; i++) s += (frozen[k] ? 0.0 : C[(size_t)k * m + i]) * y[i];
        dx[k] = s;
    }
    return 0;
}

static double norm(const double *F, int m) {
    double s = 0.0;
    for (int i = 0; i < m; i++) s += F[i] * F[i];
    return sqrt(s);
}

/* cancel: 1 and (d, j, n) solved; 0 for None */
static int cancel(const double *start, const double *target, const JpLimits *lim, double T, const JpMode *modes,
                  int n_modes, const Ph *rigid, const History *ringing, const double *omegas, const double *zetas,
                  int freqs, int doublets, const Held *pins, int n_pins, double *d_out, double *j_out, int *n_out) {
    double S_rigid = -INFINITY, omega_low = INFINITY;
    for (int f = 0; f < freqs; f++) {
        Cx S = jerk_sum(rigid->d, rigid->j, rigid->n, ph_duration(rigid), omegas[f], zetas[f], ringing);
        S_rigid = max2(S_rigid, hypot(S.re, S.im));
        omega_low = min2(omega_low, omegas[f]);
    }
    double j_max = lim->j_max;
    double tau = S_rigid > 0.0 ? sqrt(S_rigid / (j_max * omega_low * omega_low) / freqs) : 0.0;
    static double x[MAXP], jerks[MAXP], trial[MAXP], dx[MAXP];
    int n;
    if (doublets) {
        int all_zero = 1;
        for (int q = 0; q < n_modes; q++) if (modes[q].delta != 0.0) all_zero = 0;
        int count = freqs * (all_zero ? 1 : 2);
        Ph pad;
        if (padded(rigid, T, &pad) != 0 || with_doublets(&pad, count, j_max, tau, x, jerks, &n) != 0) return 0;
    } else {
        n = rigid->n;
        memcpy(x, rigid->d, sizeof(double) * (size_t)n);
        memcpy(jerks, rigid->j, sizeof(double) * (size_t)n);
    }
    static Held held[MAX_HELD];
    int n_held = held_limits(x, jerks, n, start, lim, held);
    for (int q = 0; q < n_pins && n_held < MAX_HELD; q++) held[n_held++] = pins[q];
    double v_scale = max2(lim->v_max, -lim->v_min), a_scale = max2(lim->a_max, -lim->a_min);
    System sys = {start, target, T, omegas, zetas, freqs, {a_scale, v_scale, v_scale * T, T, max2(S_rigid, j_max * 1e-12)},
                  held, n_held, ringing};
    int m = 4 + n_held + 2 * freqs;
    if (m > MAX_EQ) return 0;
    static double F[MAX_EQ], F_trial[MAX_EQ];
    double *C = malloc(sizeof(double) * (size_t)n * (size_t)m);
    double *C_trial = malloc(sizeof(double) * (size_t)n * (size_t)m);
    int frozen[MAXP];
    if (C == NULL || C_trial == NULL) { free(C); free(C_trial); return 0; }
    equations(&sys, x, jerks, n, F, C);
    double current = norm(F, m);
    int ok = 1;
    for (int it = 0; it < 40 && ok; it++) {
        if (current < 1e-14) break;
        for (int k = 0; k < n; k++) frozen[k] = 0;
        for (;;) {
            if (least_norm_step(C, frozen, n, m, F, dx) != 0) { ok = 0; break; }
            int any = 0;
            for (int k = 0; k < n; k++) if (x[k] <= 0.0 && dx[k] < 0.0 && !frozen[k]) { frozen[k] = 2; any = 1; }
            if (!any) break;
            for (int k = 0; k < n; k++) if (frozen[k] == 2) frozen[k] = 1;
        }
        if (!ok) break;
        double factor = 1.0;
        int moved = 0;
        for (int tries = 0; tries < 30; tries++) {
            double sum = 0.0;
            for (int k = 0; k < n; k++) { trial[k] = max2(x[k] + factor * dx[k], 0.0); sum += trial[k]; }
            if (sum > 2.0 * T) { factor *= 0.5; continue; }
            equations(&sys, trial, jerks, n, F_trial, C_trial);
            double next = norm(F_trial, m);
            if (next < current) {
                memcpy(x, trial, sizeof(double) * (size_t)n);
                memcpy(F, F_trial, sizeof(double) * (size_t)m);
                double *swap = C; C = C_trial; C_trial = swap;
                current = next;
                moved = 1;
                break;
            }
            factor *= 0.5;
        }
        if (!moved) break;
    }
    free(C); free(C_trial);
    if (!ok) return 0;
    if (!(current < 1e-11)) return 0;
    memcpy(d_out, x, sizeof(double) * (size_t)n);
    memcpy(j_out, jerks, sizeof(double) * (size_t)n);
    *n_out = n;
    return 1;
}

/* violation: 1 and the pin, 0 for None */
static int violation(const Ph *ph, const JpLimits *lim, Held *pin) {
    double worst = 1e-9;
    int found = 0;
    for (int k = 1; k < ph->n; k++) {
        double values[2] = {ph->a[k], ph->v[k]};
        double highs[2] = {lim->a_max, lim->v_max}, lows[2] = {lim->a_min, lim->v_min};
        for (int q = 0; q < 2; q++) {
            double levels[2] = {highs[q], lows[q]};
            for (int r = 0; r < 2; r++) {
                double excess = (values[q] - levels[r]) / levels[r];
                if (excess > worst) { worst = excess; pin->m = k; pin->kind = q; pin->level = levels[r]; found = 1; }
            }
        }
    }
    for (int k = 0; k < ph->n; k++) {
        double jk = ph->j[k], a0 = ph->a[k], a1 = ph->a[k + 1];
        if (jk != 0.0 && a0 * a1 < 0.0) {
            double turn = ph->v[k] - a0 * a0 / (2.0 * jk);
            double levels[2] = {lim->v_max, lim->v_min};
            for (int r = 0; r < 2; r++) {
                double excess = (turn - levels[r]) / levels[r];
                if (excess > worst) { worst = excess; pin->m = k; pin->kind = 2; pin->level = levels[r]; found = 1; }
            }
        }
    }
    return found;
}

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
    ph_extrema(ph, &vl, &vh, &al, &ah);
    double a_tol = relative * max2(lim->a_max, -lim->a_min), v_tol = relative * max2(lim->v_max, -lim->v_min);
    for (int k = 0; k < ph->n; k++) if (fabs(ph->j[k]) > lim->j_max * (1.0 + relative)) return 0;
    if (ah > lim->a_max + a_tol || al < lim->a_min - a_tol) return 0;
    if (vh > lim->v_max + v_tol || vl < lim->v_min - v_tol) return 0;
    int n = ph->n;
    double p_tol = relative * max2(max2(fabs(target[0] - ph->p[0]), v_tol * ph_duration(ph)), 1e-300);
    return fabs(ph->p[n] - target[0]) <= p_tol && fabs(ph->v[n] - target[1]) <= v_tol && fabs(ph->a[n] - target[2]) <= a_tol;
}

typedef struct {
    const JpRequest *rq;
    double states[JP_MAX_AXES][3];
    Rigid rigid;
    Ph *scratch;  /* MAX_EXTREMAL */
    char *message;
    int size;
} Planner;

static int plan_rigid(Planner *pl, double (*targets)[3], const JpLimits *limits, double *T, Ph *out) {
    Rigid rg;
    int status;
    if (pl->rq->straight)
        status = straight_line(&rg, pl->rq->axes, pl->states, targets, limits, T, out, pl->scratch, pl->message, pl->size);
    else
        status = synchronise(&rg, pl->rq->axes, pl->states, targets, limits, T, out, pl->scratch);
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
    static Ph rigid[JP_MAX_AXES];
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
            if (shapers[i] != NULL) { if (convolve_jerk(&rigid[i], shapers[i], &shaped[i]) != 0) return 0; }
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
        for (int i = 0; i < axes; i++) T = max2(T, ph_duration(&shaped[i]));
        int all = 1;
        for (int i = 0; i < axes; i++) {
            Ph pad;
            if (padded(&shaped[i], T, &pad) != 0) return 0;
            shaped[i] = pad;
            if (!within(&shaped[i], &rq->limits[i], rq->targets[i])) all = 0;
        }
        if (all) { *duration = T; return 1; }
        for (int i = 0; i < axes; i++) {
            double vl, vh, al, ah;
            ph_extrema(&shaped[i], &vl, &vh, &al, &ah);
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
            if (!(worst_amplitude(&phases[i], T, &rq->modes[i][q], ringing ? &ringing[i] : NULL) <= bounds[i][q] * (1.0 + 1e-9)))
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
    static double d[MAXP], j[MAXP];
    for (int attempt = 0; attempt < 8; attempt++) {
        int n;
        if (!cancel(pl->states[axis], rq->targets[axis], &rq->limits[axis], T, modes, n_modes, rigid, ringing, omegas, zetas,
                    freqs, doublets, pins, n_pins, d, j, &n))
            return 0;
        ph_set(out, pl->states[axis][0], pl->states[axis][1], pl->states[axis][2], d, j, n);
        Held past;
        if (violation(out, &rq->limits[axis], &past)) { pins[n_pins++] = past; continue; }
        if (!within(out, &rq->limits[axis], rq->targets[axis])) return 0;
        int found = 0;
        double worst_excess = 0.0, worst_omega = 0.0, worst_zeta = 0.0;
        for (int q = 0; q < n_modes; q++) {
            int count = band_count(&modes[q], T);
            for (int k = 0; k < count; k++) {
                double omega = band_frequency(&modes[q], T, k, count);
                double excess = amplitude(out->d, out->j, out->n, T, omega, modes[q].zeta, ringing) - bounds[q];
                if (excess > 0.0 && (!found || excess > worst_excess)) {
                    worst_excess = excess; worst_omega = omega; worst_zeta = modes[q].zeta; found = 1;
                }
            }
        }
        if (!found) return 1;
        if (freqs >= MAX_FREQ) return 0;
        omegas[freqs] = worst_omega; zetas[freqs++] = worst_zeta;
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
    static Ph lasting[JP_MAX_AXES];
    if (T != s->T0) { if (!profiles_lasting(&pl->rigid, T, -1, lasting)) return 0; }
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

static int plan(const JpRequest *rq, JpResult *result, Ph *scratch) {
    Planner pl = {rq, {{0}}, {0}, scratch, result->message, (int)sizeof(result->message)};
    int axes = rq->axes;
    if (axes < 1 || axes > JP_MAX_AXES) {
        snprintf(result->message, sizeof(result->message), "the number of axes must be in [1, %d], got %d", JP_MAX_AXES, axes);
        return -1;
    }
    for (int i = 0; i < axes; i++) {
        memcpy(pl.states[i], rq->states[i], sizeof(pl.states[i]));
        if (check_start_within(pl.states[i], &rq->limits[i], result->message, (int)sizeof(result->message), i) != 0) return -1;
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
    static Ph rigid[JP_MAX_AXES], ceiling_phases[JP_MAX_AXES], best[JP_MAX_AXES], found[JP_MAX_AXES];
    double T0;
    double targets[JP_MAX_AXES][3];
    memcpy(targets, rq->targets, sizeof(targets));
    if (plan_rigid(&pl, targets, rq->limits, &T0, rigid) != 0) return -1;
    if (rigid_blocks(&pl.rigid, axes, pl.states, targets, rq->limits, scratch) != 0) {
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
            if (profiles_lasting(&pl.rigid, T, -1, rigid)) { ok = 1; break; }
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
            result->references[i][q] = worst_amplitude(&rigid[i], T0, &rq->modes[i][q], ringing ? &ringing[i] : NULL);
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
            result->residuals[i][q] = worst_amplitude(&best[i], T, &rq->modes[i][q], ringing ? &ringing[i] : NULL);
        Ph pad;
        if (padded(&best[i], T, &pad) != 0) {
            snprintf(result->message, sizeof(result->message), "more than %d phases", MAXP);
            return -1;
        }
        copy_out(&pad, &result->phases[i]);
    }
    return 0;
}

int jp_plan(const JpRequest *request, JpResult *result) {
    memset(result, 0, sizeof(*result));
    Ph *scratch = malloc(sizeof(Ph) * MAX_EXTREMAL);
    if (scratch == NULL) {
        snprintf(result->message, sizeof(result->message), "out of memory");
        return -1;
    }
    int status = plan(request, result, scratch);
    free(scratch);
    return status;
}

int jp_rigid_duration(const JpRequest *request, double *duration, char *message, int size) {
    Ph *scratch = malloc(sizeof(Ph) * MAX_EXTREMAL);
    Rigid *rg = malloc(sizeof(Rigid));
    int status = -1;
    if (scratch != NULL && rg != NULL) {
        double states[JP_MAX_AXES][3], targets[JP_MAX_AXES][3];
        memcpy(states, request->states, sizeof(states));
        memcpy(targets, request->targets, sizeof(targets));
        status = 0;
        for (int i = 0; i < request->axes && status == 0; i++)
            status = check_start_within(states[i], &request->limits[i], message, size, i);
        if (status == 0 && rigid_blocks(rg, request->axes, states, targets, request->limits, scratch) == 0) {
            Candidate list[3 * JP_MAX_AXES];
            if (candidates(rg, list) > 0) *duration = list[0].t;
            else status = -1;
        } else if (status == 0) {
            status = -1;
        }
        if (status == -1) snprintf(message, (size_t)size, "unreachable target: no jerk-limited profile reaches it within the limits");
    }
    free(scratch);
    free(rg);
    return status;
}
