/* The absolute sample grid (sample_clock.h), as runtime/sample_clock.py states it. */
#include <math.h>
#include <string.h>

#include "sample_clock.h"

/* K(tau) as a double: the division rounds; the instants themselves decide (t0 + k Ts is what
 * "reached" means). */
static double newest(const SampleClock *clock, double tau) {
    const double delta = SAMPLE_TOLERANCE * clock->ts;
    double k = floor((tau - clock->t0) / clock->ts + SAMPLE_TOLERANCE);
    if (clock->t0 + (k + 1.0) * clock->ts <= tau + delta) k += 1.0;
    else if (clock->t0 + k * clock->ts > tau + delta) k -= 1.0;
    return k;
}

static int on_grid(const SampleClock *clock, double tau, long long k) {
    return fabs(tau - (clock->t0 + (double)k * clock->ts)) <= SAMPLE_TOLERANCE * clock->ts;
}

void clock_start(SampleClock *clock, double t0, double ts) {
    memset(clock, 0, sizeof *clock);
    clock->t0 = t0;
    clock->ts = ts;
}

double clock_reached(const SampleClock *clock, double end) { return newest(clock, end); }

double clock_samples_in_step(const SampleClock *clock, double t, double h) {
    return newest(clock, t + h) - (double)clock->k;
}

void clock_step(SampleClock *clock, double end, const double *u, int n,
                void (*commit)(void *context, const double *inputs), void *context) {
    clock_step_to(clock, end, newest(clock, end), u, n, commit, context);
}

void clock_step_to(SampleClock *clock, double end, double reached, const double *u, int n,
                   void (*commit)(void *context, const double *inputs), void *context) {
    long long k_end = (long long)reached;
    /* A host's time may lag the FMU's by the layer's tolerance: the clock never runs backwards. */
    if (k_end < clock->k) k_end = clock->k;
    if (k_end > clock->k) {
        commit(context, clock->latched ? clock->v : u);
        for (long long j = clock->k + 1; j < k_end; j++) commit(context, u);
        clock->k = k_end;
        clock->latched = 0;
    }
    if (!clock->latched && !on_grid(clock, end, clock->k)) {
        clock->latched = 1;
        memcpy(clock->v, u, (size_t)n * sizeof(double));
    }
}
