/* The native TrackedShaper behind the generic FMI layers: the C twin of the pythonfmu TrackedShaper
 * (fmi/kinds/tracked_shaper.py), runtime/tracked_shaper.py's TrackedShaperKernel operation for
 * operation, so that both give the same numbers.
 *
 * Each sample of the absolute grid t0 + k Ts (sample_clock.c) refers the measurement to the
 * equilibrium the last shaped command set (gain * (y - rest)), feeds it to the EKF of paper 001
 * (resonance_ekf.c, with the tracking tuning below), restarted at each new ring; takes the estimate
 * the convergence tests pass within the plausible band (keep the last good design otherwise); and
 * shapes the command with a closed-form shaper for the mode in force, re-designed with no jump
 * (mode_following.c). runtime/tracked_shaper.py's module docstring derives each rule. The FMU
 * always has a gain, so the kernel's "watch only at rest" branch (gain None) is not here.
 *
 * Feed-through: y, f and zeta at a sample depend on both inputs there. As the pythonfmu FMU does,
 * the outputs are those of the current sample run on a copy of the kernel (the probe), which the
 * step then takes for real. The probe shares the EKF's window with the kernel (its step is
 * journalled and taken back: resonance_ekf.c's ekf_take_back) and copies the shaper's ring of past
 * commands (half a period of the mode, in samples), only when the outputs are read after an input
 * changed or a step was taken: once per step for a host that sets, reads and steps.
 * Every parameter is used at the exit of initialisation, so each may be set before it.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "mode_following.h"
#include "resonance_ekf.h"
#include "sample_clock.h"
#include "tracked_shaper_model.h"

#define PI 3.14159265358979323846
/* runtime/tracked_shaper.py's tracking tuning: the phasor's random walk per sample (fraction of the
 * ring amplitude) and the decay rate's walk (fraction of the frequency's). */
#define Q_PHASOR 1e-4
#define SIGMA_DRIFT 0.3

/* TrackedShaperKernel: plain data but for the EKF's window and the shaper's buffers. */
typedef struct {
    Ekf ekf;
    EkfHistory history;
    ModeFollowing shaper;
    double band[2], zeta_max, gain, rest, mode[2], output;
    long long changed, watching;
} Kernel;

typedef struct {
    Kernel kernel, probe;
    long long started, dirty, failed;  /* dirty: an input changed or a step was taken since the probe */
    SampleClock clock;
    size_t vr[TRACK_MEANINGS];
    ModelInstance *inst;
} Tracked;

static Tracked *tracked_of(const ModelInstance *inst) { return (Tracked *)inst->model; }

static double real_of(const ModelInstance *inst, TrackedMeaning meaning) {
    return inst->reals[tracked_of(inst)->vr[meaning]];
}

/* ---------------------------------------------------------------- the kernel (runtime/tracked_shaper.py) */

/* TrackedShaperKernel.observe, with a gain. */
static void observe(Kernel *k, double measurement) {
    Ekf *e = &k->ekf;
    if (!k->watching || k->changed) {
        ekf_restart_phasor(e);  /* a new ring began with the last sample's command */
        k->watching = 1;
    }
    if (!ekf_step(e, &k->history, measurement - k->gain * (k->output - k->rest))) return;
    const double natural = ekf_omega_n(e);
    if (!(k->band[0] <= natural && natural <= k->band[1])) return;  /* a ring of another mode */
    const double zeta = e->x[3] / natural;
    if (e->omega_converged) k->mode[0] = natural;
    if (e->sigma_converged && 0.0 <= zeta && zeta <= k->zeta_max) k->mode[1] = zeta;
}

/* TrackedShaperKernel.step: 0 and *y, or -1 (k->shaper.failure says why). */
static int kernel_step(Kernel *k, ModelInstance *inst, double command, double measurement, double *y) {
    observe(k, measurement);
    if (mf_step(&k->shaper, inst, command, k->mode[0], k->mode[1], y) != 0) return -1;
    k->changed = *y != k->output;
    k->output = *y;
    return 0;
}

static void kernel_free(Kernel *k, ModelInstance *inst) {
    mf_free(&k->shaper, inst);
    model_release(inst, k->history.recent);
    model_release(inst, k->history.queued);
    k->history.recent = NULL;
    k->history.queued = NULL;
}

