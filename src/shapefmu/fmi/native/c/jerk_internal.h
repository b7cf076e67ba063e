/* The internals the parts of the C planner share (jerk_axis.c, jerk_sync.c, jerk_vibration.c,
 * jerk_planner.c): the types of the Python kernel's objects and the functions one part calls in
 * another, each named jpi_ + the function it repeats. Not an interface: jerk_planner.h is. */
#ifndef JERK_INTERNAL_H
#define JERK_INTERNAL_H

#include "jerk_types.h"

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
#define SAMPLES 24       /* hold levels and velocities tried by the second step (jerk_sync.c) */
#define MAX_POINTS 128

/* The buffers of jerk_planner.h's JpWorkspace, one per use (each was a function's static before the
 * twin was made reentrant): the functions that need one take the workspace. */
struct JpWorkspace {
    Ph extremal[MAX_EXTREMAL];                       /* jpi_block_of's candidates */
    Rigid rigid_blocks;                              /* jp_rigid_duration */
    double table[2 * SAMPLES - 1][MAX_POINTS];       /* jerk_sync.c meeting_profile */
    Ph first, second, refined, meeting;              /* jerk_sync.c with_hold, profile_of_duration */
    double cuts[(MAXP + 1) * JP_MAX_IMPULSES];       /* jerk_vibration.c jpi_convolve_jerk */
    Ph equations_phases;                             /* jerk_vibration.c equations */
    Cx steps[MAXP + 1];
    double M[MAX_EQ * MAX_EQ], L[MAX_EQ * MAX_EQ];   /* jerk_vibration.c least_norm_step */
    double x[MAXP], jerks[MAXP], trial[MAXP], dx[MAXP], F[MAX_EQ], F_trial[MAX_EQ];  /* jpi_cancel */
    double C[MAXP * MAX_EQ], C_trial[MAXP * MAX_EQ];
    Held held[MAX_HELD];
    Ph fixed_point[JP_MAX_AXES];                     /* jerk_planner.c shaped_fixed_point */
    double cancelled_d[MAXP], cancelled_j[MAXP];     /* jerk_planner.c cancelled */
    Ph lasting[JP_MAX_AXES];                         /* jerk_planner.c attempt */
    Ph rigid[JP_MAX_AXES], ceiling_phases[JP_MAX_AXES], best[JP_MAX_AXES], found[JP_MAX_AXES];  /* plan */
};

int jpi_accept(const Problem *pr, const double *durations, const double *jerks, int n, Ph *out);
double jpi_amplitude(const double *d, const double *j, int n, double T, double omega, double zeta, const History *ringing);
int jpi_band_count(const JpMode *m, double duration);
double jpi_band_frequency(const JpMode *m, double duration, int k, int count);
int jpi_block_of(const Problem *pr, Block *b, Ph *scratch /* MAX_EXTREMAL */);
int jpi_blocked(const Block *b, double t);
int jpi_cancel(const double *start, const double *target, const JpLimits *lim, double T, const JpMode *modes, int n_modes, const Ph *rigid, const History *ringing, const double *omegas, const double *zetas, int freqs, int doublets, const Held *pins, int n_pins, double *d_out, double *j_out, int *n_out, JpWorkspace *ws);
int jpi_candidates(const Rigid *rg, Candidate *out);
int jpi_check_start_within(double *state, const JpLimits *lim, char *message, int size, int axis);
int jpi_convolve_jerk(const Ph *ph, const JpShaper *shaper, Ph *out, JpWorkspace *ws);
int jpi_padded(const Ph *ph, double T, Ph *out);
double jpi_ph_duration(const Ph *ph);
void jpi_ph_extrema(const Ph *ph, double *v_low, double *v_high, double *a_low, double *a_high);
int jpi_ph_set(Ph *ph, double p0, double v0, double a0, const double *d, const double *j, int n);
void jpi_problem_set(Problem *pr, const double *state, const double *target, const JpLimits *lim);
int jpi_profiles_lasting(const Rigid *rg, double T, int owner, Ph *out, JpWorkspace *ws);
int jpi_rigid_blocks(Rigid *rg, int axes, double (*states)[3], double (*targets)[3], const JpLimits *limits, JpWorkspace *ws);
int jpi_straight_line(Rigid *rg, int axes, double (*states)[3], double (*targets)[3], const JpLimits *limits, double *T, Ph *out, JpWorkspace *ws, char *message, int size);
double jpi_sum3(const double *t);
int jpi_synchronise(Rigid *rg, int axes, double (*states)[3], double (*targets)[3], const JpLimits *limits, double *T, Ph *out, JpWorkspace *ws);
double jpi_t_min(const Block *b);
void jpi_velocity_change(double v0, double a0, double v1, double a1, double a_max, double a_min, double j_max, double *t, double *j);
int jpi_violation(const Ph *ph, const JpLimits *lim, Held *pin);
double jpi_worst_amplitude(const Ph *ph, double T, const JpMode *m, const History *ringing);
int jpi_cmp_double(const void *a, const void *b);

#endif
