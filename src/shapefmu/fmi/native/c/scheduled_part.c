/* The native ScheduledShaper (issue 37) behind the generic FMI layers: the C twin of the pythonfmu
 * ScheduledShaper, runtime/scheduled_shaper.py's ModeSchedule and ScheduledShaperKernel operation for
 * operation, its ModeFollowingShaper in mode_following.c, so that both give the same numbers bit for bit.
 *
 * The schedule maps the scheduling input to a mode (omega, zeta), linear between its rows; at each
 * sample of the absolute grid t0 + k Ts (sample_clock.c) the shaper for that mode shapes the command,
 * re-designed in closed form with no jump when the mode moved by more than the resolution
 * (mode_following.c, shared with the TrackedShaper). y feeds through from both inputs: the output if
 * the command holds plus the first tap of the design for the scheduling value set now times the
 * command's change (mf_output).
 *
 * Every parameter is used at the exit of initialisation and every design is closed-form, so all of
 * them may change before it, as in the pythonfmu FMU. A mode above the Nyquist frequency, a design
 * longer than MAX_SAMPLED_LENGTH samples, a scheduling value where the law gives no mode, or more
 * taps in flight than MF_MAX_TAPS_IN_FLIGHT are refused with a message and an error status.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mode_following.h"
#include "sample_clock.h"
#include "scheduled_model.h"

#define PI 3.14159265358979323846

typedef struct {
    /* the settings, read from the parameters at the exit of initialisation (and at a restore) */
    int rows, extrapolate, order;
    double values[SCHEDULED_MAX_ROWS], frequencies[SCHEDULED_MAX_ROWS], zetas[SCHEDULED_MAX_ROWS];
    ClosedFormKind kind;
    double fs, resolution;
    /* ScheduledShaperKernel: the scheduling value in force and its mode, and the shaper */
    double value, mode_omega, mode_zeta;
    ModeFollowing shaper;
    SampleClock clock;
    int started;
    const char *failure;    /* set by a sample that could not be taken: message, or shaper.failure */
    char message[320];
    size_t vr[SCHEDULED_MEANINGS];
    size_t value_vr[SCHEDULED_MAX_ROWS], frequency_vr[SCHEDULED_MAX_ROWS], damping_vr[SCHEDULED_MAX_ROWS];
    ModelInstance *inst;
} Scheduled;

static Scheduled *scheduled_of(const ModelInstance *inst) { return (Scheduled *)inst->model; }

static double real_of(const ModelInstance *inst, ScheduledMeaning meaning) {
    return inst->reals[scheduled_of(inst)->vr[meaning]];
}

static int integer_of(const ModelInstance *inst, ScheduledMeaning meaning) {
    return inst->integers[scheduled_of(inst)->vr[meaning] - scheduled_model.n_real];
}

/* Sets the failure message; returns -1. */
static int fail(Scheduled *s, const char *format, ...) {
    va_list args;
    va_start(args, format);
    vsnprintf(s->message, sizeof s->message, format, args);
    va_end(args);
    s->failure = s->message;
    return -1;
}

/* ---------------------------------------------------------------- the schedule (ModeSchedule) */

/* (omega rad/s, zeta) in force at scheduling value x: linear between rows, the end rows held unless
 * extrapolate; 0, or -1 (failure set) where the law gives f <= 0 or zeta outside [0, 1). */
static int schedule_mode(Scheduled *s, double value, double *omega, double *zeta) {
    const double *values = s->values, *f = s->frequencies, *z = s->zetas;
    const int rows = s->rows;
    if (rows == 1) {
        *omega = 2.0 * PI * f[0], *zeta = z[0];
        return 0;
    }
    double x = value;
    if (!s->extrapolate) {  /* Python's min(max(x, first), last): the first argument on a tie */
        x = values[0] > x ? values[0] : x;
        x = values[rows - 1] < x ? values[rows - 1] : x;
    }
    int i = 0;  /* bisect_right(values, x) - 1, kept in [0, rows - 2] */
    while (i < rows && values[i] <= x) i++;
    i = i - 1 < 0 ? 0 : i - 1 > rows - 2 ? rows - 2 : i - 1;
    const double t = (x - values[i]) / (values[i + 1] - values[i]);
    const double frequency = f[i] + t * (f[i + 1] - f[i]), damping = z[i] + t * (z[i + 1] - z[i]);
    if (!(frequency > 0.0 && 0.0 <= damping && damping < 1.0))
        return fail(s, "scheduling value %.17g lies where the schedule gives f = %g Hz, zeta = %g; the law holds only "
                    "where f > 0 and zeta is in [0, 1)", value, frequency, damping);
    *omega = 2.0 * PI * frequency, *zeta = damping;
    return 0;
}

