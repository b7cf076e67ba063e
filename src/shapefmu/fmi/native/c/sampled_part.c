/* The sampled filters' model part: what every native Shaper and ShapeFilter FMU
 * (sampled_model.h, a generated model.c) does behind the generic layer. Written once.
 *
 * At the exit of initialisation the design parameters become the taps of a sampled FIR
 * (sampled_fir.c): a Shaper's impulses are split onto the grid k Ts (grid_impulses), a
 * ShapeFilter's taps are taken as they are; a closed-form Shaper whose kind, n, n_modes, f[i] or
 * zeta[i] changed is re-designed first (shaper_designs.c). The impulses and taps are tunable: set
 * between steps, the new taps apply at once to the remembered inputs (the delay line allocated at
 * initialisation bounds the delays). Every refused value logs the variable, the value and the
 * valid range.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sampled_fir.h"
#include "sampled_model.h"
#include "shaper_designs.h"

#define PI 3.14159265358979323846
/* f[i], zeta[i] pairs a Shaper may declare. */
#define MAX_MODES 16

typedef struct {
    SampledFir fir;
    int started;             /* initialisation has ended: the filter runs */
    int design_changed;      /* a closed-form design input changed since the last design */
    double *taps;            /* the dense taps of a re-grid, length + 2 */
    double *scratch;         /* 2 * capacity doubles for the closed-form design */
    /* value references by meaning (first entry of an array); SIZE_MAX if absent */
    size_t u, y, period, rest, kind, order, modes, time, amplitude, tap;
    size_t frequency[MAX_MODES], damping[MAX_MODES]; /* f[i], zeta[i] are interleaved */
} Sampled;

static Sampled *sampled_of(ModelInstance *inst) { return (Sampled *)inst->model; }

static size_t n_variables(void) {
    const VariableTable *table = &sampled_model.variables;
    return table->n_real + table->n_integer + table->n_boolean + table->n_string;
}

/* i - 1 of a variable named base[i] (f[2] -> 1), 0 for a scalar. */
static int element(const VariableRow *v) {
    const char *bracket = strchr(v->name, '[');
    return bracket == NULL ? 0 : atoi(bracket + 1) - 1;
}

static double period(ModelInstance *inst) {
    return sampled_model.impulses ? inst->reals[sampled_of(inst)->period] : sampled_model.ts_used;
}

/* ---------------------------------------------------------------- taps */

/* The largest delay, in samples, of the design in the parameters now. */
static double longest_delay(ModelInstance *inst) {
    const Sampled *s = sampled_of(inst);
    double longest = 0.0;
    if (!sampled_model.impulses) return sampled_model.capacity - 1; /* every tap may be tuned */
    const double ts = period(inst);
    for (int i = 0; i < sampled_model.capacity; i++) {
        const double t = inst->reals[s->time + i], x = floor(t / ts) + 1.0;
        if (x > longest) longest = x; /* a split impulse reaches the sample after floor(t / ts) */
    }
    return longest;
}

/* The FIR's taps from the parameters: impulses split onto the grid, added per delay in the order
 * of the impulses (grid_impulses), or the filter's taps. */
static void regrid(ModelInstance *inst) {
    Sampled *s = sampled_of(inst);
    SampledFir *fir = &s->fir;
    const long length = fir->length;
    double *taps = s->taps;
    memset(taps, 0, (size_t)(length + 2) * sizeof(double));
    if (sampled_model.impulses) {
        const double ts = period(inst);
        for (int i = 0; i < sampled_model.capacity; i++) {
            long k;
            const double a = inst->reals[s->amplitude + i];
            const double alpha = grid_split(inst->reals[s->time + i], ts, &k);
            taps[k] += (1.0 - alpha) * a;
            if (alpha != 0.0) taps[k + 1] += alpha * a;
        }
    } else {
        for (int i = 0; i < sampled_model.capacity && i <= length; i++) taps[i] = inst->reals[s->tap + i];
    }
    fir->w0 = taps[0];
    fir->n_tail = 0;
    for (long d = 1; d <= length; d++)
        if (taps[d] != 0.0) {
            fir->tail_offset[fir->n_tail] = d - 1;
            fir->tail_weight[fir->n_tail++] = taps[d];
        }
}

static void free_line(ModelInstance *inst) {
    Sampled *s = sampled_of(inst);
    void *buffers[] = {s->fir.line, s->fir.tail_offset, s->fir.tail_weight, s->taps};
    for (size_t i = 0; i < sizeof buffers / sizeof buffers[0]; i++) model_release(inst, buffers[i]);
    s->fir.line = NULL, s->fir.tail_offset = NULL, s->fir.tail_weight = NULL, s->taps = NULL;
    s->fir.length = 0;
}

