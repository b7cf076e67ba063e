/* The internals the parts of the C planner share (jerk_axis.c, jerk_sync.c, jerk_vibration.c,
 * jerk_planner.c): the types of the Python kernel's objects and the functions one part calls in
 * another, each named jpi_ + the function it repeats. Not an interface: jerk_planner.h is. */
#ifndef JERK_INTERNAL_H
#define JERK_INTERNAL_H

#include "jerk_planner.h"

#define MAXP JP_MAX_PHASES

typedef struct {
    int n;
    double d[MAXP], j[MAXP];
    double p[MAXP + 1], v[MAXP + 1], a[MAXP + 1], e[MAXP + 1];
} Ph;

typedef struct {
    double p0, v0, a0, pf, vf, af, pd;
    JpLimits lim;
    double tol_p, tol_v, tol_a, tol_t;
} Problem;

static inline double max2(double a, double b) { return a > b ? a : b; }
static inline double min2(double a, double b) { return a < b ? a : b; }

#define MAX_EXTREMAL 24

typedef struct {
    Ph fastest;
    int intervals;
    double left[2], right[2];
    Ph at_right[2];
} Block;

typedef struct {
    int axes;
    Problem problems[JP_MAX_AXES];
    Block blocks[JP_MAX_AXES];
} Rigid;

typedef struct { double t; int axis; } Candidate;

typedef struct { double re, im; } Cx;

typedef struct {
    const double *d, *j;
    int n;
    double T;
} History;

typedef struct { int m; int kind; double level; } Held;  /* kind 0 a, 1 v, 2 turn */
#define MAX_HELD 64
#define MAX_FREQ 64
#define MAX_EQ (4 + MAX_HELD + 2 * MAX_FREQ)

int jpi_accept(const Problem *pr, const double *durations, const double *jerks, int n, Ph *out);
double jpi_amplitude(const double *d, const double *j, int n, double T, double omega, double zeta, const History *ringing);
int jpi_band_count(const JpMode *m, double duration);
double jpi_band_frequency(const JpMode *m, double duration, int k, int count);
int jpi_block_of(const Problem *pr, Block *b, Ph *scratch /* MAX_EXTREMAL */);
int jpi_blocked(const Block *b, double t);
int jpi_cancel(const double *start, const double *target, const JpLimits *lim, double T, const JpMode *modes, int n_modes, const Ph *rigid, const History *ringing, const double *omegas, const double *zetas, int freqs, int doublets, const Held *pins, int n_pins, double *d_out, double *j_out, int *n_out);
int jpi_candidates(const Rigid *rg, Candidate *out);
int jpi_check_start_within(double *state, const JpLimits *lim, char *message, int size, int axis);
int jpi_convolve_jerk(const Ph *ph, const JpShaper *shaper, Ph *out);
int jpi_padded(const Ph *ph, double T, Ph *out);
double jpi_ph_duration(const Ph *ph);
void jpi_ph_extrema(const Ph *ph, double *v_low, double *v_high, double *a_low, double *a_high);
int jpi_ph_set(Ph *ph, double p0, double v0, double a0, const double *d, const double *j, int n);
void jpi_problem_set(Problem *pr, const double *state, const double *target, const JpLimits *lim);
int jpi_profiles_lasting(const Rigid *rg, double T, int owner, Ph *out);
int jpi_rigid_blocks(Rigid *rg, int axes, double (*states)[3], double (*targets)[3], const JpLimits *limits, Ph *scratch);
int jpi_straight_line(Rigid *rg, int axes, double (*states)[3], double (*targets)[3], const JpLimits *limits, double *T, Ph *out, Ph *scratch, char *message, int size);
double jpi_sum3(const double *t);
int jpi_synchronise(Rigid *rg, int axes, double (*states)[3], double (*targets)[3], const JpLimits *limits, double *T, Ph *out, Ph *scratch);
double jpi_t_min(const Block *b);
void jpi_velocity_change(double v0, double a0, double v1, double a1, double a_max, double a_min, double j_max, double *t, double *j);
int jpi_violation(const Ph *ph, const JpLimits *lim, Held *pin);
double jpi_worst_amplitude(const Ph *ph, double T, const JpMode *m, const History *ringing);
int jpi_cmp_double(const void *a, const void *b);

#endif
