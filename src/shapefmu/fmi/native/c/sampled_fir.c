/* The sampled FIR and its clock (sampled_fir.h).
 *
 * The clock is the one rule of shapefmu's sampled FMUs (sample_clock.c): the position on the grid
 * t0 + k Ts counted from the steps, grid_step. Sample k is committed with the input in effect at s_k:
 * the value set at s_k if the step starts there (not latched), or the value latched when a step left
 * the grid inside sample k. Between samples the output is held; on the grid it follows the input at
 * once (feed-through).
 *
 * Committing is exactly runtime/shaper_filter.py's FeedthroughFIR.commit: push u, then
 * r = sum of the tail taps times the delayed inputs, added in increasing delay from 0.
 */
#include <math.h>
#include <string.h>

#include "sampled_fir.h"

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

void fir_start(SampledFir *fir, double u0, double ts) {
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
    fir->ts = ts;
    memset(&fir->at, 0, sizeof fir->at);
    fir->latched = 0;
    fir->v = 0.0;
}

void fir_step(SampledFir *fir, const GridStep *step, double u) {
    const long long count = (long long)step->count;
    if (count > 0) {
        commit(fir, fir->latched ? fir->v : u);
        for (long long j = 1; j < count; j++) commit(fir, u);
        fir->latched = 0;
    }
    grid_take(&fir->at, step);
    /* A step that leaves the grid fixes the input of the sample it ends in. */
    if (!fir->latched && step->since != 0.0) {
        fir->latched = 1;
        fir->v = u;
    }
}

/* ---------------------------------------------------------------- state */

/* Scalars of the state, then the delay line. */
typedef struct {
    long long length, pos;
    long long latched;
    double v, r, ts;
    GridPosition at;
} FirScalars;

size_t fir_state_size(const SampledFir *fir) {
    return sizeof(FirScalars) + 2 * (size_t)fir->length * sizeof(double);
}

void fir_save(const SampledFir *fir, unsigned char *bytes) {
    const FirScalars s = {fir->length, fir->pos, fir->latched, fir->v, fir->r, fir->ts, fir->at};
    memcpy(bytes, &s, sizeof s);
    memcpy(bytes + sizeof s, fir->line, 2 * (size_t)fir->length * sizeof(double));
}

int fir_restore(SampledFir *fir, const unsigned char *bytes, size_t size, double ts) {
    FirScalars s;
    if (size != fir_state_size(fir)) return -1;
    memcpy(&s, bytes, sizeof s);
    /* What fmi2SetReal lets in: finite inputs (the latched one, every one in the delay line), and a
     * history part and grid position that finite inputs and steps of this period produce. */
    if (s.length != fir->length || s.pos < 0 || s.pos >= s.length || (s.latched != 0 && s.latched != 1)
        || !isfinite(s.v) || !isfinite(s.r) || s.ts != ts || !grid_valid(&s.at, ts))
        return -1;
    for (long long j = 0; j < 2 * s.length; j++) {
        double x;
        memcpy(&x, bytes + sizeof s + (size_t)j * sizeof x, sizeof x);
        if (!isfinite(x)) return -1;
    }
    fir->pos = (long)s.pos;
    fir->latched = (int)s.latched;
    fir->v = s.v;
    fir->r = s.r;
    fir->ts = s.ts;
    fir->at = s.at;
    memcpy(fir->line, bytes + sizeof s, 2 * (size_t)fir->length * sizeof(double));
    return 0;
}
