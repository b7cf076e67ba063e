/* The native EKF tuner (paper 001, Fig. 20) behind the generic FMI 2.0 layer: the C twin of the
 * pythonfmu EKFTuner, runtime/ekf.py's ResonanceEKF and runtime/ekf_tuner.py's
 * EKFTunedShaperKernel, operation for operation, so that both give the same numbers.
 *
 * Each sample of the absolute grid t0 + k Ts (sample_clock.c) feeds the vibration to the 4-state
 * EKF of eqs. (15)-(26) (the OCR corrections are derived in runtime/ekf.py), and once its estimate
 * has converged designs a closed-form shaper (shaper_designs.c) for it, switched in when the
 * command has rested for as long as both shapers remember; the command passes through until then.
 * Every parameter is used at the exit of initialisation and every formula is closed-form, so all
 * of them may change before it, as in the pythonfmu FMU. Outputs change only in fmi2DoStep (no
 * feed-through).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "ekf_tuner_model.h"
#include "sample_clock.h"
#include "shaper_designs.h"

#define PI 3.14159265358979323846
/* runtime/ekf.py's default_tuning and ResonanceEKF defaults */
#define P0_OMEGA 0.25
#define P0_SIGMA 0.1
#define Q_PHASOR 1e-3
#define Q_OMEGA_PER_PERIOD 1e-4
#define Q_SIGMA_PER_PERIOD 1e-5
#define R_AMPLITUDE 0.1
#define OMEGA_TOL 2e-3
#define SIGMA_TOL 5e-3
#define NIS_LIMIT 9.0
/* The convergence window is one period of omega0 in samples; its history is allocated. */
#define MAX_WINDOW 1000000L
/* A shaper's delay line (runtime/limits.py MAX_SAMPLED_LENGTH). */
#define MAX_LENGTH 1000000L
/* Impulses of one single-mode closed-form design: zv_dn of order n has n + 2, n <= 62. */
#define MAX_IMPULSES 64
#define MAX_ORDER 62

typedef struct {
    double x[4], P[4][4];
    double p0[4], q[4], r, omega_tol, sigma_tol, nis_limit, nis, fs, dt, good[4];
    long long window, count, slot;  /* the last `count` <= window estimates, the next one goes to slot */
    long long samples, missing, resets, reacquisitions, reset_last, converged;
} Ekf;

/* A queue of window slots in a circular buffer of `window` entries. */
typedef struct {
    long long size, front;
} Queue;

enum { HIGH_OMEGA, LOW_OMEGA, HIGH_SIGMA, LOW_SIGMA, QUEUES };

typedef struct {
    long long length, pos;  /* taps[0..length), line[0..2 length): u[k - d] = line[pos + d] */
    double *taps, *line;
} Streaming;

typedef struct {
    Ekf ekf;
    /* The window of estimates (omega, sigma), a ring (recent[2 slot], recent[2 slot + 1]), and for
     * each extreme a monotonic queue of the slots, oldest first, that may still be it:
     * runtime/ekf.py scans its deque for max - min every sample, these give the same values in
     * O(1) per sample. */
    double *recent;          /* 2 * window */
    long long *queued;       /* QUEUES * window */
    Queue queue[QUEUES];
    Streaming active, pending;
    /* the tuner's scalars (saved as they are in an FMU state) */
    long long started, has_active, has_pending, has_design, has_last, designs, rest;
    double design_omega, design_zeta, last_command, h, retune;
    SampleClock clock;
    /* build and per-run settings */
    ClosedFormKind kind;
    int order;
    const char *failure;     /* set by a sample that could not be taken */
    double times[MAX_IMPULSES], amplitudes[MAX_IMPULSES], scratch[2 * MAX_IMPULSES];
    size_t vr[EKF_MEANINGS];
    Fmi2Instance *inst;
} Tuner;

static Tuner *tuner_of(const Fmi2Instance *inst) { return (Tuner *)inst->model; }

static size_t n_variables(void) {
    return ekf_tuner_model.n_real + ekf_tuner_model.n_integer + ekf_tuner_model.n_boolean + ekf_tuner_model.n_string;
}

