/* The native EKF tuner (paper 001, Fig. 20) behind the generic FMI layers: the C twin of the
 * pythonfmu EKFTuner, runtime/ekf.py's ResonanceEKF and runtime/ekf_tuner.py's
 * EKFTunedShaperKernel, operation for operation, so that both give the same numbers.
 *
 * Each sample of the absolute grid t0 + k Ts (sample_clock.c) feeds the vibration to the 4-state
 * EKF of eqs. (15)-(26) (the OCR corrections are derived in runtime/ekf.py), and once its estimate
 * has converged designs a closed-form shaper (shaper_designs.c) for it, switched in when the
 * command has rested for as long as both shapers remember; the command passes through until then.
 * Every parameter is used at the exit of initialisation and every formula is closed-form, so all
 * of them may change before it, as in the pythonfmu FMU. Outputs change only in a step (no
 * feed-through).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "ekf_tuner_model.h"
#include "resonance_ekf.h"
#include "sample_clock.h"
#include "shaper_designs.h"

#define PI 3.14159265358979323846

/* A shaper's delay line (runtime/limits.py MAX_SAMPLED_LENGTH). */
#define MAX_LENGTH 1000000L
/* Impulses of one single-mode closed-form design: zv_dn of order n has n + 2, n <= 62. */
#define MAX_IMPULSES 64
#define MAX_ORDER 62


typedef struct {
    long long length, pos;  /* taps[0..length), line[0..2 length): u[k - d] = line[pos + d] */
    double *taps, *line;
} Streaming;

typedef struct {
    Ekf ekf;
    EkfHistory history;
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
    ModelInstance *inst;
} Tuner;

static Tuner *tuner_of(const ModelInstance *inst) { return (Tuner *)inst->model; }


static double real_of(const ModelInstance *inst, EkfMeaning meaning) { return inst->reals[tuner_of(inst)->vr[meaning]]; }

/* ---------------------------------------------------------------- the shaper (runtime/shaper_filter.py) */

