/* The absolute sample grid of a sampled FMU without feed-through (the EKF tuner): the C twin of
 * runtime/sample_clock.py's SampleClock, rule for rule.
 *
 * Sample instants s_k = t0 + k Ts (computed so, never summed); s_k is reached at tau when
 * s_k <= tau + delta, delta = SAMPLE_TOLERANCE Ts. A step (t, t + h] with the inputs u in effect
 * commits every instant it reaches: the current sample with its latched inputs (or u while it
 * is open), the ones strictly inside the step with u; then the newest sample is open if t + h is
 * on the grid, else latched with u. The FIR of the Shaper and ShapeFilter (sampled_fir.c) keeps
 * its own copy of these rules inlined in its hot path, with feed-through; this one serves kernels
 * that commit several inputs at once through a callback.
 */
#ifndef SAMPLE_CLOCK_H
#define SAMPLE_CLOCK_H

/* A sample instant s_k counts as reached at tau when s_k <= tau + SAMPLE_TOLERANCE * Ts. */
#define SAMPLE_TOLERANCE 1e-6
/* A communication step may span at most this many samples (else fmi2Error, no state change). */
#define MAX_SAMPLES_PER_STEP 10000000LL
#define CLOCK_MAX_INPUTS 4

typedef struct {
    double t0, ts;
    long long k;        /* the current sample */
    int latched;        /* its inputs are fixed (v) */
    double v[CLOCK_MAX_INPUTS];
} SampleClock;

void clock_start(SampleClock *clock, double t0, double ts);
/* K(t + h) - k, as a double (a step may span many samples): checked before clock_step. */
double clock_samples_in_step(const SampleClock *clock, double t, double h);
/* Take the step to end with the n inputs u held over it: commit(context, inputs) per instant. */
void clock_step(SampleClock *clock, double end, const double *u, int n,
                void (*commit)(void *context, const double *inputs), void *context);
/* The same two in one division: reached = clock_reached(end) = K(end), checked against k by the
 * caller, then clock_step_to. */
double clock_reached(const SampleClock *clock, double end);
void clock_step_to(SampleClock *clock, double end, double reached, const double *u, int n,
                   void (*commit)(void *context, const double *inputs), void *context);

#endif