static double real_of(const Fmi2Instance *inst, EkfMeaning meaning) { return inst->reals[tuner_of(inst)->vr[meaning]]; }

/* ---------------------------------------------------------------- the EKF (runtime/ekf.py) */

static void diagonal(double P[4][4], const double *variances) {
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) P[i][j] = i == j ? variances[i] : 0.0;
}

static void ekf_start(Ekf *e, double fs, double omega0, double amplitude, long long window) {
    memset(e, 0, sizeof *e);
    e->fs = fs;
    const double samples_per_period = 2.0 * PI * fs / omega0;
    const double q_omega = pow(Q_OMEGA_PER_PERIOD * omega0, 2) / samples_per_period;
    const double q_sigma = pow(Q_SIGMA_PER_PERIOD * omega0, 2) / samples_per_period;
    const double p0[4] = {pow(amplitude, 2), pow(amplitude, 2), pow(P0_OMEGA * omega0, 2), pow(P0_SIGMA * omega0, 2)};
    const double q[4] = {pow(Q_PHASOR * amplitude, 2), pow(Q_PHASOR * amplitude, 2), q_omega, q_sigma};
    memcpy(e->p0, p0, sizeof p0);
    memcpy(e->q, q, sizeof q);
    e->r = pow(R_AMPLITUDE * amplitude, 2);
    e->omega_tol = OMEGA_TOL, e->sigma_tol = SIGMA_TOL, e->nis_limit = NIS_LIMIT;
    e->window = window;
    e->nis = 1.0;
    e->dt = 1.0 / fs;
    e->x[0] = 0.0, e->x[1] = 0.0, e->x[2] = omega0, e->x[3] = 0.0;
    diagonal(e->P, e->p0);
    memcpy(e->good, e->x, sizeof e->x);
}

/* Eqs. (15)-(16): the state through eq. (24), P- = F P F^T + Q (phase 0: H = [1, 0, 0, 0]). */
static void ekf_predict(Ekf *e) {
    const double x1 = e->x[0], x2 = e->x[1], omega = e->x[2], sigma = e->x[3], dt = e->dt;
    const double decay = exp(-sigma * dt);
    const double c = decay * cos(omega * dt), s = decay * sin(omega * dt);
    const double f1 = c * x1 + s * x2, f2 = -s * x1 + c * x2;
    const double F1[4] = {c, s, dt * f2, -dt * f1}, F2[4] = {-s, c, -dt * f1, -dt * f2};
    double (*P)[4] = e->P, A1[4], A2[4];
    for (int j = 0; j < 4; j++) {
        A1[j] = F1[0] * P[0][j] + F1[1] * P[1][j] + F1[2] * P[2][j] + F1[3] * P[3][j];
        A2[j] = F2[0] * P[0][j] + F2[1] * P[1][j] + F2[2] * P[2][j] + F2[3] * P[3][j];
    }
    const double *q = e->q;
    const double p11 = A1[0] * F1[0] + A1[1] * F1[1] + A1[2] * F1[2] + A1[3] * F1[3] + q[0];
    const double p12 = A1[0] * F2[0] + A1[1] * F2[1] + A1[2] * F2[2] + A1[3] * F2[3];
    const double p22 = A2[0] * F2[0] + A2[1] * F2[1] + A2[2] * F2[2] + A2[3] * F2[3] + q[1];
    const double p13 = A1[2], p14 = A1[3], p23 = A2[2], p24 = A2[3];
    const double p33 = P[2][2] + q[2], p34 = P[2][3], p44 = P[3][3] + q[3];
    e->x[0] = f1, e->x[1] = f2;
    const double next[4][4] = {{p11, p12, p13, p14}, {p12, p22, p23, p24}, {p13, p23, p33, p34}, {p14, p24, p34, p44}};
    memcpy(e->P, next, sizeof next);
}