/* A delay line of length samples and room for the taps; 0 on success. */
static int allocate_line(ModelInstance *inst, long length) {
    Sampled *s = sampled_of(inst);
    free_line(inst);
    s->fir.length = length;
    s->fir.line = model_allocate(inst, 2 * (size_t)length, sizeof(double));
    s->fir.tail_offset = model_allocate(inst, (size_t)length, sizeof(long));
    s->fir.tail_weight = model_allocate(inst, (size_t)length, sizeof(double));
    s->taps = model_allocate(inst, (size_t)length + 2, sizeof(double));
    return s->fir.line && s->fir.tail_offset && s->fir.tail_weight && s->taps ? 0 : -1;
}

/* ---------------------------------------------------------------- design */

static ModelStatus design(ModelInstance *inst, const char *function) {
    Sampled *s = sampled_of(inst);
    const char *kind = model_string(inst, s->kind);
    const int n = inst->integers[s->order - sampled_model.variables.n_real];
    const int n_modes = inst->integers[s->modes - sampled_model.variables.n_real];
    double omega[MAX_MODES], zeta[MAX_MODES];
    for (int j = 0; j < n_modes; j++) {
        omega[j] = 2.0 * PI * inst->reals[s->frequency[j]];
        zeta[j] = inst->reals[s->damping[j]];
    }
    double *times = inst->reals + s->time, *amplitudes = inst->reals + s->amplitude;
    const int count = design_closed_form(closed_form_kind(kind), n, n_modes, omega, zeta, times, amplitudes,
                                         sampled_model.capacity, s->scratch);
    if (count < 0)
        return model_fail(inst, "%s: kind %s with n = %d for n_modes = %d has more impulses than the %d this FMU "
                         "holds; rebuild it with shapefmu build shaper --native for that design", function, kind, n,
                         n_modes, sampled_model.capacity);
    for (int i = count; i < sampled_model.capacity; i++) times[i] = amplitudes[i] = 0.0; /* unused entries */
    s->design_changed = 0;
    model_debug(inst, "%s: %s re-designed in C for %d modes: %d impulses", function, kind, n_modes, count);
    return MODEL_OK;
}

static ModelStatus update(ModelInstance *inst, const char *function);

static ModelStatus exit_initialization(ModelInstance *inst, const char *function) {
    Sampled *s = sampled_of(inst);
    if (sampled_model.closed_form && s->design_changed && design(inst, function) != MODEL_OK) return MODEL_ERROR;
    const double longest = longest_delay(inst), ts = period(inst);
    if (longest > MAX_DELAY_SAMPLES)
        return model_fail(inst, "%s: the design's longest delay spans %.0f samples of Ts = %g s; at most %ld (the "
                         "delay line): use a longer Ts", function, longest, ts, MAX_DELAY_SAMPLES);
    if (allocate_line(inst, longest < 1.0 ? 1 : (long)longest) != 0)
        return model_fail(inst, "%s: out of memory for a delay line of %.0f samples", function, longest);
    regrid(inst);
    fir_start(&s->fir, inst->reals[s->rest], ts);
    s->started = 1;
    return update(inst, function);
}

static ModelStatus update(ModelInstance *inst, const char *function) {
    (void)function;
    Sampled *s = sampled_of(inst);
    if (s->started) inst->reals[s->y] = fir_output(&s->fir, inst->reals[s->u]);
    return MODEL_OK;
}

static ModelStatus do_step(ModelInstance *inst, double t, double h, const char *function) {
    Sampled *s = sampled_of(inst);
    const GridStep step = grid_step(&s->fir.at, s->fir.ts, t, h);
    if (step.count > (double)MAX_SAMPLES_PER_STEP)
        return model_fail(inst, "%s: communication step h = %g s spans %.0f samples of Ts = %g s; at most "
                         "%lld per step", function, h, step.count, s->fir.ts, MAX_SAMPLES_PER_STEP);
    fir_step(&s->fir, &step, inst->reals[s->u]);
    return MODEL_OK;
}

/* ---------------------------------------------------------------- values */

static const VariableRow *row(size_t vr) { return &sampled_model.variables.rows[vr]; }

/* Refuses a value other than the build value; given is the value as the user wrote it. */
static ModelStatus refuse_other_value(ModelInstance *inst, size_t vr, const char *given, const char *function) {
    const VariableRow *v = row(vr);
    char start[64];
    if (v->string_start != NULL) snprintf(start, sizeof start, "%s", v->string_start);
    else snprintf(start, sizeof start, "%.17g", v->start);
    return model_fail(inst, "%s: %s is %s in this native FMU, whose design is made at build time; got %s (rebuild it "
                     "with shapefmu build ... --native for another value)", function, v->name, start, given);
}

