/* The residual of a mode as the sum of the jerk steps, the shaped ceiling's convolution and the cancellation by doublets (runtime/jerk_vibration.py).
 * Part of the C twin of the motion planner (jerk_planner.h); the order of the floating-point operations
 * follows the Python code, so that both plan the same move to rounding. */
#include "jerk_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------------
 * Residual vibration (jerk_vibration) */


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

double jpi_amplitude(const double *d, const double *j, int n, double T, double omega, double zeta,
                        const History *ringing) {
    double omega_d = omega * sqrt(1.0 - zeta * zeta);
    Cx S = jerk_sum(d, j, n, T, omega, zeta, ringing);
    return hypot(S.re, S.im) / (omega * omega * omega_d);
}

int jpi_band_count(const JpMode *m, double duration) {
    if (m->delta == 0.0) return 1;
    double width = 2.0 * m->delta * m->omega;
    int count = (int)ceil(width * duration * 20.0) + 1;
    if (count < 9) count = 9;
    if (count > 401) count = 401;
    return count;
}

double jpi_band_frequency(const JpMode *m, double duration, int k, int count) {
    if (m->delta == 0.0) return m->omega;
    (void)duration;
    double width = 2.0 * m->delta * m->omega;
    double low = m->omega * (1.0 - m->delta);
    return low + width * k / (count - 1);
}

double jpi_worst_amplitude(const Ph *ph, double T, const JpMode *m, const History *ringing) {
    int count = jpi_band_count(m, T);
    double worst = -INFINITY;
    for (int k = 0; k < count; k++) {
        double a = jpi_amplitude(ph->d, ph->j, ph->n, T, jpi_band_frequency(m, T, k, count), m->zeta, ringing);
        if (a > worst) worst = a;
    }
    return worst;
}

