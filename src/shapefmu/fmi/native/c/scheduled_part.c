/* The native ScheduledShaper (issue 37) behind the generic FMI layers: the C twin of the pythonfmu
 * ScheduledShaper, runtime/scheduled_shaper.py's ModeSchedule, ModeFollowingShaper and
 * ScheduledShaperKernel, operation for operation, so that both give the same numbers bit for bit.
 *
 * The schedule maps the scheduling input to a mode (omega, zeta), linear between its rows; at each
 * sample of the absolute grid t0 + k Ts (sample_clock.c) the shaper is re-designed in closed form
 * (shaper_designs.c) when the mode moved by more than the resolution. Every change of the command is
 * shaped by the design in force when it was commanded (runtime/scheduled_shaper.py derives why: a
 * re-design then moves nothing by itself, and a move ends with the shaper it began with): the changes
 * made under one design form a segment, and
 *
 *     y[k] = c_1 + sum over the segments m in flight, over their taps (d, w) with k - d >= a_m,
 *            of w (u[min(k - d, b_m)] - c_m),
 *
 * a_m, b_m the first and last sample of segment m, c_m the command before it; a segment whose last
 * change has passed its last tap is folded into the base c_1. y feeds through from both inputs: the
 * output if the command holds plus the first tap of the design for the scheduling value set now
 * times the command's change (ModeFollowingShaper.output).
 *
 * Every parameter is used at the exit of initialisation and every design is closed-form, so all of
 * them may change before it, as in the pythonfmu FMU. A mode above the Nyquist frequency, a design
 * longer than MAX_SAMPLED_LENGTH samples, a scheduling value where the law gives no mode, or more
 * taps in flight than MAX_TAPS_IN_FLIGHT are refused with a message and an error status.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sample_clock.h"
#include "scheduled_model.h"
#include "shaper_designs.h"

#define PI 3.14159265358979323846
/* Impulses of one single-mode closed-form design: zv_dn of order n has n + 2, n <= 62; each impulse
 * split onto the grid gives at most two taps. */
#define MAX_ORDER 62
#define MAX_IMPULSES 64
#define MAX_TAPS (2 * MAX_IMPULSES)
/* runtime/limits.py MAX_SAMPLED_LENGTH: the samples one design spans (its last time / Ts + 2). */
#define MAX_SAMPLED_LENGTH 1000000.0
/* The ring of past commands holds the longest design in flight: a power of two >= MAX_SAMPLED_LENGTH. */
#define MAX_RING (1LL << 20)
/* Taps summed per sample over the designs in flight (16 bytes each): a new design at every sample of a
 * moving command keeps a segment per sample in flight, as many as the longest design spans. */
#define MAX_TAPS_IN_FLIGHT 1000000LL

typedef struct {
    long long delay;
    double weight;
} Tap;

/* The changes of the command made under one design (runtime/scheduled_shaper.py CommandSegment). */
typedef struct {
    Tap *taps;
    long long n_taps;
    long long start, end;   /* first sample, and last one once closed */
    long long open;         /* 1 while its design is in force (Python's end is None) */
    long long moved;        /* the command has changed since the segment began */
    long long reach;        /* the longest delay + 1 */
    double base, end_value; /* the command before the segment, and at its end */
} Segment;

