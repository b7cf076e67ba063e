/* Closed-form impulse shapers in C (shaper_designs.h).
 *
 * All of them solve the zero-vibration constraint of Singer & Seering (1990), eq. (20) of
 * La-orpacharapan & Pao (paper 002) for one mode, sum_i A_i exp(sigma t_i) exp(j omega_d t_i) = 0,
 * sum_i A_i = 1, with sigma = zeta omega and omega_d = omega sqrt(1 - zeta^2):
 *
 *   ZV (paper 002, eq. 3): 1/(1+K), K/(1+K) at 0 and pi/omega_d, K = exp(-zeta pi / sqrt(1 - zeta^2)).
 *   ZV^(n+1) (ZV convolved with itself n more times: n = 1 ZVD, 2 ZVDD): n + 2 impulses spaced by
 *   pi/omega_d with amplitudes C(n+1, i) K^i / (1+K)^(n+1), the binomial expansion of
 *   (1 + K z)^(n+1) / (1+K)^(n+1), whose zero at z = -1/K has multiplicity n + 1.
 *   MZV: spacing 3 pi / (4 omega_d), amplitudes (1, sqrt(2) K, K^2) / (1 + sqrt(2) K + K^2) with
 *   K = exp(-sigma spacing).
 *
 * Several modes: the single-mode shapers are convolved (paper 002, section II-A), then sorted by
 * (time, amplitude) and impulses closer than 1e-12 of the shaper's length are merged, as
 * runtime/shaper_designs.py does; the arithmetic is the same, operation for operation.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "shaper_designs.h"

#define PI 3.14159265358979323846
/* Convolution makes coincident times; closer than this fraction of the length they are one. */
#define MERGE 1e-12
/* Impulse times within this fraction of a sample from a grid point lie on it (grid_impulses). */
#define ON_GRID 1e-9
/* Impulses of one mode at most (ZV^(n+1) for n <= 62). */
#define MAX_PER_MODE 64

ClosedFormKind closed_form_kind(const char *kind) {
    static const char *const names[] = {"zv", "zvd", "zvdd", "zv_dn", "mzv"};
    for (int i = 0; i < 5; i++)
        if (strcmp(kind, names[i]) == 0) return (ClosedFormKind)i;
    return KIND_NOT_CLOSED_FORM;
}

static int order_of(ClosedFormKind kind, int n) {
    switch (kind) {
    case KIND_ZV: return 0;
    case KIND_ZVD: return 1;
    case KIND_ZVDD: return 2;
    default: return n;
    }
}

int impulses_per_mode(ClosedFormKind kind, int n) { return kind == KIND_MZV ? 3 : order_of(kind, n) + 2; }

/* C(m, i) as a double, exact while it is below 2^53 (Python's math.comb, then float). */
static double binomial(int m, int i) {
    double c = 1.0;
    for (int j = 1; j <= i; j++) c = c * (double)(m - i + j) / (double)j;
    return c;
}

/* One mode's impulses; returns their count. */
static int single_mode(ClosedFormKind kind, int n, double omega, double zeta, double *t, double *a) {
    const double sigma = zeta * omega, omega_d = omega * sqrt(1.0 - zeta * zeta);
    if (kind == KIND_MZV) {
        const double spacing = 0.75 * PI / omega_d, k = exp(-sigma * spacing);
        const double w1 = sqrt(2.0) * k, w2 = k * k, total = 1.0 + w1 + w2;
        t[0] = 0.0, t[1] = spacing, t[2] = 2.0 * spacing;
        a[0] = 1.0 / total, a[1] = w1 / total, a[2] = w2 / total;
        return 3;
    }
    const int order = order_of(kind, n);
    const double half_period = PI / omega_d, k = exp(-sigma * half_period), norm = pow(1.0 + k, order + 1);
    for (int i = 0; i < order + 2; i++) {
        t[i] = i * half_period;
        a[i] = binomial(order + 1, i) * pow(k, i) / norm;
    }
    return order + 2;
}

static int by_time_then_amplitude(const void *x, const void *y) {
    const double *p = x, *q = y;
    if (p[0] != q[0]) return p[0] < q[0] ? -1 : 1;
    return (p[1] > q[1]) - (p[1] < q[1]);
}

int design_closed_form(ClosedFormKind kind, int n, int n_modes, const double *omega, const double *zeta,
                       double *times, double *amplitudes, int capacity, double *scratch) {
    if (impulses_per_mode(kind, n) > MAX_PER_MODE) return -1;
    double count = 1.0;
    for (int j = 0; j < n_modes; j++) count *= impulses_per_mode(kind, n);
    if (count > capacity) return -1;
    /* (time, amplitude) pairs in scratch, convolved mode by mode in place from the back. */
    int m = 1;
    scratch[0] = 0.0, scratch[1] = 1.0;
    for (int j = 0; j < n_modes; j++) {
        double t[MAX_PER_MODE], a[MAX_PER_MODE];
        const int per_mode = single_mode(kind, n, omega[j], zeta[j], t, a);
        for (int p = m - 1; p >= 0; p--) {
            const double tp = scratch[2 * p], ap = scratch[2 * p + 1];
            for (int q = per_mode - 1; q >= 0; q--) {
                scratch[2 * (p * per_mode + q)] = tp + t[q];
                scratch[2 * (p * per_mode + q) + 1] = ap * a[q];
            }
        }
        m *= per_mode;
    }
    qsort(scratch, (size_t)m, 2 * sizeof(double), by_time_then_amplitude);
    const double tolerance = MERGE * fmax(scratch[2 * (m - 1)] - scratch[0], 1.0);
    int merged = 0;
    for (int p = 0; p < m; p++) {
        if (merged > 0 && scratch[2 * p] - times[merged - 1] <= tolerance) {
            amplitudes[merged - 1] += scratch[2 * p + 1];
        } else {
            times[merged] = scratch[2 * p];
            amplitudes[merged] = scratch[2 * p + 1];
            merged++;
        }
    }
    return merged;
}

double grid_split(double t, double ts, long *k) {
    const double x = t / ts, whole = floor(x);
    double alpha = x - whole;
    *k = (long)whole;
    if (alpha > 1.0 - ON_GRID) {
        *k += 1;
        alpha = 0.0;
    } else if (alpha < ON_GRID) {
        alpha = 0.0;
    }
    return alpha;
}