static int history_allocate(Kernel *k, ModelInstance *inst) {
    k->history.recent = model_allocate(inst, 2 * (size_t)k->ekf.window, sizeof(double));
    k->history.queued = model_allocate(inst, EKF_QUEUES * (size_t)k->ekf.window, sizeof(long long));
    return k->history.recent != NULL && k->history.queued != NULL ? 0 : -1;
}

/* The probe becomes the kernel but for the EKF's window, which it shares: a step of the probe is
 * journalled there (history.journal) and taken back (probe_end). 0, or -1 out of memory. */
static int probe_start(Kernel *probe, const Kernel *k, ModelInstance *inst, EkfJournal *journal) {
    const ModeFollowing shaper = probe->shaper;
    memcpy(probe, k, sizeof *probe);
    memcpy(&probe->shaper, &shaper, sizeof shaper);
    probe->history.journal = journal;
    return mf_copy(&probe->shaper, &k->shaper, inst);
}

/* The kernel's window as it was before the probe's step, and the probe holding none of it. */
static void probe_end(Kernel *probe, const Kernel *k) {
    ekf_take_back(&probe->ekf, &probe->history, &k->ekf);
    probe->history.recent = NULL;
    probe->history.queued = NULL;
    probe->history.journal = NULL;
}

/* ---------------------------------------------------------------- samples and outputs */

/* One sample: inputs[0] the command u, inputs[1] the measurement. */
static void commit(void *context, const double *inputs) {
    Tracked *t = context;
    double y;
    if (!t->failed && kernel_step(&t->kernel, t->inst, inputs[0], inputs[1], &y) != 0) t->failed = 1;
}

/* The outputs of the current sample (its latched inputs, or the inputs while it is open), run on
 * the probe (fmi/kinds/tracked_shaper.py's _show). */
static ModelStatus preview(ModelInstance *inst, const char *function) {
    Tracked *t = tracked_of(inst);
    const double open[2] = {real_of(inst, TRACK_COMMAND), real_of(inst, TRACK_MEASUREMENT)};
    const double *inputs = t->clock.latched ? t->clock.v : open;
    double y;
    EkfJournal journal = {0};
    const int copied = probe_start(&t->probe, &t->kernel, inst, &journal) == 0;
    const int failed = !copied || kernel_step(&t->probe, inst, inputs[0], inputs[1], &y) != 0;
    probe_end(&t->probe, &t->kernel);
    if (!copied) return model_fail(inst, "%s: out of memory for a copy of the shaper", function);
    if (failed) return model_fail(inst, "%s: %s", function, t->probe.shaper.failure);
    inst->reals[t->vr[TRACK_OUTPUT]] = y;
    inst->reals[t->vr[TRACK_FREQUENCY]] = t->probe.mode[0] / (2.0 * PI);
    inst->reals[t->vr[TRACK_DAMPING]] = t->probe.mode[1];
    t->dirty = 0;
    return MODEL_OK;
}

static ModelStatus update(ModelInstance *inst, const char *function) {
    Tracked *t = tracked_of(inst);
    return t->started && t->dirty ? preview(inst, function) : MODEL_OK;
}

static ModelStatus do_step(ModelInstance *inst, double t_now, double h, const char *function) {
    Tracked *t = tracked_of(inst);
    const double inputs[2] = {real_of(inst, TRACK_COMMAND), real_of(inst, TRACK_MEASUREMENT)};
    if (twin_clock_step(inst, &t->clock, t_now, h, inputs, 2, commit, t, function) != MODEL_OK) return MODEL_ERROR;
    if (t->failed) return model_fail(inst, "%s: at t = %g s: %s", function, t_now, t->kernel.shaper.failure);
    t->dirty = 1;  /* the outputs of the sample now current, made when they are read (update) */
    return MODEL_OK;
}

/* ---------------------------------------------------------------- life cycle */

static void release_run(ModelInstance *inst) {
    Tracked *t = tracked_of(inst);
    kernel_free(&t->kernel, inst);
    kernel_free(&t->probe, inst);
    t->started = t->dirty = t->failed = 0;
}

