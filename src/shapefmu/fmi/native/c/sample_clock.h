/* The sample grid t0 + k Ts of a sampled FMU, counted from the steps the host takes: the C twin of
 * runtime/sample_clock.py, rule for rule (sample_clock.c states the rule).
 *
 * GridPosition and grid_step are the rule; every sampled model part keeps its position with them (the
 * FIR of the Shaper and ShapeFilter, sampled_fir.c; the SampleClock below for kernels that commit
 * several inputs at once through a callback), and the FMI 3.0 layer keeps the position of its input
 * clock with them (fmi3_layer_clock.c), so that ticks and samples are the same instants. StepTime is
 * the time since the start of an FMU that plays a function of it (the profile generator).
 */
#ifndef SAMPLE_CLOCK_H
#define SAMPLE_CLOCK_H

/* runtime/limits.py's: a step ends on the grid within SAMPLE_TOLERANCE Ts; for a step aimed at an
 * absolute instant the tolerance grows by the host's rounding, to at most AIMED_STEP_TOLERANCE Ts. */
#define SAMPLE_TOLERANCE 1e-6
#define AIMED_STEP_TOLERANCE 0.25
/* A communication step may span at most this many samples (else fmi2Error, no state change). */
#define MAX_SAMPLES_PER_STEP 10000000LL
#define CLOCK_MAX_INPUTS 4

/* Where an FMU stands on its grid. */
typedef struct {
    long long k;      /* the newest sample instant reached */
    double since;     /* the time after it, summed from the steps: 0 on the grid */
    long long steps;  /* free steps (not aimed at an absolute instant) since the host last aimed at the grid */
} GridPosition;

/* What a step does: the instants it reaches after the position's (a double: a step may span many,
 * which the caller bounds before grid_take), then the time after the newest (0: the step ends on the
 * grid) and the free steps since the host last aimed at the grid. */
typedef struct {
    double count;
    double since;
    long long steps;
} GridStep;

/* The step (t, t + h], h > 0 finite, from position at of the grid of period ts. */
GridStep grid_step(const GridPosition *at, double ts, double t, double h);
/* Move at by step (whose count the caller has bounded). */
void grid_take(GridPosition *at, const GridStep *step);
/* Whether at is a position on the grid of period ts a state may restore: k, steps >= 0, 0 <= since < ts
 * (inline: the generic layers' FMU states check their clock's, in FMUs without sample_clock.c). */
static inline int grid_valid(const GridPosition *at, double ts) {
    return at->k >= 0 && at->steps >= 0 && at->since >= 0.0 && at->since < ts;
}

typedef struct {
    double ts;
    GridPosition at;
    int latched;      /* the current sample's inputs are fixed (v) */
    double v[CLOCK_MAX_INPUTS];
} SampleClock;

void clock_start(SampleClock *clock, double ts);
/* Whether a state may restore clock (with n inputs): a period > 0, a valid position, finite latched inputs. */
int clock_valid(const SampleClock *clock, int n);
/* Take step (from grid_step, bounded) with the n inputs u held over it: commit(context, inputs) per
 * instant reached, the current sample with its latched inputs (or u while it is open), then u. */
void clock_take(SampleClock *clock, const GridStep *step, const double *u, int n,
                void (*commit)(void *context, const double *inputs), void *context);

/* The time since the start, summed from the steps (runtime/sample_clock.py's StepTime). */
typedef struct {
    double sum, compensation;
} StepTime;

void step_time_add(StepTime *time, double h);
double step_time_value(const StepTime *time);

#endif