/* What a sample of command u at scheduling value will give, without taking it (the kernels' output):
 * the output if the command holds plus the first tap of the design for the mode times the change. */
static int output(Scheduled *s, double u, double value, double *y) {
    double omega = s->mode_omega, zeta = s->mode_zeta;
    if (value != s->value && schedule_mode(s, value, &omega, &zeta) != 0) return -1;
    if (mf_output(&s->shaper, u, omega, zeta, y) != 0) {
        s->failure = s->shaper.failure;
        return -1;
    }
    return 0;
}

/* One sample: inputs[0] the command u, inputs[1] the scheduling value (ScheduledShaperKernel.step). */
static void commit(void *context, const double *inputs) {
    Scheduled *s = context;
    if (s->failure != NULL) return;
    if (inputs[1] != s->value) {
        if (schedule_mode(s, inputs[1], &s->mode_omega, &s->mode_zeta) != 0) return;
        s->value = inputs[1];
    }
    if (mf_step(&s->shaper, s->inst, inputs[0], s->mode_omega, s->mode_zeta, NULL) != 0) s->failure = s->shaper.failure;
}

/* ---------------------------------------------------------------- the part's hooks: life cycle */

/* Back to before initialisation: the run's buffers freed, no failure (also the reset hook). */
static void release_run(ModelInstance *inst) {
    Scheduled *s = scheduled_of(inst);
    mf_free(&s->shaper, inst);
    s->started = 0;
    s->failure = NULL;
}

/* The settings of the run from the parameters (checked when they were set, and at the build). */
static void read_settings(ModelInstance *inst) {
    Scheduled *s = scheduled_of(inst);
    s->rows = integer_of(inst, SCHEDULED_ROWS);
    for (int i = 0; i < s->rows; i++) {
        s->values[i] = inst->reals[s->value_vr[i]];
        s->frequencies[i] = inst->reals[s->frequency_vr[i]];
        s->zetas[i] = inst->reals[s->damping_vr[i]];
    }
    s->extrapolate = inst->booleans[s->vr[SCHEDULED_EXTRAPOLATE] - scheduled_model.n_real - scheduled_model.n_integer];
    s->kind = closed_form_kind(model_string(inst, s->vr[SCHEDULED_KIND]));
    s->order = integer_of(inst, SCHEDULED_ORDER);
    s->resolution = real_of(inst, SCHEDULED_RESOLUTION);
    s->fs = 1.0 / real_of(inst, SCHEDULED_PERIOD);
}

/* i - 1 of a variable named base[i] (f[2] -> 1). */
static int element(const char *name) {
    const char *bracket = strchr(name, '[');
    return bracket == NULL ? 0 : (int)strtol(bracket + 1, NULL, 10) - 1;
}

static int instantiate(ModelInstance *inst) {
    Scheduled *s = model_allocate(inst, 1, sizeof(Scheduled));
    if (s == NULL) return -1;
    memset(s, 0, sizeof *s);
    inst->model = s;
    s->inst = inst;
    twin_index(&scheduled_model, s->vr, SCHEDULED_MEANINGS);
    const VariableTable *table = &scheduled_model;
    const size_t n = table->n_real + table->n_integer + table->n_boolean + table->n_string;
    for (size_t vr = 0; vr < n; vr++) {
        const VariableRow *v = &scheduled_model.rows[vr];
        const int i = element(v->name);
        if (i < 0 || i >= SCHEDULED_MAX_ROWS) continue;
        if (v->meaning == SCHEDULED_VALUE) s->value_vr[i] = vr;
        if (v->meaning == SCHEDULED_FREQUENCY) s->frequency_vr[i] = vr;
        if (v->meaning == SCHEDULED_DAMPING) s->damping_vr[i] = vr;
    }
    return 0;
}

