/* The STOS law (stos_law.h): runtime/stos.py operation for operation, so that the native
 * STOSController gives the pythonfmu one's numbers. The mathematics (switching curves, regions,
 * sub-sample switching, the settle hand-over) is derived in that module's docstring. */
#include <math.h>
#include <stddef.h>

#include "exact_sum.h"
#include "stos_law.h"

typedef struct {
    int quadrant, region;
    double level;
} Located;

typedef struct {
    const StosCurves *curves;
    const StosSettle *settle;  /* NULL: no settle law and no sub-sample switching */
    double bU, d, ts;
} Law;

/* (e, g, m) of one constant-input piece of length h (runtime/stos.py _piece). */
static void piece(double d, double h, double *e, double *g, double *m) {
    if (d == 0.0) {
        *e = 1.0, *g = h, *m = 0.5 * h * h;
        return;
    }
    *e = exp(-d * h);
    *g = -expm1(-d * h) / d;
    const double dh = d * h;
    if (dh < 1e-3) *m = h * h * (0.5 - dh / 6.0 + dh * dh / 24.0 - pow(dh, 3) / 120.0 + pow(dh, 4) / 720.0);
    else *m = (h - *g) / d;
}

/* F(w): x_e on the -U trajectory through the start of the decelerating tail at velocity w. */
static double base_curve(const StosCurves *k, double w) {
    const double bU = k->b * k->U, d = k->damping, x_p = k->x_base, v_p = k->v_decel[0];
    if (d == 0.0) return x_p - (w * w - v_p * v_p) / (2.0 * bU);
    const double ratio = d * (w - v_p) / (d * v_p + bU);
    if (ratio <= -1.0) return -INFINITY;
    return x_p - (w - v_p) / d + bU / (d * d) * log1p(ratio);
}

static double mid_curve(const StosCurves *k, int j, double v) {
    if (k->quadratic) return (k->alpha[j] * v + k->beta[j]) * v + k->gamma[j];
    return base_curve(k, k->a[j] * v + k->c[j]) + k->p[j] * v + k->q[j];
}

/* runtime/stos.py _second_quadrant: (region, u / U) for x_e < 0, v >= 0. */
static void second_quadrant(const StosCurves *k, double x_e, double v, double margin, int *region, double *level) {
    const int n = k->n;
    for (int j = n - 1; j >= 0; j--) {
        if (x_e >= mid_curve(k, j, v) - margin) {
            if (j < n - 1) {
                *region = n + j, *level = k->levels_mid[j];
                return;
            }
            const double *w = k->v_decel;
            if (v > w[0]) {
                *region = 2 * n - 1, *level = -1.0;
                return;
            }
            for (int i = 0; i < n - 1; i++)
                if (v > w[i + 1]) {
                    *region = 2 * n + i, *level = k->levels_decel[i];
                    return;
                }
            if (n > 1) *region = 3 * n - 2, *level = k->levels_decel[n - 2];
            else *region = 2 * n - 1, *level = 0.0;
            return;
        }
    }
    for (int j = 0; j < n - 1; j++)
        if (v < k->v_accel[j]) {
            *region = j, *level = k->levels_accel[j];
            return;
        }
    *region = n - 1, *level = 1.0;
}

/* runtime/stos.py locate: quadrant, region and u / U of eq. (17). */
static Located locate(const StosCurves *k, double x_e, double v, double margin) {
    Located at = {0, 0, 0.0};
    if (x_e < 0.0) {
        if (v >= 0.0) {
            at.quadrant = 1;
            second_quadrant(k, x_e, v, margin, &at.region, &at.level);
        } else {
            at.region = 2, at.level = 1.0;
        }
    } else if (x_e > 0.0) {
        if (v <= 0.0) {
            at.quadrant = -1;
            second_quadrant(k, -x_e, -v, margin, &at.region, &at.level);
            at.level = -at.level; /* eq. (19) */
        } else {
            at.region = 1, at.level = -1.0;
        }
    } else if (v > 0.0) {
        at.region = 1, at.level = -1.0;
    } else if (v < 0.0) {
        at.region = 2, at.level = 1.0;
    }
    return at;
}

static int arrived(const Law *law, double x_e, double v, double slack) {
    const StosSettle *s = law->settle;
    if (s == NULL || fabs(x_e) / s->x_enter + fabs(v) / s->v_enter > 1.0) return 0;
    return x_e * v >= 0.0 || fabs(v) <= 1e-3 * slack * law->bU * law->ts;
}

static void flow(const Law *law, double x_e, double v, double level, double h, double *x_next, double *v_next) {
    double e, g, m;
    piece(law->d, h, &e, &g, &m);
    *x_next = x_e + g * v + law->bU * level * m;
    *v_next = e * v + law->bU * level * g;
}

static int moved_on(const Law *law, Located present, double x_e, double v) {
    if (arrived(law, x_e, v, 1.0)) return 1;
    const Located at = locate(law->curves, x_e, v, 0.0);
    return at.quadrant != present.quadrant || (at.quadrant ? at.region > present.region : at.region != present.region);
}