static int instantiate(ModelInstance *inst) {
    Tracked *t = model_allocate(inst, 1, sizeof(Tracked));
    if (t == NULL) return -1;
    memset(t, 0, sizeof *t);
    inst->model = t;
    t->inst = inst;
    twin_index(&tracked_shaper_model, t->vr, TRACK_MEANINGS);
    return 0;
}

static void free_model(ModelInstance *inst) {
    Tracked *t = tracked_of(inst);
    if (t == NULL) return;
    release_run(inst);
    model_release(inst, t);
    inst->model = NULL;
}

/* runtime/tracked_shaper.py's tracking_tuning: p0, q of (x1, x2, omega, sigma) and r. */
static void tracking_tuning(double fs, double omega0, double amplitude, double noise, double drift, double p0[4],
                            double q[4], double *r) {
    const double samples_per_period = 2.0 * PI * fs / omega0;
    p0[0] = p0[1] = pow(amplitude, 2);
    p0[2] = pow(EKF_P0_OMEGA * omega0, 2), p0[3] = pow(EKF_P0_SIGMA * omega0, 2);
    q[0] = q[1] = pow(Q_PHASOR * amplitude, 2);
    q[2] = pow(drift * omega0, 2) / samples_per_period;
    q[3] = pow(SIGMA_DRIFT * drift * omega0, 2) / samples_per_period;
    *r = pow(noise, 2);
}

static ModelStatus exit_initialization(ModelInstance *inst, const char *function) {
    Tracked *t = tracked_of(inst);
    Kernel *k = &t->kernel;
    release_run(inst);
    const double ts = real_of(inst, TRACK_PERIOD), fs = 1.0 / ts, omega0 = 2.0 * PI * real_of(inst, TRACK_F0);
    const double zeta0 = real_of(inst, TRACK_ZETA0), u0 = real_of(inst, TRACK_REST_COMMAND);
    const ClosedFormKind kind = closed_form_kind(model_string(inst, t->vr[TRACK_KIND]));
    const int order = inst->integers[t->vr[TRACK_ORDER] - tracked_shaper_model.n_real];
    if (mf_start(&k->shaper, inst, fs, omega0, zeta0, kind, order, u0, real_of(inst, TRACK_RESOLUTION)) != 0) {
        const ModelStatus status = model_fail(inst, "%s: %s", function, k->shaper.failure);
        release_run(inst);
        return status;
    }
    /* The EKF starts at the guess's damped frequency and decay rate (TrackedShaperKernel.__init__). */
    const double omega_d = omega0 * sqrt(1.0 - zeta0 * zeta0);
    if (!(omega_d < PI * fs)) {
        release_run(inst);
        return model_fail(inst, "%s: the guess's damped frequency must be in (0, pi/Ts) = (0, %g) rad/s, got %g "
                          "(f0 = %g Hz, zeta0 = %g)", function, PI * fs, omega_d, real_of(inst, TRACK_F0), zeta0);
    }
    const double window = nearbyint(2.0 * PI * fs / omega_d);  /* Python's round: half to even */
    if (!(window <= (double)EKF_MAX_WINDOW)) {
        release_run(inst);
        return model_fail(inst, "%s: one period of f0 = %g Hz spans %.0f samples of Ts = %g s, the EKF's convergence "
                          "window; at most %ld: raise Ts or f0", function, real_of(inst, TRACK_F0), window, ts,
                          EKF_MAX_WINDOW);
    }
    double p0[4], q[4], r;
    tracking_tuning(fs, omega0, real_of(inst, TRACK_AMPLITUDE), real_of(inst, TRACK_NOISE), real_of(inst, TRACK_DRIFT),
                    p0, q, &r);
    ekf_start_tuned(&k->ekf, fs, omega_d, zeta0 * omega0, p0, q, r, real_of(inst, TRACK_OMEGA_TOL),
                    real_of(inst, TRACK_SIGMA_TOL), window < 2.0 ? 2 : (long long)window);
    if (history_allocate(k, inst) != 0) {
        release_run(inst);
        return model_fail(inst, "%s: out of memory for a window of %.0f samples", function, window);
    }
    k->band[0] = real_of(inst, TRACK_BAND_LOW) * omega0, k->band[1] = real_of(inst, TRACK_BAND_HIGH) * omega0;
    k->zeta_max = real_of(inst, TRACK_ZETA_MAX);
    k->gain = real_of(inst, TRACK_GAIN), k->rest = real_of(inst, TRACK_REST);
    k->mode[0] = omega0, k->mode[1] = zeta0;
    k->output = u0, k->changed = 0, k->watching = 0;
    clock_start(&t->clock, ts);
    t->started = 1;
    return preview(inst, function);
}