static void free_model(ModelInstance *inst) {
    Scheduled *s = scheduled_of(inst);
    if (s == NULL) return;
    release_run(inst);
    model_release(inst, s);
    inst->model = NULL;
}

static ModelStatus update(ModelInstance *inst, const char *function) {
    Scheduled *s = scheduled_of(inst);
    if (!s->started) return MODEL_OK;
    const double u = s->clock.latched ? s->clock.v[0] : real_of(inst, SCHEDULED_COMMAND);
    const double value = s->clock.latched ? s->clock.v[1] : real_of(inst, SCHEDULED_SCHEDULING);
    if (output(s, u, value, &inst->reals[s->vr[SCHEDULED_OUTPUT]]) != 0)
        return model_fail(inst, "%s: %s", function, s->failure);
    return MODEL_OK;
}

static ModelStatus exit_initialization(ModelInstance *inst, const char *function) {
    Scheduled *s = scheduled_of(inst);
    release_run(inst);
    read_settings(inst);
    for (int i = 1; i < s->rows; i++)
        if (!(s->values[i] > s->values[i - 1]))
            return model_fail(inst, "%s: values must be strictly increasing over the n_rows = %d rows used, got "
                             "values[%d] = %.17g after values[%d] = %.17g", function, s->rows, i + 1, s->values[i], i,
                             s->values[i - 1]);
    if (!isfinite(s->fs))
        return model_fail(inst, "%s: Ts must be > 0 with a finite sampling rate 1/Ts, got %g", function,
                         real_of(inst, SCHEDULED_PERIOD));
    s->value = real_of(inst, SCHEDULED_SCHEDULING);
    if (schedule_mode(s, s->value, &s->mode_omega, &s->mode_zeta) != 0)
        return model_fail(inst, "%s: %s", function, s->failure);
    if (mf_start(&s->shaper, inst, s->fs, s->mode_omega, s->mode_zeta, s->kind, s->order,
                 real_of(inst, SCHEDULED_REST), s->resolution) != 0) {
        const ModelStatus status = model_fail(inst, "%s: %s", function, s->shaper.failure);
        release_run(inst);
        return status;
    }
    clock_start(&s->clock, real_of(inst, SCHEDULED_PERIOD));
    s->started = 1;
    return update(inst, function);
}

static ModelStatus do_step(ModelInstance *inst, double t, double h, const char *function) {
    Scheduled *s = scheduled_of(inst);
    const double inputs[2] = {real_of(inst, SCHEDULED_COMMAND), real_of(inst, SCHEDULED_SCHEDULING)};
    if (twin_clock_step(inst, &s->clock, t, h, inputs, 2, commit, s, function) != MODEL_OK) return MODEL_ERROR;
    if (s->failure != NULL) return model_fail(inst, "%s: at t = %g s: %s", function, t, s->failure);
    return MODEL_OK;
}

/* ---------------------------------------------------------------- the part's hooks: values */

static ModelStatus check_real(ModelInstance *inst, size_t vr, double value, const char *function) {
    Scheduled *s = scheduled_of(inst);
    const VariableRow *v = &scheduled_model.rows[vr];
    switch (v->meaning) {
    case SCHEDULED_PERIOD: case SCHEDULED_FREQUENCY:
        return twin_range(inst, v->name, value, value > 0.0, "> 0", function);
    case SCHEDULED_DAMPING:
        return twin_range(inst, v->name, value, value >= 0.0 && value < 1.0, "in [0, 1)", function);
    case SCHEDULED_TOLERANCE:
        return twin_range(inst, v->name, value, value > 0.0 && value < 1.0, "in (0, 1)", function);
    case SCHEDULED_RESOLUTION: return twin_range(inst, v->name, value, value >= 0.0, ">= 0", function);
    case SCHEDULED_SCHEDULING: {
        /* the value the output is computed for at once (an open sample) must give a mode and a design */
        if (twin_range(inst, v->name, value, 1, "finite", function) != MODEL_OK) return MODEL_ERROR;
        if (!s->started || s->clock.latched || value == s->value) return MODEL_OK;
        double y;
        if (output(s, s->shaper.last, value, &y) == 0) return MODEL_OK;
        const char *why = s->failure;
        s->failure = NULL;  /* a value refused when set leaves the run as it was */
        return model_fail(inst, "%s: %s", function, why);
    }
    default: return twin_range(inst, v->name, value, 1, "finite", function);
    }
}

