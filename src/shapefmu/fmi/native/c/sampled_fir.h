/* A sampled FIR filter on the absolute time grid t0 + k Ts: the native counterpart of
 * runtime/shaper_filter.py's FeedthroughFIR driven by the clock of notes' sampled semantics
 * (DESIGN.md, "Sampled FMUs take their samples on the absolute grid").
 *
 * y[k] = w0 u[k] + r[k], r[k] = sum_{d >= 1} w_d u[k - d]: the feed-through part w0 u is kept apart
 * from the committed history r, so that an input set at a communication point on the grid shows
 * in y at once without committing the sample.
 */
#ifndef SAMPLED_FIR_H
#define SAMPLED_FIR_H

#include <stddef.h>

#include "sample_clock.h" /* GridPosition, MAX_SAMPLES_PER_STEP */
/* The delay line holds at most this many samples (the longest delay of a design, in samples). */
#define MAX_DELAY_SAMPLES 10000000L

typedef struct {
    /* the taps: w0 at delay 0, then n_tail non-zero taps at delays d >= 1, increasing, each
     * stored with its offset d - 1 into the delay line */
    double w0;
    int n_tail;
    long *tail_offset;
    double *tail_weight;
    /* delay line of the committed inputs, twice over so that a read never wraps:
     * u[k - j] = line[pos + j] for j < length */
    long length;
    long pos;
    double *line;
    double r;
    /* the sample clock (sample_clock.h): where the filter stands on its grid, latched when the
     * current sample's input is fixed (v) */
    double ts;
    GridPosition at;
    int latched;
    double v;
} SampledFir;

/* Bytes of the FIR's state (clock, history part, delay line) and their copy / restore. */
size_t fir_state_size(const SampledFir *fir);
void fir_save(const SampledFir *fir, unsigned char *bytes);
/* 0, or -1 if the bytes are no state of this FIR: another delay line, or a value a running filter
 * cannot hold (a non-finite input, history or position on the grid of its period ts). */
int fir_restore(SampledFir *fir, const unsigned char *bytes, size_t size, double ts);

/* At rest on u0 before the first sample, at sample 0 of the grid of period ts, not latched. */
void fir_start(SampledFir *fir, double u0, double ts);
/* r from the delay line with the current taps (after the taps changed). */
void fir_recompute(SampledFir *fir);
/* y at the current communication point for input u. */
static inline double fir_output(const SampledFir *fir, double u) {
    return fir->w0 * (fir->latched ? fir->v : u) + fir->r;
}
/* Take step (grid_step of the FIR's position, its count bounded by the caller) with input u held over it. */
void fir_step(SampledFir *fir, const GridStep *step, double u);

#endif