/* Eqs. (17)-(19) for z = x1 + n, P = P- - K S K^T. */
static void ekf_update(Ekf *e, double z) {
    double (*P)[4] = e->P, pht[4], K[4];
    const double h1 = 1.0, h2 = 0.0;  /* cos(0), sin(0): the reference phase 0 */
    for (int i = 0; i < 4; i++) pht[i] = h1 * P[i][0] + h2 * P[i][1];
    const double innovation_var = h1 * pht[0] + h2 * pht[1] + e->r;
    for (int i = 0; i < 4; i++) K[i] = pht[i] / innovation_var;
    const double innovation = z - (h1 * e->x[0] + h2 * e->x[1]);
    for (int i = 0; i < 4; i++) e->x[i] = e->x[i] + K[i] * innovation;
    e->nis += (innovation * innovation / innovation_var - e->nis) / (double)e->window;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) P[i][j] = P[i][j] - pht[i] * K[j];
}

static int ekf_healthy(const Ekf *e) {
    for (int i = 0; i < 4; i++) {
        if (!isfinite(e->x[i])) return 0;
        for (int j = 0; j < 4; j++)
            if (!isfinite(e->P[i][j])) return 0;
    }
    for (int i = 0; i < 4; i++)
        if (e->P[i][i] < 0.0) return 0;
    return 0.0 < e->x[2] && e->x[2] < PI * e->fs;
}

static double omega_n(const Ekf *e) { return hypot(e->x[2], e->x[3]); }
static double zeta_of(const Ekf *e) { return e->x[3] / hypot(e->x[2], e->x[3]); }

static double estimate(const Tuner *t, long long slot, int which) {
    return t->recent[2 * slot + (which >= HIGH_SIGMA)];
}

static void window_clear(Tuner *t) {
    t->ekf.count = 0;
    memset(t->queue, 0, sizeof t->queue);
}

static long long wrapped(long long i, long long w) { return i >= w ? i - w : i; }

/* Append the estimate (omega, sigma) at the next slot; in a full window it replaces the oldest,
 * which leaves every queue it is still at the front of. */
static void window_push(Tuner *t, double omega, double sigma) {
    Ekf *e = &t->ekf;
    const long long w = e->window, slot = e->slot;
    const int full = e->count == w;
    t->recent[2 * slot] = omega;
    t->recent[2 * slot + 1] = sigma;
    for (int k = 0; k < QUEUES; k++) {
        Queue *queue = &t->queue[k];
        long long *at = t->queued + k * w;
        if (full && queue->size > 0 && at[queue->front] == slot) queue->front = wrapped(queue->front + 1, w), queue->size--;
        const double value = k < HIGH_SIGMA ? omega : sigma;
        const int high = k == HIGH_OMEGA || k == HIGH_SIGMA;
        while (queue->size > 0) {
            const double back = estimate(t, at[wrapped(queue->front + queue->size - 1, w)], k);
            if (high ? back <= value : back >= value) queue->size--;
            else break;
        }
        at[wrapped(queue->front + queue->size, w)] = slot;
        queue->size++;
    }
    e->slot = wrapped(slot + 1, w);
    if (!full) e->count++;
}

static double extreme(const Tuner *t, int which) {
    return estimate(t, t->queued[which * t->ekf.window + t->queue[which].front], which);
}

/* Covariance of omega and sigma small and both estimates stable over the last window. */
static int ekf_converged(const Tuner *t) {
    const Ekf *e = &t->ekf;
    const double omega = e->x[2];
    const double omega_std = sqrt(e->P[2][2] > 0.0 ? e->P[2][2] : 0.0);
    const double sigma_std = sqrt(e->P[3][3] > 0.0 ? e->P[3][3] : 0.0);
    if (omega_std > e->omega_tol * omega || sigma_std > e->sigma_tol * omega) return 0;
    if (e->count < e->window) return 0;
    return extreme(t, HIGH_OMEGA) - extreme(t, LOW_OMEGA) <= e->omega_tol * omega
           && extreme(t, HIGH_SIGMA) - extreme(t, LOW_SIGMA) <= e->sigma_tol * omega;
}