static ModelStatus check_integer(ModelInstance *inst, size_t vr, int value, const char *function) {
    const VariableRow *v = &scheduled_model.rows[vr];
    if (v->meaning == SCHEDULED_ORDER && (value < 0 || value > MF_MAX_ORDER))
        return model_fail(inst, "%s: %s must be an integer in [0, %d] in the native ScheduledShaper, got %d", function,
                         v->name, MF_MAX_ORDER, value);
    if (v->meaning == SCHEDULED_ROWS && (value < 1 || value > SCHEDULED_MAX_ROWS))
        return model_fail(inst, "%s: %s must be in [1, %d], got %d", function, v->name, SCHEDULED_MAX_ROWS, value);
    return MODEL_OK;
}

static ModelStatus check_string(ModelInstance *inst, size_t vr, const char *value, const char *function) {
    const VariableRow *v = &scheduled_model.rows[vr];
    if (v->meaning == SCHEDULED_KIND && closed_form_kind(value) == KIND_NOT_CLOSED_FORM)
        return model_fail(inst, "%s: %s must be one of zv, zvd, zvdd, zv_dn, mzv (the kinds the native ScheduledShaper "
                         "re-designs in C), got %s", function, v->name, value);
    return MODEL_OK;
}

/* ---------------------------------------------------------------- the part's hooks: state
 * Bytes: a fixed header (the kernel's scalars and the clock), then the shaper (mode_following.c).
 * The settings are the parameters', read again at a restore. */

typedef struct {
    long long magic, started;
    double value, mode_omega, mode_zeta;
    SampleClock clock;
} StateHeader;

#define STATE_MAGIC 0x5343484544ULL /* "SCHED" */

static size_t state_size(const ModelInstance *inst) {
    const Scheduled *s = scheduled_of(inst);
    return sizeof(StateHeader) + (s->started ? mf_bytes(&s->shaper) : 0);
}

static void save_state(const ModelInstance *inst, unsigned char *bytes) {
    const Scheduled *s = scheduled_of(inst);
    StateHeader header;
    memset(&header, 0, sizeof header);
    header.magic = (long long)STATE_MAGIC, header.started = s->started;
    if (s->started) {
        header.value = s->value, header.mode_omega = s->mode_omega, header.mode_zeta = s->mode_zeta;
        header.clock = s->clock;
    }
    memcpy(bytes, &header, sizeof header);
    if (s->started) mf_save(&s->shaper, bytes + sizeof header);
}

static int restore_state(ModelInstance *inst, const unsigned char *bytes, size_t size, const char *function) {
    (void)function;
    Scheduled *s = scheduled_of(inst);
    StateHeader h;
    if (size < sizeof h) return -1;
    memcpy(&h, bytes, sizeof h);
    if (h.magic != (long long)STATE_MAGIC || (h.started != 0 && h.started != 1)) return -1;
    release_run(inst);
    if (!h.started) return size == sizeof h ? 0 : -1;
    read_settings(inst);
    if (!isfinite(h.value) || !(h.mode_omega > 0.0 && isfinite(h.mode_omega)) || !(h.mode_zeta >= 0.0 && h.mode_zeta < 1.0)
        || !clock_valid(&h.clock, 2) || h.clock.ts != real_of(inst, SCHEDULED_PERIOD))
        return -1;
    const unsigned char *at = bytes + sizeof h;
    s->shaper.kind = s->kind, s->shaper.order = s->order, s->shaper.resolution = s->resolution;
    s->shaper.fs = s->fs, s->shaper.h = 1.0 / s->fs;
    if (mf_restore(&s->shaper, inst, &at, bytes + size) != 0 || at != bytes + size) {
        release_run(inst);
        return -1;
    }
    s->value = h.value, s->mode_omega = h.mode_omega, s->mode_zeta = h.mode_zeta, s->clock = h.clock;
    s->started = 1;
    return 0;
}

const ModelPart model_part = {
    .variables = &scheduled_model, .instantiate = instantiate, .free = free_model, .reset = release_run,
    .check_real = check_real, .check_integer = check_integer, .check_string = check_string, .update = update,
    .exit_initialization = exit_initialization, .do_step = do_step,
    .state_size = state_size, .save_state = save_state, .restore_state = restore_state,
};
