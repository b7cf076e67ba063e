/* The sampled FIR and its clock (sampled_fir.h).
 *
 * The clock follows the one spec of shapefmu's sampled FMUs: sample instants s_k = t0 + k Ts
 * (computed so, never summed), s_k reached at tau when s_k <= tau + delta, delta = 1e-6 Ts, so the
 * newest reached sample is K(tau) = floor((tau - t0) / Ts + 1e-6), guarded against rounding. Sample
 * k is committed with the input in effect at s_k: the value set at s_k if the step starts there
 * (not latched), or the value latched when a step left the grid inside sample k. Between samples
 * the output is held; on the grid it follows the input at once (feed-through).
 *
 * Committing is exactly runtime/shaper_filter.py's FeedthroughFIR.commit: push u, then
 * r = sum of the tail taps times the delayed inputs, added in increasing delay from 0.
 */
#include <math.h>
#include <string.h>

#include "sampled_fir.h"

/* ---------------------------------------------------------------- clock */

static inline double instant(const SampledFir *fir, long long k) { return fir->t0 + (double)k * fir->ts; }

/* K(tau): the index of the newest sample reached at tau, as a double (a step may span many). */
static double newest_sample(const SampledFir *fir, double tau) {
    const double delta = SAMPLE_TOLERANCE * fir->ts;
    double k = floor((tau - fir->t0) / fir->ts + SAMPLE_TOLERANCE);
    if (fir->t0 + (k + 1.0) * fir->ts <= tau + delta) k += 1.0;
    if (fir->t0 + k * fir->ts > tau + delta) k -= 1.0;
    return k;
}

/* Sample k becomes the current one: its instant and the next two's, computed once. */
static inline void set_sample(SampledFir *fir, long long k) {
    if (k == fir->k + 1) { /* the usual step: the instants move up by one */
        fir->s_k = fir->s_next;
        fir->s_next = fir->s_after;
    } else {
        fir->s_k = instant(fir, k);
        fir->s_next = instant(fir, k + 1);
    }
    fir->s_after = instant(fir, k + 2);
    fir->k = k;
}

static inline long long fir_reached(const SampledFir *fir, double tau) {
    /* A step of at most one sample, the common case, needs no division: the K with
     * s_K <= tau + delta < s_{K+1} is k or k + 1 (the s computed as everywhere, t0 + K Ts). */
    const double limit = tau + fir->delta;
    if (fir->s_next > limit) {
        if (fir->s_k <= limit) return fir->k;
    } else if (fir->s_after > limit) {
        return fir->k + 1;
    }
    return (long long)newest_sample(fir, tau);
}

static inline int on_grid(const SampledFir *fir, double tau, long long k) {
    const double s = k == fir->k ? fir->s_k : k == fir->k + 1 ? fir->s_next : instant(fir, k);
    return fabs(tau - s) <= fir->delta;
}

/* ---------------------------------------------------------------- filter */

static inline void commit(SampledFir *fir, double u) {
    const long length = fir->length;
    fir->pos = fir->pos ? fir->pos - 1 : length - 1;
    double *history = fir->line + fir->pos;
    history[0] = history[length] = u;
    /* tail delay d reads u[k + 1 - d]: the sample committed d - 1 samples ago */
    const long *offset = fir->tail_offset;
    const double *weight = fir->tail_weight;
    double r = 0.0;
    for (int i = 0; i < fir->n_tail; i++) r += weight[i] * history[offset[i]];
    fir->r = r;
}

void fir_recompute(SampledFir *fir) {
    const double *history = fir->line + fir->pos;
    double r = 0.0;
    for (int i = 0; i < fir->n_tail; i++) r += fir->tail_weight[i] * history[fir->tail_offset[i]];
    fir->r = r;
}