static void ekf_step(Tuner *t, double z) {
    Ekf *e = &t->ekf;
    e->samples++;
    ekf_predict(e);
    if (isfinite(z)) ekf_update(e, z);
    else e->missing++;
    e->reset_last = !ekf_healthy(e);
    if (e->reset_last) {
        e->resets++;
        memcpy(e->x, e->good, sizeof e->x);
        diagonal(e->P, e->p0);
        window_clear(t);
    } else {
        if (e->nis > e->nis_limit) {
            e->reacquisitions++;
            diagonal(e->P, e->p0);
            e->nis = 1.0;
            window_clear(t);
        }
        memcpy(e->good, e->x, sizeof e->x);
        window_push(t, e->x[2], e->x[3]);
    }
    e->converged = ekf_converged(t);
}

/* ---------------------------------------------------------------- the shaper (runtime/shaper_filter.py) */

static void streaming_free(Fmi2Instance *inst, Streaming *f) {
    fmi2_release(inst, f->taps);
    fmi2_release(inst, f->line);
    memset(f, 0, sizeof *f);
}

/* StreamingShaper.from_impulses: the impulses split onto the grid k h (grid_impulses), the delay
 * line as long as the last non-zero tap; 0, or -1 (t->failure set) if it cannot be held. */
static int streaming_design(Tuner *t, Streaming *f, int count) {
    long longest = 0;
    for (int i = 0; i < count; i++) {
        const double x = floor(t->times[i] / t->h) + 2.0;
        if (!(x <= (double)MAX_LENGTH + 1.0)) {
            t->failure = "the shaper designed for the estimate spans more than 1000000 samples of Ts (shapefmu."
                         "runtime.limits.MAX_SAMPLED_LENGTH); use a longer Ts";
            return -1;
        }
        if ((long)x > longest) longest = (long)x;
    }
    streaming_free(t->inst, f);
    f->taps = fmi2_allocate(t->inst, (size_t)longest, sizeof(double));
    if (f->taps == NULL) {
        t->failure = "out of memory for the shaper's taps";
        return -1;
    }
    memset(f->taps, 0, (size_t)longest * sizeof(double));
    for (int i = 0; i < count; i++) {
        long k;
        const double alpha = grid_split(t->times[i], t->h, &k);
        f->taps[k] += (1.0 - alpha) * t->amplitudes[i];
        if (alpha != 0.0) f->taps[k + 1] += alpha * t->amplitudes[i];
    }
    long length = longest;
    while (length > 1 && f->taps[length - 1] == 0.0) length--;
    f->length = length;
    f->line = fmi2_allocate(t->inst, 2 * (size_t)length, sizeof(double));
    if (f->line == NULL) {
        t->failure = "out of memory for the shaper's delay line";
        return -1;
    }
    return 0;
}

static void streaming_reset(Streaming *f, double u0) {
    for (long long j = 0; j < 2 * f->length; j++) f->line[j] = u0;
    f->pos = 0;
}

static double streaming_step(Streaming *f, double u) {
    const long long length = f->length;
    f->pos = f->pos ? f->pos - 1 : length - 1;
    double *history = f->line + f->pos;
    history[0] = history[length] = u;
    double y = 0.0;
    for (long long d = 0; d < length; d++)
        if (f->taps[d] != 0.0) y += f->taps[d] * history[d];
    return y;
}

/* ---------------------------------------------------------------- the tuner (runtime/ekf_tuner.py) */

static void observe(Tuner *t, double measurement) {
    Ekf *e = &t->ekf;
    ekf_step(t, measurement);
    if (!e->converged) return;
    const double omega = omega_n(e), zeta = zeta_of(e);
    if (!(0.0 <= zeta && zeta < 1.0)) return;  /* a growing or over-damped "mode" is no design point */
    if (t->has_design) {
        const double by_omega = fabs(omega - t->design_omega) / t->design_omega, by_zeta = fabs(zeta - t->design_zeta);
        const double moved = by_zeta > by_omega ? by_zeta : by_omega;
        if (moved <= t->retune) return;
    }
    const int count = design_closed_form(t->kind, t->order, 1, &omega, &zeta, t->times, t->amplitudes,
                                         MAX_IMPULSES, t->scratch);
    if (count < 0 || streaming_design(t, &t->pending, count) != 0) {
        if (t->failure == NULL) t->failure = "the shaper's design failed";
        return;
    }
    t->design_omega = omega, t->design_zeta = zeta;
    t->has_design = 1, t->has_pending = 1;
    t->designs++;
}

