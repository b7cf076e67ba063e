/* The sample grid of a sampled FMU (sample_clock.h), as runtime/sample_clock.py states it.
 *
 * Counting. Samples are taken at s_k = t0 + k Ts, but the host's absolute time is never compared with
 * them: at t0 = 1.7e9 (a Unix epoch) doubles are 2.4e-7 s apart, a host's t += h drifts by ulps of t
 * at every step, and 1e-6 Ts is below both. The position is (k, since): k the newest instant reached,
 * since the time after it, summed from the steps h (since + h, then minus whole Ts). Only numbers of
 * the size of Ts and h enter, so the same steps take the same samples, bit for bit, whatever t0 is,
 * and the count never drifts.
 *
 * Reached. A step of h reaches instant k + j when j Ts <= since + h + delta: the largest such j, the
 * floor of a quotient guarded by the products j Ts themselves. It ends on the grid when what is left,
 * since + h - j Ts, is within delta of 0, and since is then set to 0, so the error of a step such as
 * 0.7 Ts never adds up.
 *
 * Tolerance. delta = SAMPLE_TOLERANCE Ts. A host that aims a step at an absolute instant (a tick: h =
 * target - t) computes h from two times rounded to ulp(t), so that h is a whole number of those ulps,
 * and it is off by their rounding: half an ulp at the target, half a one at the grid point it last aimed
 * at, half a one for each free step since then (a step the host sized itself, whose end t + h it
 * rounded; an aimed step adds none). For an aimed step only (h a multiple of ulp(max(|t|, |t + h|)))
 * delta grows by (m + 1) ulp, m those free steps, to at most AIMED_STEP_TOLERANCE Ts. A free step (Ts,
 * 0.7 Ts, a random size: not a multiple of ulp(t) at large t) keeps delta, and takes exactly the
 * samples it takes at t0 = 0.
 *
 * Latching (SampleClock; the FIR keeps its own, sampled_fir.c). A step commits every instant it
 * reaches: the current sample with its latched inputs (or u while it is open), the ones after it
 * with u; then the newest sample is open if the step ended on the grid, else latched with u.
 */
#include <math.h>
#include <string.h>

#include "sample_clock.h"

/* The largest j with j ts <= after + delta, and what is left after it. */
static void reach(double after, double ts, double delta, GridStep *step) {
    const double limit = after + delta;
    double j;
    if (limit < ts) j = 0.0;  /* the usual steps, without a division: none or one instant */
    else if (limit < 2.0 * ts) j = 1.0;
    else {
        j = floor(limit / ts);
        /* The division rounds; the products decide (j Ts is what "reached" means). */
        if ((j + 1.0) * ts <= limit) j += 1.0;
        else if (j * ts > limit) j -= 1.0;
    }
    step->count = j;
    step->since = after - j * ts;
}

GridStep grid_step(const GridPosition *at, double ts, double t, double h) {
    const double a = fmax(fabs(t), fabs(t + h)), ulp = nextafter(a, INFINITY) - a;
    const double whole = h / ulp;  /* exact: an ulp is a power of two */
    const int aimed = isfinite(ulp) && whole == floor(whole);
    double delta = SAMPLE_TOLERANCE * ts;
    if (aimed) delta += fmin(((double)at->steps + 1.0) * ulp, AIMED_STEP_TOLERANCE * ts);
    GridStep step;
    reach(at->since + h, ts, delta, &step);
    const int on_grid = fabs(step.since) <= delta;
    /* Free steps add the host's rounding of t + h; an aimed step to a grid point ends it. */
    step.steps = !aimed ? at->steps + 1 : on_grid ? 0 : at->steps;
    if (on_grid) step.since = 0.0;
    return step;
}

void grid_take(GridPosition *at, const GridStep *step) {
    at->k += (long long)step->count;
    at->since = step->since;
    at->steps = step->steps;
}

void clock_start(SampleClock *clock, double ts) {
    memset(clock, 0, sizeof *clock);
    clock->ts = ts;
}

int clock_valid(const SampleClock *clock, int n) {
    if (!(clock->ts > 0.0 && clock->ts < INFINITY) || !grid_valid(&clock->at, clock->ts)
        || (clock->latched != 0 && clock->latched != 1))
        return 0;
    for (int i = 0; i < n && clock->latched; i++)
        if (!isfinite(clock->v[i])) return 0;
    return 1;
}

void clock_take(SampleClock *clock, const GridStep *step, const double *u, int n,
                void (*commit)(void *context, const double *inputs), void *context) {
    const long long count = (long long)step->count;
    if (count > 0) {
        commit(context, clock->latched ? clock->v : u);
        for (long long j = 1; j < count; j++) commit(context, u);
        clock->latched = 0;
    }
    grid_take(&clock->at, step);
    if (!clock->latched && step->since != 0.0) {
        clock->latched = 1;
        memcpy(clock->v, u, (size_t)n * sizeof(double));
    }
}

void step_time_add(StepTime *time, double h) {
    const double total = time->sum + h;
    /* The rounding error of the sum, exact (Neumaier): from the smaller of the two terms. */
    time->compensation += fabs(time->sum) >= fabs(h) ? (time->sum - total) + h : (h - total) + time->sum;
    time->sum = total;
}

double step_time_value(const StepTime *time) { return time->sum + time->compensation; }