static void streaming_free(ModelInstance *inst, Streaming *f) {
    model_release(inst, f->taps);
    model_release(inst, f->line);
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
    f->taps = model_allocate(t->inst, (size_t)longest, sizeof(double));
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
    f->line = model_allocate(t->inst, 2 * (size_t)length, sizeof(double));
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
    ekf_step(e, &t->history, measurement);
    if (!e->converged) return;
    const double omega = ekf_omega_n(e), zeta = e->x[3] / omega;  /* runtime/ekf.py's omega_n and zeta */
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

static void publish_estimates(ModelInstance *inst) {
    const Tuner *t = tuner_of(inst);
    const double natural = ekf_omega_n(&t->ekf);
    inst->reals[t->vr[EKF_OMEGA_EST]] = natural;
    inst->reals[t->vr[EKF_ZETA_EST]] = t->ekf.x[3] / natural;
    inst->reals[t->vr[EKF_CONVERGED]] = t->ekf.converged ? 1.0 : 0.0;
}

/* ---------------------------------------------------------------- the part's hooks: life cycle */

static void release_run(ModelInstance *inst) {
    Tuner *t = tuner_of(inst);
    streaming_free(inst, &t->active);
    streaming_free(inst, &t->pending);
    model_release(inst, t->history.recent);
    model_release(inst, t->history.queued);
    t->history.recent = NULL;
    t->history.queued = NULL;
    t->started = t->has_active = t->has_pending = t->has_design = t->has_last = 0;
}

static void reset(ModelInstance *inst) {
    release_run(inst);
    tuner_of(inst)->failure = NULL;
}

static int instantiate(ModelInstance *inst) {
    Tuner *t = model_allocate(inst, 1, sizeof(Tuner));
    if (t == NULL) return -1;
    memset(t, 0, sizeof *t);
    inst->model = t;
    t->inst = inst;
    twin_index(&ekf_tuner_model, t->vr, EKF_MEANINGS);
    return 0;
}

static void free_model(ModelInstance *inst) {
    Tuner *t = tuner_of(inst);
    if (t == NULL) return;
    release_run(inst);
    model_release(inst, t);
    inst->model = NULL;
}

static ModelStatus exit_initialization(ModelInstance *inst, const char *function) {
    Tuner *t = tuner_of(inst);
    const double ts = real_of(inst, EKF_PERIOD), omega0 = real_of(inst, EKF_OMEGA0);
    const double fs = 1.0 / ts;
    if (!(omega0 < PI * fs))
        return model_fail(inst, "%s: omega0 must be in (0, pi/Ts) = (0, %g) rad/s, got %g", function, PI * fs, omega0);
    const double window = nearbyint(2.0 * PI * fs / omega0);  /* Python's round: half to even */
    if (!(window <= (double)EKF_MAX_WINDOW))
        return model_fail(inst, "%s: one period of omega0 = %g rad/s spans %.0f samples of Ts = %g s, the EKF's "
                         "convergence window; at most %ld: raise Ts or omega0", function, omega0, window, ts, EKF_MAX_WINDOW);
    release_run(inst);
    t->kind = closed_form_kind(model_string(inst, t->vr[EKF_KIND]));
    t->order = inst->integers[t->vr[EKF_ORDER] - ekf_tuner_model.n_real];
    t->retune = real_of(inst, EKF_RETUNE);
    ekf_start(&t->ekf, fs, omega0, real_of(inst, EKF_AMPLITUDE), window < 2.0 ? 2 : (long long)window);
    t->h = 1.0 / t->ekf.fs;
    t->history.recent = model_allocate(inst, 2 * (size_t)t->ekf.window, sizeof(double));
    t->history.queued = model_allocate(inst, EKF_QUEUES * (size_t)t->ekf.window, sizeof(long long));
    if (t->history.recent == NULL || t->history.queued == NULL)
        return model_fail(inst, "%s: out of memory for a window of %lld samples", function, t->ekf.window);
    clock_start(&t->clock, ts);
    t->failure = NULL;
    t->started = 1;
    inst->reals[t->vr[EKF_OUTPUT]] = 0.0;
    publish_estimates(inst);
    return MODEL_OK;
}

static ModelStatus do_step(ModelInstance *inst, double t_now, double h, const char *function) {
    Tuner *t = tuner_of(inst);
    const double inputs[2] = {real_of(inst, EKF_COMMAND), real_of(inst, EKF_VIBRATION)};
    if (twin_clock_step(inst, &t->clock, t_now, h, inputs, 2, commit, t, function) != MODEL_OK) return MODEL_ERROR;
    if (t->failure != NULL) return model_fail(inst, "%s: at t = %g s: %s", function, t_now, t->failure);
    publish_estimates(inst);
    return MODEL_OK;
}

/* ---------------------------------------------------------------- the part's hooks: values */

static ModelStatus check_real(ModelInstance *inst, size_t vr, double value, const char *function) {
    const VariableRow *v = &ekf_tuner_model.rows[vr];
    switch (v->meaning) {
    case EKF_PERIOD: case EKF_OMEGA0: case EKF_AMPLITUDE: case EKF_RETUNE:
        return twin_range(inst, v->name, value, value > 0.0, "> 0", function);
    default: return twin_range(inst, v->name, value, 1, "finite", function);
    }
}

static ModelStatus check_integer(ModelInstance *inst, size_t vr, int value, const char *function) {
    const VariableRow *v = &ekf_tuner_model.rows[vr];
    if (v->meaning == EKF_ORDER && (value < 0 || value > MAX_ORDER))
        return model_fail(inst, "%s: %s must be an integer in [0, %d], got %d", function, v->name, MAX_ORDER, value);
    return MODEL_OK;
}

static ModelStatus check_string(ModelInstance *inst, size_t vr, const char *value, const char *function) {
    const VariableRow *v = &ekf_tuner_model.rows[vr];
    if (v->meaning == EKF_KIND && closed_form_kind(value) == KIND_NOT_CLOSED_FORM)
        return model_fail(inst, "%s: %s must be one of zv, zvd, zvdd, zv_dn, mzv, got %s", function, v->name, value);
    return MODEL_OK;
}

/* ---------------------------------------------------------------- the part's hooks: state
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

static size_t state_size(const ModelInstance *inst) {
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

static void save_state(const ModelInstance *inst, unsigned char *bytes) {
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
    memcpy(at, t->history.recent, 2 * (size_t)t->ekf.window * sizeof(double));
    at = put_streaming(&t->active, at + 2 * (size_t)t->ekf.window * sizeof(double));
    put_streaming(&t->pending, at);
}

/* A filter of length taps from the bytes at *at (advanced), or -1. */
static int take_streaming(Tuner *t, Streaming *f, long long length, long long pos, const unsigned char **at, const unsigned char *end) {
    streaming_free(t->inst, f);
    if (length == 0) return pos == 0 ? 0 : -1;
    if (length < 0 || length > MAX_LENGTH || pos < 0 || pos >= length || (size_t)(end - *at) < (size_t)length * 3 * sizeof(double))
        return -1;
    f->taps = model_allocate(t->inst, (size_t)length, sizeof(double));
    f->line = model_allocate(t->inst, 2 * (size_t)length, sizeof(double));
    if (f->taps == NULL || f->line == NULL) return -1;
    f->length = length, f->pos = pos;
    memcpy(f->taps, *at, (size_t)length * sizeof(double));
    memcpy(f->line, *at + (size_t)length * sizeof(double), 2 * (size_t)length * sizeof(double));
    *at += streaming_bytes(f);
    return 0;
}

static int restore_state(ModelInstance *inst, const unsigned char *bytes, size_t size, const char *function) {
    (void)function;
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
    if (!ekf_valid(&header.ekf) || header.kind < 0 || header.kind >= KIND_NOT_CLOSED_FORM || header.order < 0
        || header.order > MAX_ORDER || !clock_valid(&header.clock, 2) || !(header.h > 0.0))
        return -1;
    const unsigned char *at = bytes + sizeof header, *end = bytes + size;
    if ((size_t)(end - at) < 2 * (size_t)window * sizeof(double)) return -1;
    t->history.recent = model_allocate(inst, 2 * (size_t)window, sizeof(double));
    t->history.queued = model_allocate(inst, EKF_QUEUES * (size_t)window, sizeof(long long));
    if (t->history.recent == NULL || t->history.queued == NULL) {
        release_run(inst);
        return -1;
    }
    memcpy(t->history.recent, at, 2 * (size_t)window * sizeof(double));
    at += 2 * (size_t)window * sizeof(double);
    if (take_streaming(t, &t->active, header.active_length, header.active_pos, &at, end) != 0
        || take_streaming(t, &t->pending, header.pending_length, header.pending_pos, &at, end) != 0 || at != end
        || (header.has_active && t->active.length == 0) || (header.has_pending && t->pending.length == 0)) {
        release_run(inst);
        return -1;
    }
    t->ekf = header.ekf, t->clock = header.clock;
    ekf_rebuild_history(&t->ekf, &t->history);
    t->has_active = header.has_active, t->has_pending = header.has_pending, t->has_design = header.has_design;
    t->has_last = header.has_last, t->designs = header.designs, t->rest = header.rest;
    t->design_omega = header.design_omega, t->design_zeta = header.design_zeta, t->last_command = header.last_command;
    t->h = header.h, t->retune = header.retune;
    t->kind = (ClosedFormKind)header.kind, t->order = (int)header.order;
    t->failure = NULL;
    t->started = 1;
    return 0;
}

const ModelPart model_part = {
    .variables = &ekf_tuner_model, .instantiate = instantiate, .free = free_model, .reset = reset,
    .check_real = check_real, .check_integer = check_integer, .check_string = check_string,
    .exit_initialization = exit_initialization, .do_step = do_step,
    .state_size = state_size, .save_state = save_state, .restore_state = restore_state,
};