static double shape(Tuner *t, double command) {
    if (t->has_last && command == t->last_command) {
        t->rest++;
    } else {
        t->has_last = 1, t->last_command = command, t->rest = 1;
    }
    if (t->has_pending) {
        const long long old = t->has_active ? t->active.length : 1, wanted = old > t->pending.length ? old : t->pending.length;
        if (t->rest >= wanted) {
            streaming_reset(&t->pending, command);
            const Streaming swap = t->active;
            t->active = t->pending, t->pending = swap;
            streaming_free(t->inst, &t->pending);
            t->has_active = 1, t->has_pending = 0;
        }
    }
    return t->has_active ? streaming_step(&t->active, command) : command;
}

/* One sample: inputs[0] the command u, inputs[1] the vibration. */
static void commit(void *context, const double *inputs) {
    Tuner *t = context;
    if (t->failure != NULL) return;
    observe(t, inputs[1]);
    t->inst->reals[t->vr[EKF_OUTPUT]] = shape(t, inputs[0]);
}

static void publish_estimates(Fmi2Instance *inst) {
    const Tuner *t = tuner_of(inst);
    const double natural = omega_n(&t->ekf);  /* hypot once: zeta_of's is the same value */
    inst->reals[t->vr[EKF_OMEGA_EST]] = natural;
    inst->reals[t->vr[EKF_ZETA_EST]] = t->ekf.x[3] / natural;
    inst->reals[t->vr[EKF_CONVERGED]] = t->ekf.converged ? 1.0 : 0.0;
}

/* ---------------------------------------------------------------- FMI hooks: life cycle */

void model_describe(Fmi2ModelInfo *info) {
    memset(info, 0, sizeof *info);
    info->guid = ekf_tuner_model.guid;
    info->n_real = ekf_tuner_model.n_real;
    info->n_integer = ekf_tuner_model.n_integer;
    info->n_boolean = ekf_tuner_model.n_boolean;
    info->n_string = ekf_tuner_model.n_string;
}

Fmi2Role model_variable(const Fmi2Instance *inst, Fmi2Type type, size_t vr, const char **name) {
    (void)inst, (void)type;
    if (vr >= n_variables()) return FMI2_NO_VARIABLE;
    *name = ekf_tuner_model.variables[vr].name;
    return ekf_tuner_model.variables[vr].role;
}

static void release_run(Fmi2Instance *inst) {
    Tuner *t = tuner_of(inst);
    streaming_free(inst, &t->active);
    streaming_free(inst, &t->pending);
    fmi2_release(inst, t->recent);
    fmi2_release(inst, t->queued);
    t->recent = NULL;
    t->queued = NULL;
    t->started = t->has_active = t->has_pending = t->has_design = t->has_last = 0;
}

void model_reset(Fmi2Instance *inst) {
    const size_t n_real = ekf_tuner_model.n_real, n_integer = ekf_tuner_model.n_integer;
    for (size_t vr = 0; vr < n_variables(); vr++) {
        const EkfVariable *v = &ekf_tuner_model.variables[vr];
        if (vr < n_real) inst->reals[vr] = v->start;
        else if (vr < n_real + n_integer) inst->integers[vr - n_real] = (int)v->start;
        else if (vr < n_real + n_integer + ekf_tuner_model.n_boolean) inst->booleans[vr - n_real - n_integer] = v->start != 0.0;
        else snprintf(fmi2_string(inst, vr), FMI2_STRING_CAPACITY + 1, "%s", v->string_start);
    }
    release_run(inst);
    tuner_of(inst)->failure = NULL;
}

int model_instantiate(Fmi2Instance *inst) {
    Tuner *t = fmi2_allocate(inst, 1, sizeof(Tuner));
    if (t == NULL) return -1;
    memset(t, 0, sizeof *t);
    inst->model = t;
    t->inst = inst;
    for (size_t vr = 0; vr < n_variables(); vr++) t->vr[ekf_tuner_model.variables[vr].meaning] = vr;
    model_reset(inst);
    return 0;
}