typedef struct {
    /* the settings, read from the parameters at the exit of initialisation (and at a restore) */
    int rows, extrapolate, order;
    double values[SCHEDULED_MAX_ROWS], frequencies[SCHEDULED_MAX_ROWS], zetas[SCHEDULED_MAX_ROWS];
    ClosedFormKind kind;
    double fs, h, resolution;
    /* ScheduledShaperKernel: the scheduling value in force and its mode */
    double value, mode_omega, mode_zeta;
    /* ModeFollowingShaper: the mode designed for, the next sample, the newest command */
    double design_omega, design_zeta, last;
    long long k;
    double *ring;           /* ring_size (a power of two) past commands: u[j] at ring[j & (ring_size - 1)] */
    long long ring_size;
    Segment *segments;      /* a deque: the m-th in flight at segments[(head + m) & (capacity - 1)] */
    long long head, count, capacity, taps_in_flight;
    /* the newest design, shared by output (at a communication point) and the step that takes it */
    int has_pending;
    double pending_omega, pending_zeta;
    Tap pending[MAX_TAPS];
    long long n_pending;
    double times[MAX_IMPULSES], amplitudes[MAX_IMPULSES], scratch[2 * MAX_IMPULSES];
    SampleClock clock;
    int started;
    const char *failure;    /* set by a sample that could not be taken: message */
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

static Segment *segment_at(const Scheduled *s, long long m) { return &s->segments[(s->head + m) & (s->capacity - 1)]; }

static Segment *newest(const Scheduled *s) { return segment_at(s, s->count - 1); }

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

/* ---------------------------------------------------------------- designs (ModeFollowingShaper._taps) */

/* The design for (omega, zeta) on the sample grid into s->pending, unless it is there already; 0, or
 * -1 (failure set). The impulses are split onto the grid as grid_impulses does: the weights of one
 * delay added in the order of the impulses, then sorted by delay, zero weights left out. */
static int design(Scheduled *s, double omega, double zeta) {
    if (s->has_pending && s->pending_omega == omega && s->pending_zeta == zeta) return 0;
    if (omega * sqrt(1.0 - zeta * zeta) >= PI / s->h)
        return fail(s, "the mode omega = %g rad/s, zeta = %g lies at or above the Nyquist frequency pi*fs = %g rad/s: "
                    "sampled at fs = %g Hz no shaper can cancel it", omega, zeta, PI * s->fs, s->fs);
    const int count = design_closed_form(s->kind, s->order, 1, &omega, &zeta, s->times, s->amplitudes, MAX_IMPULSES,
                                         s->scratch);
    if (count < 1) return fail(s, "the shaper of order n = %d has more than %d impulses", s->order, MAX_IMPULSES);
    const double length = s->times[count - 1] / s->h + 2.0;
    if (!(length <= MAX_SAMPLED_LENGTH))
        return fail(s, "a shaper for omega = %g rad/s sampled at fs = %g Hz would be %.4g samples long, more than the "
                    "limit of 1,000,000 (shapefmu.runtime.limits.MAX_SAMPLED_LENGTH); use a lower fs or a higher "
                    "frequency", omega, s->fs, length);
    Tap taps[MAX_TAPS];
    long long n = 0;
    for (int i = 0; i < count; i++) {
        long k;
        const double alpha = grid_split(s->times[i], s->h, &k), a = s->amplitudes[i];
        const long long delays[2] = {k, (long long)k + 1};
        const double parts[2] = {(1.0 - alpha) * a, alpha * a};
        for (int p = 0; p < (alpha != 0.0 ? 2 : 1); p++) {
            long long at = 0;
            while (at < n && taps[at].delay != delays[p]) at++;
            if (at == n) taps[n++] = (Tap){delays[p], 0.0};
            taps[at].weight = taps[at].weight + parts[p];
        }
    }
    s->n_pending = 0;
    for (long long m = 0; m < n; m++) {  /* insertion by delay */
        if (taps[m].weight == 0.0) continue;
        long long at = s->n_pending++;
        for (; at > 0 && s->pending[at - 1].delay > taps[m].delay; at--) s->pending[at] = s->pending[at - 1];
        s->pending[at] = taps[m];
    }
    s->has_pending = 1, s->pending_omega = omega, s->pending_zeta = zeta;
    return 0;
}

/* The pending design copied into segment g (its taps replaced); 0, or -1 (failure set). */
static int take_pending(Scheduled *s, Segment *g) {
    const long long in_flight = s->taps_in_flight - g->n_taps + s->n_pending;
    if (in_flight > MAX_TAPS_IN_FLIGHT)
        return fail(s, "the designs in flight would hold %lld taps, more than the %lld summed per sample (a new "
                    "design at nearly every sample of a moving command): raise resolution", in_flight,
                    MAX_TAPS_IN_FLIGHT);
    Tap *taps = model_allocate(s->inst, (size_t)s->n_pending, sizeof(Tap));
    if (taps == NULL) return fail(s, "out of memory for a design of %lld taps", s->n_pending);
    memcpy(taps, s->pending, (size_t)s->n_pending * sizeof(Tap));
    model_release(s->inst, g->taps);
    g->taps = taps, g->n_taps = s->n_pending, g->reach = taps[g->n_taps - 1].delay + 1;
    s->taps_in_flight = in_flight;
    return 0;
}

/* ---------------------------------------------------------------- the shaper (ModeFollowingShaper) */

/* Grow the ring to hold reach samples (a power of two, the samples in order): _fit. */
static int fit(Scheduled *s, long long reach) {
    long long size = s->ring_size;
    if (size >= reach) return 0;
    while (size < reach) size *= 2;
    double *ring = model_allocate(s->inst, (size_t)size, sizeof(double));
    if (ring == NULL) return fail(s, "out of memory for %lld past commands", size);
    for (long long j = 0; j < size; j++) ring[j] = s->last;
    for (long long j = s->k - s->ring_size > 0 ? s->k - s->ring_size : 0; j < s->k; j++)
        ring[j & (size - 1)] = s->ring[j & (s->ring_size - 1)];
    model_release(s->inst, s->ring);
    s->ring = ring, s->ring_size = size;
    return 0;
}

/* A new open segment at the back, starting at sample start after the command base; 0, or -1. */
static int push_segment(Scheduled *s, long long start, double base) {
    if (s->count == s->capacity) {
        Segment *grown = model_allocate(s->inst, 2 * (size_t)s->capacity, sizeof(Segment));
        if (grown == NULL) return fail(s, "out of memory for %lld designs in flight", 2 * s->capacity);
        for (long long m = 0; m < s->count; m++) grown[m] = *segment_at(s, m);
        model_release(s->inst, s->segments);
        s->segments = grown, s->head = 0, s->capacity *= 2;
    }
    Segment *g = segment_at(s, s->count);
    memset(g, 0, sizeof *g);
    g->start = start, g->base = base, g->end_value = base, g->open = 1;
    if (take_pending(s, g) != 0) return -1;
    s->count++;
    return 0;
}

static void pop_segment(Scheduled *s) {
    Segment *g = segment_at(s, 0);
    s->taps_in_flight -= g->n_taps;
    model_release(s->inst, g->taps);
    g->taps = NULL;
    s->head = (s->head + 1) & (s->capacity - 1), s->count--;
}

static int moved(const Scheduled *s, double omega, double zeta) {
    const double w = s->design_omega, z = s->design_zeta;
    return fabs(omega - w) > s->resolution * w || fabs(zeta - z) > s->resolution;
}

/* The output at sample k with command u there and the samples before it in the ring (_sum). */
static double sum(const Scheduled *s, long long k, double u) {
    const long long mask = s->ring_size - 1;
    double y = segment_at(s, 0)->base;
    for (long long m = 0; m < s->count; m++) {
        const Segment *g = segment_at(s, m);
        for (long long i = 0; i < g->n_taps; i++) {
            const long long j = k - g->taps[i].delay;
            if (j < g->start) continue;
            const double value = j == k ? u : s->ring[j & mask];
            y += g->taps[i].weight * ((g->open || j <= g->end ? value : g->end_value) - g->base);
        }
    }
    return y;
}

/* One sample of the command u for the mode (omega, zeta) (ModeFollowingShaper.step); 0, or -1. */
static int shaper_step(Scheduled *s, double u, double omega, double zeta) {
    const long long k = s->k;
    if (moved(s, omega, zeta)) {
        if (design(s, omega, zeta) != 0) return -1;
        s->design_omega = omega, s->design_zeta = zeta;
        Segment *current = newest(s);
        if (current->moved) {  /* the changes made so far keep their design: a new segment begins here */
            current->open = 0, current->end = k - 1, current->end_value = s->last;
            if (push_segment(s, k, s->last) != 0) return -1;
        } else if (take_pending(s, current) != 0) {  /* nothing in flight depends on the old design */
            return -1;
        }
        if (fit(s, newest(s)->reach) != 0) return -1;
    }
    if (u != s->last) newest(s)->moved = 1;
    s->ring[k & (s->ring_size - 1)] = u;
    s->last = u;
    /* a segment whose last change has reached its last tap is folded into the base */
    while (s->count > 1 && k - (segment_at(s, 0)->reach - 1) >= segment_at(s, 0)->end) pop_segment(s);
    s->k = k + 1;
    return 0;
}

/* What a sample of command u at scheduling value will give, without taking it (the kernels' output):
 * the output if the command holds plus the first tap of the design for the mode times the change. */
static int output(Scheduled *s, double u, double value, double *y) {
    double omega = s->mode_omega, zeta = s->mode_zeta;
    if (value != s->value && schedule_mode(s, value, &omega, &zeta) != 0) return -1;
    const Tap *taps = newest(s)->taps;
    if (moved(s, omega, zeta)) {
        if (design(s, omega, zeta) != 0) return -1;
        taps = s->pending;
    }
    const double first = taps[0].delay == 0 ? taps[0].weight : 0.0;
    *y = sum(s, s->k, s->last) + first * (u - s->last);
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
    shaper_step(s, inputs[0], s->mode_omega, s->mode_zeta);
}

/* ---------------------------------------------------------------- the part's hooks: life cycle */

/* Back to before initialisation: the run's buffers freed, no failure (also the reset hook). */
static void release_run(ModelInstance *inst) {
    Scheduled *s = scheduled_of(inst);
    while (s->count > 0) pop_segment(s);
    model_release(inst, s->segments);
    model_release(inst, s->ring);
    s->segments = NULL, s->ring = NULL;
    s->head = s->capacity = s->ring_size = s->taps_in_flight = 0;
    s->started = s->has_pending = 0;
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
    s->h = 1.0 / s->fs;
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
    s->last = real_of(inst, SCHEDULED_REST);
    if (schedule_mode(s, s->value, &s->mode_omega, &s->mode_zeta) != 0 || design(s, s->mode_omega, s->mode_zeta) != 0)
        return model_fail(inst, "%s: %s", function, s->failure);
    s->design_omega = s->mode_omega, s->design_zeta = s->mode_zeta;
    s->k = 0, s->ring_size = 1;
    s->ring = model_allocate(inst, 1, sizeof(double));
    s->capacity = 4;
    s->segments = model_allocate(inst, (size_t)s->capacity, sizeof(Segment));
    if (s->ring == NULL || s->segments == NULL) return model_fail(inst, "%s: out of memory", function);
    s->ring[0] = s->last;
    if (push_segment(s, 0, s->last) != 0 || fit(s, newest(s)->reach) != 0)
        return model_fail(inst, "%s: %s", function, s->failure);
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
        double omega = s->mode_omega, zeta = s->mode_zeta;
        if (!s->started || s->clock.latched || value == s->value) return MODEL_OK;
        if (schedule_mode(s, value, &omega, &zeta) != 0 || (moved(s, omega, zeta) && design(s, omega, zeta) != 0)) {
            s->failure = NULL;
            return model_fail(inst, "%s: %s", function, s->message);
        }
        return MODEL_OK;
    }
    default: return twin_range(inst, v->name, value, 1, "finite", function);
    }
}

