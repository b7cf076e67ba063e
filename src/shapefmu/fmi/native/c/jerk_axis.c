/* One axis: its phases, the real roots of the polynomials its profiles solve, and its extremal profiles and blocked intervals (runtime/jerk_profiles.py).
 * Part of the C twin of the motion planner (jerk_planner.h); the order of the floating-point operations
 * follows the Python code, so that both plan the same move to rounding. */
#include "jerk_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------------
 * Phases (jerk_profiles.Phases) */


int jpi_ph_set(Ph *ph, double p0, double v0, double a0, const double *d, const double *j, int n) {
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

double jpi_ph_duration(const Ph *ph) { return ph->e[ph->n]; }

void jpi_ph_extrema(const Ph *ph, double *v_low, double *v_high, double *a_low, double *a_high) {
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

int jpi_cmp_double(const void *a, const void *b) {
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
    qsort(roots, (size_t)count, sizeof(double), jpi_cmp_double);
    return count;
}

/* ------------------------------------------------------------------------------------------------
 * One axis's problem (jerk_profiles.Problem) and its extremal profiles */



void jpi_problem_set(Problem *pr, const double *state, const double *target, const JpLimits *lim) {
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
int jpi_accept(const Problem *pr, const double *durations, const double *jerks, int n, Ph *out) {
    double clipped[MAXP];
    if (n > MAXP) return 0;
    for (int k = 0; k < n; k++) {
        if (durations[k] < -pr->tol_t || durations[k] != durations[k]) return 0;
        clipped[k] = durations[k] > 0.0 ? durations[k] : 0.0;
    }
    jpi_ph_set(out, pr->p0, pr->v0, pr->a0, clipped, jerks, n);
    if (fabs(out->p[n] - pr->pf) > pr->tol_p || fabs(out->v[n] - pr->vf) > pr->tol_v || fabs(out->a[n] - pr->af) > pr->tol_a)
        return 0;
    double vl, vh, al, ah;
    jpi_ph_extrema(out, &vl, &vh, &al, &ah);
    const JpLimits *lim = &pr->lim;
    if (ah > lim->a_max + pr->tol_a || al < lim->a_min - pr->tol_a || vh > lim->v_max + pr->tol_v || vl < lim->v_min - pr->tol_v)
        return 0;
    return 1;
}

/* velocity_change: three phases (durations t[3], jerks j[3]) from (v0, a0) to (v1, a1). */
void jpi_velocity_change(double v0, double a0, double v1, double a1, double a_max, double a_min, double j_max,
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

double jpi_sum3(const double *t) { return ((0.0 + t[0]) + t[1]) + t[2]; }

static void oriented(const JpLimits *lim, int up, double *vU, double *aU, double *aL, double *J) {
    if (up) { *vU = lim->v_max; *aU = lim->a_max; *aL = lim->a_min; *J = lim->j_max; }
    else { *vU = lim->v_min; *aU = lim->a_min; *aL = lim->a_max; *J = -lim->j_max; }
}

/* _with_cruise */
static int with_cruise(const Problem *pr, int up, Ph *out) {
    const JpLimits *lim = &pr->lim;
    double vU, aU, aL, J, ta[3], ja[3], td[3], jd[3];
    oriented(lim, up, &vU, &aU, &aL, &J);
    jpi_velocity_change(pr->v0, pr->a0, vU, 0.0, lim->a_max, lim->a_min, lim->j_max, ta, ja);
    jpi_velocity_change(vU, 0.0, pr->vf, pr->af, lim->a_max, lim->a_min, lim->j_max, td, jd);
    if ((ja[0] != J && ta[0] > pr->tol_t) || (jd[0] != -J && td[0] > pr->tol_t)) return 0;
    double durations[7] = {ta[0], ta[1], ta[2], 0.0, td[0], td[1], td[2]};
    double jerks[7] = {J, 0.0, -J, 0.0, -J, 0.0, J};
    Ph without;
    jpi_ph_set(&without, pr->p0, pr->v0, pr->a0, durations, jerks, 7);
    durations[3] = (pr->pf - without.p[7]) / vU;
    if (durations[3] <= pr->tol_t) return 0;
    return jpi_accept(pr, durations, jerks, 7, out);
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
        if (*found < capacity && jpi_accept(pr, d, jerks, 7, &list[*found])) (*found)++;
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
        if (*found < capacity && jpi_accept(pr, d, jerks, 7, &list[*found])) (*found)++;
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
        if (*found < capacity && jpi_accept(pr, d, jerks, 7, &list[*found])) (*found)++;
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
        if (*found < capacity && jpi_accept(pr, d, jerks, 7, &list[*found])) (*found)++;
    }
}



/* extremal_profiles + block: 0, or -1 when no profile reaches the target */
int jpi_block_of(const Problem *pr, Block *b, Ph *scratch /* MAX_EXTREMAL */) {
    int found = 0;
    for (int up = 1; up >= 0; up--) {
        if (found < MAX_EXTREMAL && with_cruise(pr, up, &scratch[found])) found++;
        without_cruise(pr, up, scratch, &found, MAX_EXTREMAL);
    }
    if (pr->pd == 0.0 && pr->v0 == 0.0 && pr->vf == 0.0 && pr->a0 == 0.0 && pr->af == 0.0 && found < MAX_EXTREMAL) {
        double zeros[7] = {0, 0, 0, 0, 0, 0, 0};
        jpi_ph_set(&scratch[found++], pr->p0, 0.0, 0.0, zeros, zeros, 7);
    }
    /* stable insertion sort by duration (Python's list.sort) */
    int order[MAX_EXTREMAL];
    for (int k = 0; k < found; k++) order[k] = k;
    for (int k = 1; k < found; k++) {
        int x = order[k], i = k - 1;
        while (i >= 0 && jpi_ph_duration(&scratch[order[i]]) > jpi_ph_duration(&scratch[x])) { order[i + 1] = order[i]; i--; }
        order[i + 1] = x;
    }
    int distinct[MAX_EXTREMAL], count = 0;
    for (int k = 0; k < found; k++) {
        const Ph *ph = &scratch[order[k]];
        if (count == 0 || jpi_ph_duration(ph) - jpi_ph_duration(&scratch[distinct[count - 1]]) > 1e3 * pr->tol_t)
            distinct[count++] = order[k];
    }
    if (count == 0) return -1;
    b->fastest = scratch[distinct[0]];
    int rest = count - 1;
    b->intervals = 0;
    if (rest == 1) {
        b->intervals = 1;
        b->left[0] = jpi_ph_duration(&b->fastest); b->right[0] = jpi_ph_duration(&scratch[distinct[1]]);
        b->at_right[0] = scratch[distinct[1]];
    } else if (rest == 2 || rest == 3) {
        int last = rest == 2 ? 2 : 3;
        b->intervals = 1;
        b->left[0] = jpi_ph_duration(&scratch[distinct[1]]); b->right[0] = jpi_ph_duration(&scratch[distinct[last]]);
        b->at_right[0] = scratch[distinct[last]];
    } else if (rest == 4) {
        b->intervals = 2;
        for (int i = 0; i < 2; i++) {
            b->left[i] = jpi_ph_duration(&scratch[distinct[1 + 2 * i]]);
            b->right[i] = jpi_ph_duration(&scratch[distinct[2 + 2 * i]]);
            b->at_right[i] = scratch[distinct[2 + 2 * i]];
        }
    }
    return 0;
}

double jpi_t_min(const Block *b) { return jpi_ph_duration(&b->fastest); }

int jpi_blocked(const Block *b, double t) {
    if (t < jpi_t_min(b)) return 1;
    for (int i = 0; i < b->intervals; i++) if (b->left[i] < t && t < b->right[i]) return 1;
    return 0;
}