static ModelStatus real_range(ModelInstance *inst, const char *name, double value, int ok, const char *range,
                             const char *function) {
    if (ok && isfinite(value)) return MODEL_OK;
    return model_fail(inst, "%s: %s must be %s, got %g", function, name, range, value);
}

static ModelStatus keeps_real(ModelInstance *inst, size_t vr, double value, int same, const char *function) {
    if (same) return MODEL_OK;
    char given[32];
    snprintf(given, sizeof given, "%.17g", value);
    return refuse_other_value(inst, vr, given, function);
}

static ModelStatus keeps_integer(ModelInstance *inst, size_t vr, int value, int same, const char *function) {
    if (same) return MODEL_OK;
    char given[32];
    snprintf(given, sizeof given, "%d", value);
    return refuse_other_value(inst, vr, given, function);
}

static ModelStatus check_real(ModelInstance *inst, size_t vr, double value, const char *function) {
    if (vr == sampled_of(inst)->u && isfinite(value)) return MODEL_OK; /* the input, every step: first */
    const VariableRow *v = row(vr);
    switch (v->meaning) {
    case MEANS_PERIOD: return real_range(inst, v->name, value, value > 0.0, "> 0", function);
    case MEANS_IMPULSE_TIME: {
        if (real_range(inst, v->name, value, value >= 0.0, ">= 0 (s)", function) != MODEL_OK) return MODEL_ERROR;
        const Sampled *s = sampled_of(inst);
        if (s->started && floor(value / period(inst)) + 1.0 > (double)s->fir.length)
            return model_fail(inst, "%s: %s = %g s lies beyond the delay line of %ld samples of Ts = %g s allocated at "
                             "initialisation", function, v->name, value, s->fir.length, period(inst));
        return MODEL_OK;
    }
    case MEANS_TAP:
        if (element(v) == 0 && !sampled_model.feedthrough && value != 0.0)
            return model_fail(inst, "%s: %s must stay 0, since this FMU declares y independent of u at the same "
                             "instant, got %g", function, v->name, value);
        return real_range(inst, v->name, value, 1, "finite", function);
    case MEANS_FREQUENCY:
        if (real_range(inst, v->name, value, value > 0.0, "> 0", function) != MODEL_OK) return MODEL_ERROR;
        return keeps_real(inst, vr, value, sampled_model.closed_form || value == v->start, function);
    case MEANS_DAMPING:
        if (real_range(inst, v->name, value, value >= 0.0 && value < 1.0, "in [0, 1)", function) != MODEL_OK)
            return MODEL_ERROR;
        return keeps_real(inst, vr, value, sampled_model.closed_form || value == v->start, function);
    case MEANS_TOLERANCE:
        if (real_range(inst, v->name, value, value > 0.0 && value < 1.0, "in (0, 1)", function) != MODEL_OK)
            return MODEL_ERROR;
        return keeps_real(inst, vr, value, sampled_model.closed_form || value == v->start, function);
    case MEANS_BUILD_VALUE: return keeps_real(inst, vr, value, value == v->start, function);
    default: return real_range(inst, v->name, value, 1, "finite", function);
    }
}

static ModelStatus check_integer(ModelInstance *inst, size_t vr, int value, const char *function) {
    const VariableRow *v = row(vr);
    switch (v->meaning) {
    case MEANS_ORDER:
        if (value < 0 || value > 62) return model_fail(inst, "%s: n must be an integer in [0, 62], got %d", function, value);
        return keeps_integer(inst, vr, value, sampled_model.closed_form || value == v->start, function);
    case MEANS_MODES:
        if (value < 1 || value > sampled_model.max_modes)
            return model_fail(inst, "%s: n_modes must be in [1, %d], got %d", function, sampled_model.max_modes, value);
        return keeps_integer(inst, vr, value, sampled_model.closed_form || value == v->start, function);
    default: return keeps_integer(inst, vr, value, value == (int)v->start, function);
    }
}

static ModelStatus check_string(ModelInstance *inst, size_t vr, const char *value, const char *function) {
    const VariableRow *v = row(vr);
    const int same = strcmp(value, v->string_start) == 0;
    if (v->meaning == MEANS_KIND && sampled_model.closed_form && !same && closed_form_kind(value) == KIND_NOT_CLOSED_FORM)
        return model_fail(inst, "%s: kind must be a kind this FMU designs in C (zv, zvd, zvdd, zv_dn, mzv), got %s; "
                         "other kinds are designed at build time: shapefmu build shaper --native --kind %s", function,
                         value, value);
    if (same || (v->meaning == MEANS_KIND && sampled_model.closed_form)) return MODEL_OK;
    return refuse_other_value(inst, vr, value, function);
}