void model_free(Fmi2Instance *inst) {
    Tuner *t = tuner_of(inst);
    if (t == NULL) return;
    release_run(inst);
    fmi2_release(inst, t);
    inst->model = NULL;
}

fmi2Status model_exit_initialization(Fmi2Instance *inst) {
    static const char *const function = "fmi2ExitInitializationMode";
    Tuner *t = tuner_of(inst);
    const double ts = real_of(inst, EKF_PERIOD), omega0 = real_of(inst, EKF_OMEGA0);
    const double fs = 1.0 / ts;
    if (!(omega0 < PI * fs))
        return fmi2_fail(inst, "%s: omega0 must be in (0, pi/Ts) = (0, %g) rad/s, got %g", function, PI * fs, omega0);
    const double window = nearbyint(2.0 * PI * fs / omega0);  /* Python's round: half to even */
    if (!(window <= (double)MAX_WINDOW))
        return fmi2_fail(inst, "%s: one period of omega0 = %g rad/s spans %.0f samples of Ts = %g s, the EKF's "
                         "convergence window; at most %ld: raise Ts or omega0", function, omega0, window, ts, MAX_WINDOW);
    release_run(inst);
    t->kind = closed_form_kind(fmi2_string(inst, t->vr[EKF_KIND]));
    t->order = inst->integers[t->vr[EKF_ORDER] - ekf_tuner_model.n_real];
    t->retune = real_of(inst, EKF_RETUNE);
    ekf_start(&t->ekf, fs, omega0, real_of(inst, EKF_AMPLITUDE), window < 2.0 ? 2 : (long long)window);
    t->h = 1.0 / t->ekf.fs;
    t->recent = fmi2_allocate(inst, 2 * (size_t)t->ekf.window, sizeof(double));
    t->queued = fmi2_allocate(inst, QUEUES * (size_t)t->ekf.window, sizeof(long long));
    if (t->recent == NULL || t->queued == NULL)
        return fmi2_fail(inst, "%s: out of memory for a window of %lld samples", function, t->ekf.window);
    window_clear(t);
    clock_start(&t->clock, inst->start_time, ts);
    t->failure = NULL;
    t->started = 1;
    inst->reals[t->vr[EKF_OUTPUT]] = 0.0;
    publish_estimates(inst);
    return fmi2OK;
}

fmi2Status model_update(Fmi2Instance *inst, const char *function) {
    (void)inst, (void)function;
    return fmi2OK; /* outputs change only in fmi2DoStep */
}

fmi2Status model_do_step(Fmi2Instance *inst, double t_now, double h) {
    Tuner *t = tuner_of(inst);
    const double reached = clock_reached(&t->clock, t_now + h), samples = reached - (double)t->clock.k;
    if (samples > (double)MAX_SAMPLES_PER_STEP)
        return fmi2_fail(inst, "fmi2DoStep: communication step h = %g s spans %.0f samples of Ts = %g s; at most %lld "
                         "per step", h, samples, t->clock.ts, MAX_SAMPLES_PER_STEP);
    const double inputs[2] = {real_of(inst, EKF_COMMAND), real_of(inst, EKF_VIBRATION)};
    clock_step_to(&t->clock, t_now + h, reached, inputs, 2, commit, t);
    if (t->failure != NULL) return fmi2_fail(inst, "fmi2DoStep: at t = %g s: %s", t_now, t->failure);
    publish_estimates(inst);
    return fmi2OK;
}

/* ---------------------------------------------------------------- FMI hooks: values */

static fmi2Status range(Fmi2Instance *inst, const char *name, double value, int ok, const char *valid,
                        const char *function) {
    if (ok && isfinite(value)) return fmi2OK;
    return fmi2_fail(inst, "%s: %s must be %s, got %g", function, name, valid, value);
}

fmi2Status model_check_real(Fmi2Instance *inst, size_t vr, double value, const char *function) {
    const EkfVariable *v = &ekf_tuner_model.variables[vr];
    switch (v->meaning) {
    case EKF_PERIOD: case EKF_OMEGA0: case EKF_AMPLITUDE: case EKF_RETUNE:
        return range(inst, v->name, value, value > 0.0, "> 0", function);
    default: return range(inst, v->name, value, 1, "finite", function);
    }
}

