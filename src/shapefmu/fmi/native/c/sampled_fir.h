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

/* A sample instant s_k counts as reached at tau when s_k <= tau + SAMPLE_TOLERANCE * Ts. */
#define SAMPLE_TOLERANCE 1e-6
/* A communication step may span at most this many samples (else fmi2Error, no state change). */
#define MAX_SAMPLES_PER_STEP 10000000LL
/* The delay line holds at most this many samples (the longest delay of a design, in samples). */
#define MAX_DELAY_SAMPLES 10000000L

typedef struct {
    /* the taps: w0 at delay 0, then n_tail non-zero taps at delays >= 1, increasing */
    double w0;
    int n_tail;
    long *tail_delay;
    double *tail_weight;
    /* delay line of the committed inputs, twice over so that a read never wraps:
     * u[k - j] = line[pos + j] for j < length */
    long length;
    long pos;
    double *line;
    double r;
    /* the sample clock: k the current sample, latched when its input is fixed (v) */
    double t0, ts;
    long long k;
    int latched;
    double v;
} SampledFir;

/* Bytes of the FIR's state (clock, history part, delay line) and their copy / restore. */
size_t fir_state_size(const SampledFir *fir);
void fir_save(const SampledFir *fir, unsigned char *bytes);
/* 0, or -1 if the bytes do not fit this FIR's delay line. */
int fir_restore(SampledFir *fir, const unsigned char *bytes, size_t size);

/* At rest on u0 before the first sample, at sample 0 of the grid t0 + k ts, not latched. */
void fir_start(SampledFir *fir, double u0, double t0, double ts);
/* r from the delay line with the current taps (after the taps changed). */
void fir_recompute(SampledFir *fir);
/* y at the current communication point for input u. */
double fir_output(const SampledFir *fir, double u);
/* The samples a step from t to t + h reaches: K(t + h) - k (>= 0). */
double fir_samples_in_step(const SampledFir *fir, double t, double h);
/* Advance from t to t + h with input u held over the step (the spec's steps 2-4). */
void fir_step(SampledFir *fir, double t, double h, double u);

#endif