static void changed(ModelInstance *inst, size_t vr) {
    Sampled *s = sampled_of(inst);
    if (vr == s->u) return; /* y follows u in update */
    switch (row(vr)->meaning) {
    case MEANS_KIND: case MEANS_ORDER: case MEANS_MODES: case MEANS_FREQUENCY: case MEANS_DAMPING:
        s->design_changed = 1;
        break;
    case MEANS_IMPULSE_TIME: case MEANS_IMPULSE_AMPLITUDE: case MEANS_TAP:
        if (s->started) {
            regrid(inst);
            fir_recompute(&s->fir);
        }
        break;
    default: break;
    }
}



/* ---------------------------------------------------------------- state */

/* started, design_changed, then the FIR's state when started. */
static size_t state_size(const ModelInstance *inst) {
    const Sampled *s = (const Sampled *)inst->model;
    return 2 * sizeof(long long) + (s->started ? fir_state_size(&s->fir) : 0);
}

static void save_state(const ModelInstance *inst, unsigned char *bytes) {
    const Sampled *s = (const Sampled *)inst->model;
    const long long flags[2] = {s->started, s->design_changed};
    memcpy(bytes, flags, sizeof flags);
    if (s->started) fir_save(&s->fir, bytes + sizeof flags);
}

static int restore_state(ModelInstance *inst, const unsigned char *bytes, size_t size, const char *function) {
    (void)function;
    Sampled *s = sampled_of(inst);
    long long flags[2];
    if (size < sizeof flags) return -1;
    memcpy(flags, bytes, sizeof flags);
    if ((flags[0] != 0 && flags[0] != 1) || (flags[1] != 0 && flags[1] != 1)) return -1;
    s->started = 0;
    s->design_changed = (int)flags[1];
    if (!flags[0]) return size == sizeof flags ? 0 : -1;
    /* The delay line's length is the first scalar of the FIR's state (sampled_fir.c). */
    long long length;
    if (size < sizeof flags + sizeof(long long)) return -1;
    memcpy(&length, bytes + sizeof flags, sizeof length);
    if (length < 1 || length > MAX_DELAY_SAMPLES || (length != s->fir.length && allocate_line(inst, (long)length) != 0))
        return -1;
    if (fir_restore(&s->fir, bytes + sizeof flags, size - sizeof flags, period(inst)) != 0 || longest_delay(inst) > (double)length)
        return -1;
    regrid(inst);
    s->started = 1;
    return 0;
}

/* ---------------------------------------------------------------- life cycle */

static size_t first_of(SampledMeaning meaning) {
    for (size_t vr = 0; vr < n_variables(); vr++)
        if (row(vr)->meaning == (int)meaning) return vr;
    return (size_t)-1;
}

static void reset(ModelInstance *inst) {
    Sampled *s = sampled_of(inst);
    s->started = 0;
    s->design_changed = 0;
}

static void free_model(ModelInstance *inst) {
    Sampled *s = sampled_of(inst);
    if (s == NULL) return;
    free_line(inst);
    model_release(inst, s->scratch);
    model_release(inst, s);
    inst->model = NULL;
}

static int instantiate(ModelInstance *inst) {
    Sampled *s = model_allocate(inst, 1, sizeof(Sampled));
    if (s == NULL) return -1;
    memset(s, 0, sizeof *s);
    inst->model = s;
    s->u = first_of(MEANS_INPUT), s->y = first_of(MEANS_OUTPUT), s->rest = first_of(MEANS_REST);
    s->period = first_of(MEANS_PERIOD), s->kind = first_of(MEANS_KIND), s->order = first_of(MEANS_ORDER);
    s->modes = first_of(MEANS_MODES), s->time = first_of(MEANS_IMPULSE_TIME);
    s->amplitude = first_of(MEANS_IMPULSE_AMPLITUDE), s->tap = first_of(MEANS_TAP);
    for (size_t vr = 0; vr < n_variables(); vr++) {
        const VariableRow *v = row(vr);
        if (element(v) >= MAX_MODES) continue;
        if (v->meaning == MEANS_FREQUENCY) s->frequency[element(v)] = vr;
        if (v->meaning == MEANS_DAMPING) s->damping[element(v)] = vr;
    }
    if (sampled_model.closed_form) {
        s->scratch = model_allocate(inst, 2 * (size_t)sampled_model.capacity, sizeof(double));
        if (s->scratch == NULL) return -1;
    }
    return 0;
}

const ModelPart model_part = {
    .variables = &sampled_model.variables, .instantiate = instantiate, .free = free_model, .reset = reset,
    .check_real = check_real, .check_integer = check_integer, .check_string = check_string, .changed = changed,
    .update = update, .exit_initialization = exit_initialization, .do_step = do_step,
    .state_size = state_size, .save_state = save_state, .restore_state = restore_state,
};