int jpi_padded(const Ph *ph, double T, Ph *out) {
    double rest = T - jpi_ph_duration(ph);
    if (rest <= 0.0) { *out = *ph; return 0; }
    if (ph->n + 1 > MAXP) return -1;
    double d[MAXP], j[MAXP];
    memcpy(d, ph->d, sizeof(double) * (size_t)ph->n);
    memcpy(j, ph->j, sizeof(double) * (size_t)ph->n);
    d[ph->n] = rest; j[ph->n] = 0.0;
    return jpi_ph_set(out, ph->p[0], ph->v[0], ph->a[0], d, j, ph->n + 1);
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
int jpi_convolve_jerk(const Ph *ph, const JpShaper *shaper, Ph *out, JpWorkspace *ws) {
    double *cuts = ws->cuts;
    double edges[MAXP + 1];
    edges[0] = 0.0;
    for (int k = 0; k < ph->n; k++) edges[k + 1] = edges[k] + ph->d[k];
    int n = 0;
    for (int k = 0; k <= ph->n; k++)
        for (int i = 0; i < shaper->count; i++) cuts[n++] = edges[k] + shaper->times[i];
    qsort(cuts, (size_t)n, sizeof(double), jpi_cmp_double);
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
    return jpi_ph_set(out, ph->p[0], ph->v[0], ph->a[0], d, j, merged - 1);
}

/* _with_doublets: the durations and jerks with count doublets */
static int with_doublets(const Ph *ph, int count, const JpLimits *lim, double tau, double *d, double *j, int *n_out) {
    double j_max = lim->j_max;
    double v_tol = 1e-9 * max2(lim->v_max, -lim->v_min);
    int n = ph->n;
    double acc[MAXP + 1], vel[MAXP + 1];
    memcpy(d, ph->d, sizeof(double) * (size_t)n);
    memcpy(j, ph->j, sizeof(double) * (size_t)n);
    memcpy(acc, ph->a, sizeof(double) * (size_t)(n + 1));
    memcpy(vel, ph->v, sizeof(double) * (size_t)(n + 1));
    for (int c = 0; c < count; c++) {
        if (n + 4 > MAXP) return -1;
        int k = -1;
        for (int i = 0; i < n; i++) {
            int on_limit = fabs(acc[i]) <= 1e-9 * lim->a_max
                           && min2(fabs(vel[i] - lim->v_max), fabs(vel[i] - lim->v_min)) <= v_tol;
            if (j[i] == 0.0 && !on_limit && (k < 0 || d[i] > d[k])) k = i;
        }
        if (k < 0)
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


static int held_limits(const double *d, const double *j, int n, const double *start, const JpLimits *lim, Held *held) {
    Ph ph;
    jpi_ph_set(&ph, start[0], start[1], start[2], d, j, n);
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
    JpWorkspace *ws;
} System;

/* _equations: F (m) and columns (n x m, column k at C[k * m]) ; returns m */
static int equations(const System *sys, const double *d, const double *j, int n, double *F, double *C) {
    Ph *ph = &sys->ws->equations_phases;
    jpi_ph_set(ph, sys->start[0], sys->start[1], sys->start[2], d, j, n);
    const double *sc = sys->scales;
    int m = 4 + sys->n_held + 2 * sys->freqs;
    double total = ph->e[n];
    F[0] = (ph->a[n] - sys->target[2]) / sc[0];
    F[1] = (ph->v[n] - sys->target[1]) / sc[1];
    F[2] = (ph->p[n] - sys->target[0]) / sc[2];
    F[3] = (total - sys->T) / sc[3];
    for (int k = 0; k < n; k++) {
        double R = total - ph->e[k + 1];
        double dv = ph->v[k + 1], da = ph->a[k + 1], dj = j[k];
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
        if (kind == 0) F[row] = (ph->a[mm] - level) / sc[0];
        else if (kind == 1) F[row] = (ph->v[mm] - level) / sc[1];
        else F[row] = (ph->v[mm] - ph->a[mm] * ph->a[mm] / (2.0 * j[mm]) - level) / sc[1];
        for (int k = 0; k < n; k++) {
            double value;
            if (k >= mm) value = 0.0;
            else if (kind == 0) value = j[k] / sc[0];
            else {
                double dv = ph->a[k + 1] + j[k] * (ph->e[mm] - ph->e[k + 1]);
                if (kind == 2) dv -= ph->a[mm] / j[mm] * j[k];
                value = dv / sc[1];
            }
            C[(size_t)k * m + row] = value;
        }
    }
    Cx *steps = sys->ws->steps;
    for (int f = 0; f < sys->freqs; f++) {
        double omega = sys->omegas[f], zeta = sys->zetas[f];
        double sre = -zeta * omega, sim = omega * sqrt(1.0 - zeta * zeta);
        double previous = 0.0;
        for (int k = 0; k <= n; k++) {
            double level = k < n ? j[k] : 0.0;
            Cx e = cx_exp(sre * (sys->T - ph->e[k]), sim * (sys->T - ph->e[k]));
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
static int least_norm_step(const double *C, const int *frozen, int n, int m, const double *F, double *dx, JpWorkspace *ws) {
    double *M = ws->M, *L = ws->L;
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
int jpi_cancel(const double *start, const double *target, const JpLimits *lim, double T, const JpMode *modes,
                  int n_modes, const Ph *rigid, const History *ringing, const double *omegas, const double *zetas,
                  int freqs, int doublets, const Held *pins, int n_pins, double *d_out, double *j_out, int *n_out,
                  JpWorkspace *ws) {
    double S_rigid = -INFINITY, omega_low = INFINITY;
    for (int f = 0; f < freqs; f++) {
        Cx S = jerk_sum(rigid->d, rigid->j, rigid->n, jpi_ph_duration(rigid), omegas[f], zetas[f], ringing);
        S_rigid = max2(S_rigid, hypot(S.re, S.im));
        omega_low = min2(omega_low, omegas[f]);
    }
    double j_max = lim->j_max;
    double tau = S_rigid > 0.0 ? sqrt(S_rigid / (j_max * omega_low * omega_low) / freqs) : 0.0;
    double *x = ws->x, *jerks = ws->jerks, *trial = ws->trial, *dx = ws->dx;
    int n;
    if (doublets) {
        int all_zero = 1;
        for (int q = 0; q < n_modes; q++) if (modes[q].delta != 0.0) all_zero = 0;
        int count = freqs * (all_zero ? 1 : 2);
        Ph pad;
        if (jpi_padded(rigid, T, &pad) != 0 || with_doublets(&pad, count, lim, tau, x, jerks, &n) != 0) return 0;
    } else {
        n = rigid->n;
        memcpy(x, rigid->d, sizeof(double) * (size_t)n);
        memcpy(jerks, rigid->j, sizeof(double) * (size_t)n);
    }
    Held *held = ws->held;
    int n_held = held_limits(x, jerks, n, start, lim, held);
    for (int q = 0; q < n_pins && n_held < MAX_HELD; q++) held[n_held++] = pins[q];
    double v_scale = max2(lim->v_max, -lim->v_min), a_scale = max2(lim->a_max, -lim->a_min);
    System sys = {start, target, T, omegas, zetas, freqs, {a_scale, v_scale, v_scale * T, T, max2(S_rigid, j_max * 1e-12)},
                  held, n_held, ringing, ws};
    int m = 4 + n_held + 2 * freqs;
    if (m > MAX_EQ) return 0;
    double *F = ws->F, *F_trial = ws->F_trial, *C = ws->C, *C_trial = ws->C_trial;
    int frozen[MAXP];
    equations(&sys, x, jerks, n, F, C);
    double current = norm(F, m);
    int ok = 1;
    for (int it = 0; it < 40 && ok; it++) {
        if (current < 1e-14) break;
        for (int k = 0; k < n; k++) frozen[k] = 0;
        for (;;) {
            if (least_norm_step(C, frozen, n, m, F, dx, ws) != 0) { ok = 0; break; }
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
    if (!ok) return 0;
    if (!(current < 1e-11)) return 0;
    memcpy(d_out, x, sizeof(double) * (size_t)n);
    memcpy(j_out, jerks, sizeof(double) * (size_t)n);
    *n_out = n;
    return 1;
}

/* violation: 1 and the pin, 0 for None */
int jpi_violation(const Ph *ph, const JpLimits *lim, Held *pin) {
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