static ModelStatus check_integer(ModelInstance *inst, size_t vr, int value, const char *function) {
    const VariableRow *v = &scheduled_model.rows[vr];
    if (v->meaning == SCHEDULED_ORDER && (value < 0 || value > MAX_ORDER))
        return model_fail(inst, "%s: %s must be an integer in [0, %d] in the native ScheduledShaper, got %d", function,
                         v->name, MAX_ORDER, value);
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
 * Bytes: a fixed header (the kernel's scalars and the clock), the ring of past commands, then each
 * segment in flight: its scalars and its taps. */

typedef struct {
    long long magic, started, k, ring_size, count;
    double value, mode_omega, mode_zeta, design_omega, design_zeta, last;
    SampleClock clock;
} StateHeader;

#define STATE_MAGIC 0x5343484544ULL /* "SCHED" */

static size_t state_size(const ModelInstance *inst) {
    const Scheduled *s = scheduled_of(inst);
    if (!s->started) return sizeof(StateHeader);
    return sizeof(StateHeader) + (size_t)s->ring_size * sizeof(double) + (size_t)s->count * sizeof(Segment)
           + (size_t)s->taps_in_flight * sizeof(Tap);
}

static void save_state(const ModelInstance *inst, unsigned char *bytes) {
    const Scheduled *s = scheduled_of(inst);
    StateHeader header;
    memset(&header, 0, sizeof header);
    header.magic = (long long)STATE_MAGIC, header.started = s->started;
    if (s->started) {
        header.k = s->k, header.ring_size = s->ring_size, header.count = s->count;
        header.value = s->value, header.mode_omega = s->mode_omega, header.mode_zeta = s->mode_zeta;
        header.design_omega = s->design_omega, header.design_zeta = s->design_zeta, header.last = s->last;
        header.clock = s->clock;
    }
    memcpy(bytes, &header, sizeof header);
    if (!s->started) return;
    unsigned char *at = bytes + sizeof header;
    memcpy(at, s->ring, (size_t)s->ring_size * sizeof(double));
    at += (size_t)s->ring_size * sizeof(double);
    for (long long m = 0; m < s->count; m++) {
        Segment g = *segment_at(s, m);
        const Tap *taps = g.taps;
        g.taps = NULL;
        memcpy(at, &g, sizeof g);
        memcpy(at + sizeof g, taps, (size_t)g.n_taps * sizeof(Tap));
        at += sizeof g + (size_t)g.n_taps * sizeof(Tap);
    }
}

/* Whether segment g (the m-th of count) is one a run at sample k with a ring of ring_size can hold:
 * its taps are read and checked by the caller. */
static int segment_valid(const Segment *g, long long m, long long count, long long k, long long ring_size) {
    const int last = m == count - 1;
    return g->n_taps >= 1 && g->n_taps <= MAX_TAPS && (g->open == last) && (g->moved == 0 || g->moved == 1)
           && g->start >= 0 && g->start <= k && (g->open || (g->end >= g->start - 1 && g->end < k))
           && isfinite(g->base) && isfinite(g->end_value) && g->reach >= 1 && g->reach <= ring_size;
}

static int taps_valid(const Tap *taps, long long n, long long reach) {
    for (long long i = 0; i < n; i++)
        if (taps[i].delay < (i ? taps[i - 1].delay + 1 : 0) || !isfinite(taps[i].weight) || taps[i].weight == 0.0)
            return 0;
    return taps[n - 1].delay + 1 == reach;
}

static int mode_valid(double omega, double zeta) { return omega > 0.0 && isfinite(omega) && zeta >= 0.0 && zeta < 1.0; }

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
    const int ring_ok = h.ring_size >= 1 && h.ring_size <= MAX_RING && (h.ring_size & (h.ring_size - 1)) == 0;
    if (!ring_ok || h.k < 0 || h.count < 1 || h.count > MAX_RING + 1 || !isfinite(h.value)
        || !isfinite(h.last) || !mode_valid(h.mode_omega, h.mode_zeta) || !mode_valid(h.design_omega, h.design_zeta)
        || !clock_valid(&h.clock, 2) || h.clock.ts != real_of(inst, SCHEDULED_PERIOD)
        || (size - sizeof h) / sizeof(double) < (size_t)h.ring_size)
        return -1;
    const unsigned char *at = bytes + sizeof h, *end = bytes + size;
    s->ring = model_allocate(inst, (size_t)h.ring_size, sizeof(double));
    for (s->capacity = 4; s->capacity < h.count; s->capacity *= 2) {}
    s->segments = model_allocate(inst, (size_t)s->capacity, sizeof(Segment));
    if (s->ring == NULL || s->segments == NULL) goto refused;
    s->ring_size = h.ring_size;
    memcpy(s->ring, at, (size_t)h.ring_size * sizeof(double));
    at += (size_t)h.ring_size * sizeof(double);
    for (long long j = 0; j < h.ring_size; j++)
        if (!isfinite(s->ring[j])) goto refused;
    for (long long m = 0; m < h.count; m++) {
        Segment g;
        if ((size_t)(end - at) < sizeof g) goto refused;
        memcpy(&g, at, sizeof g);
        at += sizeof g;
        if (!segment_valid(&g, m, h.count, h.k, h.ring_size) || (size_t)(end - at) < (size_t)g.n_taps * sizeof(Tap)
            || s->taps_in_flight + g.n_taps > MAX_TAPS_IN_FLIGHT)
            goto refused;
        g.taps = model_allocate(inst, (size_t)g.n_taps, sizeof(Tap));
        if (g.taps == NULL) goto refused;
        memcpy(g.taps, at, (size_t)g.n_taps * sizeof(Tap));
        at += (size_t)g.n_taps * sizeof(Tap);
        s->segments[m] = g, s->count = m + 1, s->taps_in_flight += g.n_taps;
        if (!taps_valid(g.taps, g.n_taps, g.reach)) goto refused;
    }
    if (at != end) goto refused;
    s->k = h.k, s->value = h.value, s->mode_omega = h.mode_omega, s->mode_zeta = h.mode_zeta;
    s->design_omega = h.design_omega, s->design_zeta = h.design_zeta, s->last = h.last, s->clock = h.clock;
    s->started = 1;
    return 0;
refused:
    release_run(inst);
    return -1;
}

const ModelPart model_part = {
    .variables = &scheduled_model, .instantiate = instantiate, .free = free_model, .reset = release_run,
    .check_real = check_real, .check_integer = check_integer, .check_string = check_string, .update = update,
    .exit_initialization = exit_initialization, .do_step = do_step,
    .state_size = state_size, .save_state = save_state, .restore_state = restore_state,
};