fmi2Status model_check_integer(Fmi2Instance *inst, size_t vr, int value, const char *function) {
    const EkfVariable *v = &ekf_tuner_model.variables[vr];
    if (v->meaning == EKF_ORDER && (value < 0 || value > MAX_ORDER))
        return fmi2_fail(inst, "%s: %s must be an integer in [0, %d], got %d", function, v->name, MAX_ORDER, value);
    return fmi2OK;
}

fmi2Status model_check_string(Fmi2Instance *inst, size_t vr, const char *value, const char *function) {
    const EkfVariable *v = &ekf_tuner_model.variables[vr];
    if (v->meaning == EKF_KIND && closed_form_kind(value) == KIND_NOT_CLOSED_FORM)
        return fmi2_fail(inst, "%s: %s must be one of zv, zvd, zvdd, zv_dn, mzv, got %s", function, v->name, value);
    return fmi2OK;
}

void model_changed(Fmi2Instance *inst, size_t vr) { (void)inst, (void)vr; }
void model_states_changed(Fmi2Instance *inst) { (void)inst; }

fmi2Status model_partial_derivative(Fmi2Instance *inst, size_t unknown, size_t known, double *entry,
                                    const char *function) {
    (void)unknown, (void)known, (void)entry;
    return fmi2_fail(inst, "%s: this FMU provides no directional derivatives", function);
}

/* ---------------------------------------------------------------- FMI hooks: state
 * Bytes: the Tuner's scalars, the EKF and the clock (a fixed header), then the window's history
 * and each filter's taps and delay line, whose lengths are in the header. */

typedef struct {
    long long magic, started, has_active, has_pending, has_design, has_last, designs, rest;
    double design_omega, design_zeta, last_command, h, retune;
    long long active_length, active_pos, pending_length, pending_pos;
    long long kind, order;
    Ekf ekf;
    SampleClock clock;
} StateHeader;

#define STATE_MAGIC 0x454b46545552ULL /* "EKFTUR" */

static size_t streaming_bytes(const Streaming *f) { return (size_t)f->length * 3 * sizeof(double); }

size_t model_state_size(const Fmi2Instance *inst) {
    const Tuner *t = tuner_of(inst);
    if (!t->started) return sizeof(StateHeader);
    return sizeof(StateHeader) + 2 * (size_t)t->ekf.window * sizeof(double) + streaming_bytes(&t->active)
           + streaming_bytes(&t->pending);
}

static unsigned char *put_streaming(const Streaming *f, unsigned char *at) {
    memcpy(at, f->taps, (size_t)f->length * sizeof(double));
    memcpy(at + (size_t)f->length * sizeof(double), f->line, 2 * (size_t)f->length * sizeof(double));
    return at + streaming_bytes(f);
}

void model_save_state(const Fmi2Instance *inst, unsigned char *bytes) {
    const Tuner *t = tuner_of(inst);
    StateHeader header;
    memset(&header, 0, sizeof header);
    header.magic = (long long)STATE_MAGIC, header.started = t->started;
    header.has_active = t->has_active, header.has_pending = t->has_pending, header.has_design = t->has_design;
    header.has_last = t->has_last, header.designs = t->designs, header.rest = t->rest;
    header.design_omega = t->design_omega, header.design_zeta = t->design_zeta, header.last_command = t->last_command;
    header.h = t->h, header.retune = t->retune;
    header.active_length = t->active.length, header.active_pos = t->active.pos;
    header.pending_length = t->pending.length, header.pending_pos = t->pending.pos;
    header.kind = t->kind, header.order = t->order;
    header.ekf = t->ekf, header.clock = t->clock;
    memcpy(bytes, &header, sizeof header);
    if (!t->started) return;
    unsigned char *at = bytes + sizeof header;
    memcpy(at, t->recent, 2 * (size_t)t->ekf.window * sizeof(double));
    at = put_streaming(&t->active, at + 2 * (size_t)t->ekf.window * sizeof(double));
    put_streaming(&t->pending, at);
}