/* ---------------------------------------------------------------- values */

static ModelStatus check_real(ModelInstance *inst, size_t vr, double value, const char *function) {
    const VariableRow *v = &tracked_shaper_model.rows[vr];
    const char *valid = NULL;
    switch (v->meaning) {
    case TRACK_F0: case TRACK_NOISE: case TRACK_AMPLITUDE: case TRACK_DRIFT: case TRACK_OMEGA_TOL:
    case TRACK_SIGMA_TOL: case TRACK_PERIOD:
        valid = value > 0.0 ? NULL : "> 0";
        break;
    case TRACK_ZETA0: case TRACK_ZETA_MAX: valid = value >= 0.0 && value < 1.0 ? NULL : "in [0, 1)"; break;
    case TRACK_VTOL: valid = value > 0.0 && value < 1.0 ? NULL : "in (0, 1)"; break;
    case TRACK_BAND_LOW: valid = value > 0.0 && value < 1.0 ? NULL : "in (0, 1)"; break;
    case TRACK_BAND_HIGH: valid = value > 1.0 ? NULL : "> 1"; break;
    case TRACK_RESOLUTION: valid = value >= 0.0 ? NULL : ">= 0"; break;
    default: break;
    }
    return twin_range(inst, v->name, value, valid == NULL, valid == NULL ? "finite" : valid, function);
}

static ModelStatus check_integer(ModelInstance *inst, size_t vr, int value, const char *function) {
    const VariableRow *v = &tracked_shaper_model.rows[vr];
    if (v->meaning == TRACK_ORDER && (value < 0 || value > MF_MAX_ORDER))
        return model_fail(inst, "%s: %s must be an integer in [0, %d], got %d", function, v->name, MF_MAX_ORDER, value);
    return MODEL_OK;
}

static ModelStatus check_string(ModelInstance *inst, size_t vr, const char *value, const char *function) {
    const VariableRow *v = &tracked_shaper_model.rows[vr];
    if (v->meaning == TRACK_KIND && closed_form_kind(value) == KIND_NOT_CLOSED_FORM)
        return model_fail(inst, "%s: %s must be one of zv, zvd, zvdd, zv_dn, mzv (the kinds this FMU designs in C), "
                          "got %s", function, v->name, value);
    return MODEL_OK;
}

static void changed(ModelInstance *inst, size_t vr) {
    const int meaning = tracked_shaper_model.rows[vr].meaning;
    if (meaning == TRACK_COMMAND || meaning == TRACK_MEASUREMENT) tracked_of(inst)->dirty = 1;
}

/* ---------------------------------------------------------------- state
 * Bytes: the kernel's plain data and the clock (a fixed header), then the EKF window's history and
 * the shaper (mode_following.c). The probe is not saved: it is made again from the kernel. */

typedef struct {
    long long magic, started, dirty, changed, watching, kind, order;
    double band[2], zeta_max, gain, rest, mode[2], output, fs, h, resolution;
    Ekf ekf;
    SampleClock clock;
} StateHeader;

#define STATE_MAGIC 0x545241434b4544ULL /* "TRACKED" */

static size_t state_size(const ModelInstance *inst) {
    const Tracked *t = tracked_of(inst);
    if (!t->started) return sizeof(StateHeader);
    return sizeof(StateHeader) + 2 * (size_t)t->kernel.ekf.window * sizeof(double) + mf_bytes(&t->kernel.shaper);
}