void fir_start(SampledFir *fir, double u0, double t0, double ts) {
    for (long j = 0; j < 2 * fir->length; j++) fir->line[j] = u0;
    fir->pos = 0;
    /* r = u0 times the sum of the tail taps (FeedthroughFIR: u0 * fsum(tail)); compensated
     * (Neumaier) so that a long filter's sum is as exact as fsum's to the last bits. */
    double sum = 0.0, compensation = 0.0;
    for (int i = 0; i < fir->n_tail; i++) {
        const double w = fir->tail_weight[i], t = sum + w;
        compensation += fabs(sum) >= fabs(w) ? (sum - t) + w : (w - t) + sum;
        sum = t;
    }
    fir->r = u0 * (sum + compensation);
    fir->t0 = t0;
    fir->ts = ts;
    fir->delta = SAMPLE_TOLERANCE * ts;
    fir->k = -2; /* no cached instants yet */
    set_sample(fir, 0);
    fir->latched = 0;
    fir->v = 0.0;
}

double fir_samples_in_step(const SampledFir *fir, double t, double h) {
    return newest_sample(fir, t + h) - (double)fir->k;
}

void fir_step(SampledFir *fir, double end, double u) {
    if (!fir->latched && fir->s_next <= end + fir->delta && fir->s_after > end + fir->delta) {
        /* The usual step: from sample k on the grid to exactly the next one, which it reaches. */
        commit(fir, u);
        set_sample(fir, fir->k + 1);
        if (fabs(end - fir->s_k) > fir->delta) {
            fir->latched = 1;
            fir->v = u;
        }
        return;
    }
    long long k_end = fir_reached(fir, end);
    /* A host's time may lag the FMU's by the layer's tolerance: the clock never runs backwards. */
    if (k_end < fir->k) k_end = fir->k;
    if (k_end == fir->k) {
        /* Nothing sampled; a step that leaves the grid fixes sample k's input. */
        if (!fir->latched && !on_grid(fir, end, fir->k)) {
            fir->latched = 1;
            fir->v = u;
        }
        return;
    }
    commit(fir, fir->latched ? fir->v : u);
    for (long long j = fir->k + 1; j < k_end; j++) commit(fir, u);
    const int grid = on_grid(fir, end, k_end);
    set_sample(fir, k_end);
    fir->latched = !grid;
    fir->v = fir->latched ? u : 0.0;
}

/* ---------------------------------------------------------------- state */

/* Scalars of the state, then the delay line. */
typedef struct {
    long long k;
    long long length, pos;
    long long latched;
    double v, r, t0, ts;
} FirScalars;

size_t fir_state_size(const SampledFir *fir) {
    return sizeof(FirScalars) + 2 * (size_t)fir->length * sizeof(double);
}

void fir_save(const SampledFir *fir, unsigned char *bytes) {
    const FirScalars s = {fir->k, fir->length, fir->pos, fir->latched, fir->v, fir->r, fir->t0, fir->ts};
    memcpy(bytes, &s, sizeof s);
    memcpy(bytes + sizeof s, fir->line, 2 * (size_t)fir->length * sizeof(double));
}

int fir_restore(SampledFir *fir, const unsigned char *bytes, size_t size) {
    FirScalars s;
    if (size != fir_state_size(fir)) return -1;
    memcpy(&s, bytes, sizeof s);
    if (s.length != fir->length || s.pos < 0 || s.pos >= s.length || s.k < 0 || (s.latched != 0 && s.latched != 1)
        || !(s.ts > 0.0))
        return -1;
    fir->pos = (long)s.pos;
    fir->latched = (int)s.latched;
    fir->v = s.v;
    fir->r = s.r;
    fir->t0 = s.t0;
    fir->ts = s.ts;
    fir->delta = SAMPLE_TOLERANCE * s.ts;
    fir->k = s.k - 2; /* no cached instants yet */
    set_sample(fir, s.k);
    memcpy(fir->line, bytes + sizeof s, 2 * (size_t)fir->length * sizeof(double));
    return 0;
}