/* A filter of length taps from the bytes at *at (advanced), or -1. */
static int take_streaming(Tuner *t, Streaming *f, long long length, long long pos, const unsigned char **at, const unsigned char *end) {
    streaming_free(t->inst, f);
    if (length == 0) return pos == 0 ? 0 : -1;
    if (length < 0 || length > MAX_LENGTH || pos < 0 || pos >= length || (size_t)(end - *at) < (size_t)length * 3 * sizeof(double))
        return -1;
    f->taps = fmi2_allocate(t->inst, (size_t)length, sizeof(double));
    f->line = fmi2_allocate(t->inst, 2 * (size_t)length, sizeof(double));
    if (f->taps == NULL || f->line == NULL) return -1;
    f->length = length, f->pos = pos;
    memcpy(f->taps, *at, (size_t)length * sizeof(double));
    memcpy(f->line, *at + (size_t)length * sizeof(double), 2 * (size_t)length * sizeof(double));
    *at += streaming_bytes(f);
    return 0;
}

int model_restore_state(Fmi2Instance *inst, const unsigned char *bytes, size_t size) {
    Tuner *t = tuner_of(inst);
    StateHeader header;
    if (size < sizeof header) return -1;
    memcpy(&header, bytes, sizeof header);
    const int flags_ok = (header.started | header.has_active | header.has_pending | header.has_design | header.has_last) <= 1
                         && header.started >= 0 && header.has_active >= 0 && header.has_pending >= 0
                         && header.has_design >= 0 && header.has_last >= 0;
    if (header.magic != (long long)STATE_MAGIC || !flags_ok) return -1;
    release_run(inst);
    if (!header.started) return size == sizeof header ? 0 : -1;
    const long long window = header.ekf.window;
    if (window < 2 || window > MAX_WINDOW || header.ekf.count < 0 || header.ekf.count > window
        || header.ekf.slot < 0 || header.ekf.slot >= window || (header.ekf.converged != 0 && header.ekf.converged != 1) || header.kind < 0 || header.kind >= KIND_NOT_CLOSED_FORM || header.order < 0
        || header.order > MAX_ORDER || !(header.clock.ts > 0.0) || !(header.h > 0.0))
        return -1;
    const unsigned char *at = bytes + sizeof header, *end = bytes + size;
    if ((size_t)(end - at) < 2 * (size_t)window * sizeof(double)) return -1;
    t->recent = fmi2_allocate(inst, 2 * (size_t)window, sizeof(double));
    t->queued = fmi2_allocate(inst, QUEUES * (size_t)window, sizeof(long long));
    if (t->recent == NULL || t->queued == NULL) {
        release_run(inst);
        return -1;
    }
    memcpy(t->recent, at, 2 * (size_t)window * sizeof(double));
    at += 2 * (size_t)window * sizeof(double);
    if (take_streaming(t, &t->active, header.active_length, header.active_pos, &at, end) != 0
        || take_streaming(t, &t->pending, header.pending_length, header.pending_pos, &at, end) != 0 || at != end
        || (header.has_active && t->active.length == 0) || (header.has_pending && t->pending.length == 0)) {
        release_run(inst);
        return -1;
    }
    t->ekf = header.ekf, t->clock = header.clock;
    /* the queues from the window's estimates, pushed again oldest first */
    const long long count = t->ekf.count;
    window_clear(t);
    t->ekf.slot = wrapped(t->ekf.slot + window - count, window);
    for (long long j = 0; j < count; j++) {
        const long long slot = t->ekf.slot;
        window_push(t, t->recent[2 * slot], t->recent[2 * slot + 1]);
    }
    t->has_active = header.has_active, t->has_pending = header.has_pending, t->has_design = header.has_design;
    t->has_last = header.has_last, t->designs = header.designs, t->rest = header.rest;
    t->design_omega = header.design_omega, t->design_zeta = header.design_zeta, t->last_command = header.last_command;
    t->h = header.h, t->retune = header.retune;
    t->kind = (ClosedFormKind)header.kind, t->order = (int)header.order;
    t->failure = NULL;
    t->started = 1;
    return 0;
}