/* runtime/stos.py STOSKernel._subsample: the held level matching the switched law's integral. */
static double subsample(const Law *law, double x_e, double v) {
    const double ts = law->ts;
    const Located present = locate(law->curves, x_e, v, 0.5 * law->bU * ts * ts);
    const double level = present.level;
    double x1, v1;
    flow(law, x_e, v, level, ts, &x1, &v1);
    if (!moved_on(law, present, x1, v1)) return level;
    double low = 0.0, high = 1.0;
    for (int i = 0; i < 40; i++) {
        const double alpha = 0.5 * (low + high);
        flow(law, x_e, v, level, alpha * ts, &x1, &v1);
        if (moved_on(law, present, x1, v1)) high = alpha;
        else low = alpha;
    }
    flow(law, x_e, v, level, high * ts, &x1, &v1);
    const double following = arrived(law, x1, v1, 1.0) ? 0.0 : locate(law->curves, x1, v1, 0.0).level;
    return high * level + (1.0 - high) * following;
}

static double settle_step(const Law *law, StosState *state, double x_e, double v) {
    const StosSettle *s = law->settle;
    const double U = law->curves->U;
    const double u = -(s->kp * x_e + s->kd * v + s->ki * state->integral);
    if (!((u > U && x_e < 0.0) || (u < -U && x_e > 0.0))) state->integral += s->ts * x_e;
    const double low = u < U ? u : U;
    return low > -U ? low : -U;
}

double stos_control(const StosCurves *curves, const StosSettle *settle, StosState *state, double target, double x_r,
                    double x_r_dot) {
    const Law law = {curves, settle, curves->b * curves->U, curves->damping, settle ? settle->ts : 0.0};
    const double x_e = x_r - target, v = x_r_dot;
    if (settle != NULL) {
        if (state->settling == 1.0) {
            if (fabs(x_e) / settle->x_exit + fabs(v) / settle->v_exit > 1.0) state->settling = 0.0, state->integral = 0.0;
        } else if (arrived(&law, x_e, v, 2.0)) {
            state->settling = 1.0, state->integral = 0.0;
        }
        if (state->settling == 1.0) return settle_step(&law, state, x_e, v);
        return curves->U * subsample(&law, x_e, v);
    }
    return curves->U * locate(curves, x_e, v, 0.0).level;
}

/* ---------------------------------------------------------------- the curves (runtime/stos.py stos_curves) */

const char *stos_design_curves(StosCurves *k, double *storage, double b, double U, double damping,
                               const double *times, const double *amplitudes, int n) {
    const double bU = b * U, d = damping;
    double *cumulative = storage, *levels_accel = storage + n, *v_accel = levels_accel + n, *levels_mid = v_accel + n;
    double *levels_decel = levels_mid + n, *v_decel = levels_decel + n, *a = v_decel + n, *c = a + n, *p = c + n;
    double *q = p + n, *alpha = q + n, *beta = alpha + n;
    for (int j = 0; j < n; j++) cumulative[j] = exact_sum(amplitudes, j + 1);
    cumulative[n - 1] = 1.0;
    double v = 0.0;
    for (int j = 0; j < n - 1; j++) {
        double e, g, m;
        piece(d, (times[j + 1] - times[0]) - (times[j] - times[0]), &e, &g, &m);
        v = e * v + bU * cumulative[j] * g;
        v_accel[j] = v;
        levels_accel[j] = cumulative[j];
        levels_mid[j] = 1.0 - 2.0 * cumulative[j];
        levels_decel[j] = cumulative[j] - 1.0;
    }
    double x = 0.0;
    v = 0.0;
    v_decel[n - 1] = 0.0;
    for (int j = n - 2; j >= 0; j--) {
        double e, g, m;
        piece(d, (times[j + 1] - times[0]) - (times[j] - times[0]), &e, &g, &m);
        const double level = cumulative[j] - 1.0;
        v = (v - bU * level * g) / e;
        x = x - g * v - bU * level * m;
        v_decel[j] = v;
    }
    double ak = 1.0, ck = 0.0, pk = 0.0, qk = 0.0;
    a[n - 1] = ak, c[n - 1] = ck, p[n - 1] = pk, q[n - 1] = qk;
    for (int j = n - 2; j >= 0; j--) {
        double e, g, m;
        piece(d, (times[j + 1] - times[0]) - (times[j] - times[0]), &e, &g, &m);
        const double level = 1.0 - 2.0 * cumulative[j];
        const double a1 = ak * e, c1 = ak * bU * level * g + ck, p1 = pk * e - g, q1 = pk * bU * level * g + qk - bU * level * m;
        ak = a1, ck = c1, pk = p1, qk = q1;
        a[j] = ak, c[j] = ck, p[j] = pk, q[j] = qk;
    }
    k->n = n, k->b = b, k->U = U, k->damping = d, k->x_base = x;
    k->levels_accel = levels_accel, k->v_accel = v_accel, k->levels_mid = levels_mid, k->levels_decel = levels_decel;
    k->v_decel = v_decel, k->a = a, k->c = c, k->p = p, k->q = q;
    k->quadratic = d == 0.0;
    /* the quadratics of the middle curves without damping: gamma in the storage's last n doubles */
    double *gamma = beta + n;
    for (int j = 0; j < n; j++) {
        alpha[j] = -0.5 / bU;
        beta[j] = p[j] - c[j] / bU;
        gamma[j] = x + (pow(v_decel[0], 2) - c[j] * c[j]) / (2.0 * bU) + q[j];
    }
    k->alpha = alpha, k->beta = beta, k->gamma = gamma;
    if (d > 0.0) { /* _min_distance: the shaper must fit what the damped rigid body can use */
        const double v_peak = bU / d * expm1(d * (times[n - 1] - times[0]));
        if (v_peak >= bU / d) return "the shaper is longer than the damped rigid body can use: its velocity limit b U / damping is below the peak the shaped move needs";
    }
    return NULL;
}