static void save_state(const ModelInstance *inst, unsigned char *bytes) {
    const Tracked *t = tracked_of(inst);
    const Kernel *k = &t->kernel;
    StateHeader header;
    memset(&header, 0, sizeof header);
    header.magic = (long long)STATE_MAGIC, header.started = t->started, header.dirty = t->dirty;
    header.changed = k->changed, header.watching = k->watching;
    header.kind = k->shaper.kind, header.order = k->shaper.order;
    memcpy(header.band, k->band, sizeof header.band);
    header.zeta_max = k->zeta_max, header.gain = k->gain, header.rest = k->rest, header.output = k->output;
    memcpy(header.mode, k->mode, sizeof header.mode);
    header.fs = k->shaper.fs, header.h = k->shaper.h, header.resolution = k->shaper.resolution;
    header.ekf = k->ekf, header.clock = t->clock;
    memcpy(bytes, &header, sizeof header);
    if (!t->started) return;
    memcpy(bytes + sizeof header, k->history.recent, 2 * (size_t)k->ekf.window * sizeof(double));
    mf_save(&k->shaper, bytes + sizeof header + 2 * (size_t)k->ekf.window * sizeof(double));
}

static int flag(long long value) { return value == 0 || value == 1; }

/* What a run reaches: flags, a build kind and order, a sample period, a band around a mode, finite numbers. */
static int header_valid(const StateHeader *s) {
    return s->magic == (long long)STATE_MAGIC && flag(s->started) && flag(s->dirty) && flag(s->changed)
           && flag(s->watching) && s->kind >= 0 && s->kind < KIND_NOT_CLOSED_FORM && s->order >= 0
           && s->order <= MF_MAX_ORDER && s->fs > 0.0 && isfinite(s->fs) && s->h > 0.0 && isfinite(s->h)
           && s->resolution >= 0.0 && isfinite(s->resolution) && s->band[0] > 0.0 && s->band[0] < s->band[1]
           && isfinite(s->band[1]) && s->zeta_max >= 0.0 && s->zeta_max < 1.0 && isfinite(s->gain)
           && isfinite(s->rest) && isfinite(s->output) && s->mode[0] > 0.0 && isfinite(s->mode[0])
           && s->mode[1] >= 0.0 && s->mode[1] < 1.0 && ekf_valid(&s->ekf) && clock_valid(&s->clock, 2);
}

static int restore_state(ModelInstance *inst, const unsigned char *bytes, size_t size, const char *function) {
    (void)function;
    Tracked *t = tracked_of(inst);
    Kernel *k = &t->kernel;
    StateHeader header;
    if (size < sizeof header) return -1;
    memcpy(&header, bytes, sizeof header);
    if (header.magic != (long long)STATE_MAGIC || !flag(header.started)) return -1;
    release_run(inst);
    if (!header.started) return size == sizeof header ? 0 : -1;
    if (!header_valid(&header)) return -1;
    const unsigned char *at = bytes + sizeof header, *end = bytes + size;
    const size_t history = 2 * (size_t)header.ekf.window * sizeof(double);
    k->ekf = header.ekf;
    if ((size_t)(end - at) < history || history_allocate(k, inst) != 0) {
        release_run(inst);
        return -1;
    }
    memcpy(k->history.recent, at, history);
    at += history;
    for (long long j = 0; j < 2 * header.ekf.window; j++)
        if (!isfinite(k->history.recent[j])) at = NULL;
    k->shaper.kind = (ClosedFormKind)header.kind, k->shaper.order = (int)header.order;
    k->shaper.fs = header.fs, k->shaper.h = header.h, k->shaper.resolution = header.resolution;
    if (at == NULL || mf_restore(&k->shaper, inst, &at, end) != 0 || at != end) {
        release_run(inst);
        return -1;
    }
    ekf_rebuild_history(&k->ekf, &k->history);
    memcpy(k->band, header.band, sizeof k->band);
    k->zeta_max = header.zeta_max, k->gain = header.gain, k->rest = header.rest, k->output = header.output;
    memcpy(k->mode, header.mode, sizeof k->mode);
    k->changed = header.changed, k->watching = header.watching;
    t->clock = header.clock;
    t->dirty = header.dirty;
    t->started = 1;
    return 0;
}

const ModelPart model_part = {
    .variables = &tracked_shaper_model, .instantiate = instantiate, .free = free_model, .reset = release_run,
    .check_real = check_real, .check_integer = check_integer, .check_string = check_string, .changed = changed,
    .update = update, .exit_initialization = exit_initialization, .do_step = do_step,
    .state_size = state_size, .save_state = save_state, .restore_state = restore_state,
};
