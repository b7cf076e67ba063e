/* The native profile generator behind the generic FMI layers: the C twin of the pythonfmu
 * ProfileGenerator, runtime/motion.py's PiecewiseAcceleration.state operation for operation.
 *
 * A twin-pulse or time-frequency move is designed at build time (motion_model.h), so its design
 * parameters keep their build values (another value is refused with a message saying to rebuild).
 * A shaped bang-bang is closed-form: it is re-designed in C at the exit of initialisation
 * (motion_design.c) from distance, speed and acceleration_limit, and, if its shaper is none or a
 * closed-form kind (zv, zvd, zvdd, zv_dn, mzv), from shaper, n, n_modes, omega[i] and zeta[i]
 * (shaper_designs.c), as the pythonfmu FMU does; t_start may change before initialisation. The move starts at
 * t_start, or earlier at the first communication point where the input start is >= 0.5 (a rising
 * start latches); the outputs at a communication point are the move's exact state at the time since
 * its start, counted from the steps the host took (sample_clock.h's StepTime: a start time of 1.7e9
 * plays the move of 0, bit for bit). Setting start high after initialisation starts the move at that instant, where the
 * acceleration jumps to its first level: the acceleration depends on start (ModelStructure).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "motion_model.h"
#include "sample_clock.h"
#include "shaper_designs.h"

/* Impulses of a shaper re-designed in C (the product over the modes of each mode's). */
#define MAX_IMPULSES 4096

typedef struct {
    long long started, has_start;  /* initialised; the move has started, at started_at */
    double started_at;             /* a time since t0, as elapsed */
    StepTime elapsed;              /* the time since t0, summed from the steps */
    MotionPath path;               /* the move played: the build's, or re-designed in storage */
    double *storage;
    size_t vr[MOTION_MEANINGS];
} Generator;

static Generator *generator_of(const ModelInstance *inst) { return (Generator *)inst->model; }


/* (position, velocity, acceleration) at t; the acceleration is right-continuous. */
static void state_at(const MotionPath *path, double t, double *out) {
    const double *breaks = path->breaks;
    const size_t n = path->n_levels;
    /* k = bisect_right(breaks, t + tolerance) - 1 */
    const double key = t + path->tolerance;
    size_t low = 0, high = n + 1;
    while (low < high) {
        const size_t mid = low + (high - low) / 2;
        if (breaks[mid] <= key) low = mid + 1;
        else high = mid;
    }
    if (low == 0) {
        out[0] = out[1] = out[2] = 0.0;
        return;
    }
    const size_t k = low - 1;
    if (k >= n) {
        const double s = t - breaks[n];
        out[0] = path->position[n] + path->velocity[n] * s, out[1] = path->velocity[n], out[2] = 0.0;
        return;
    }
    const double s = t - breaks[k], a = path->levels[k], v = path->velocity[k];
    out[0] = path->position[k] + v * s + 0.5 * a * s * s, out[1] = v + a * s, out[2] = a;
}

static void update(ModelInstance *inst, double elapsed) {
    const Generator *g = generator_of(inst);
    double out[3] = {0.0, 0.0, 0.0};
    if (g->has_start) state_at(&g->path, elapsed - g->started_at, out);
    inst->reals[g->vr[MOTION_POSITION]] = out[0];
    inst->reals[g->vr[MOTION_VELOCITY]] = out[1];
    inst->reals[g->vr[MOTION_ACCELERATION]] = out[2];
}

/* Whether the move's t_start (an absolute time; negative: none) has come elapsed after t0. */
static int scheduled(const ModelInstance *inst, double elapsed) {
    const double t_start = inst->reals[generator_of(inst)->vr[MOTION_T_START]];
    return 0.0 <= t_start && t_start - inst->start_time <= elapsed;
}

static void maybe_start(ModelInstance *inst, double elapsed) {
    Generator *g = generator_of(inst);
    if (g->has_start) return;
    if (inst->reals[g->vr[MOTION_START]] >= 0.5) g->has_start = 1, g->started_at = elapsed;
    else if (scheduled(inst, elapsed))
        g->has_start = 1, g->started_at = inst->reals[g->vr[MOTION_T_START]] - inst->start_time;
}

/* ---------------------------------------------------------------- life cycle */



static void release_path(ModelInstance *inst) {
    Generator *g = generator_of(inst);
    model_release(inst, g->storage);
    g->storage = NULL;
    g->path = motion_path;
}

static void reset(ModelInstance *inst) {
    release_path(inst);
    Generator *g = generator_of(inst);
    g->started = g->has_start = 0;
    g->started_at = 0.0;
    memset(&g->elapsed, 0, sizeof g->elapsed);
}

static int instantiate(ModelInstance *inst) {
    Generator *g = model_allocate(inst, 1, sizeof(Generator));
    if (g == NULL) return -1;
    memset(g, 0, sizeof *g);
    inst->model = g;
    twin_index(&motion_variables, g->vr, MOTION_MEANINGS);
    g->path = motion_path;
    return 0;
}

static void free_model(ModelInstance *inst) {
    if (inst->model == NULL) return;
    release_path(inst);
    model_release(inst, inst->model);
    inst->model = NULL;
}

static double real_of(const ModelInstance *inst, int meaning) { return inst->reals[generator_of(inst)->vr[meaning]]; }
static int integer_of(const ModelInstance *inst, int meaning) {
    return inst->integers[generator_of(inst)->vr[meaning] - motion_variables.n_real];
}

/* A bang-bang build's move for the parameters now (shaped_bang_bang.py): its shaper re-designed
 * if closed-form (none: one impulse), else the build's impulses. */
static ModelStatus design(ModelInstance *inst, const char *function) {
    Generator *g = generator_of(inst);
    double omega[MOTION_MAX_MODES], zeta[MOTION_MAX_MODES];
    int count = motion_shaper.count;
    const double *times = motion_shaper.times, *amplitudes = motion_shaper.amplitudes;
    double *work = model_allocate(inst, 4 * MAX_IMPULSES + 2, sizeof(double)); /* impulses, and their design's scratch */
    if (work == NULL) return model_fail(inst, "%s: out of memory for the move's design", function);
    if (motion_shaper.closed_form) {
        const char *shaper = model_string(inst, g->vr[MOTION_SHAPER]);
        double *t = work, *a = work + MAX_IMPULSES;
        if (strcmp(shaper, "none") == 0) {
            t[0] = 0.0, a[0] = 1.0, count = 1;
        } else {
            const int n_modes = integer_of(inst, MOTION_MODES);
            for (int j = 0; j < n_modes; j++) omega[j] = real_of(inst, MOTION_OMEGA1 + j), zeta[j] = real_of(inst, MOTION_ZETA1 + j);
            count = design_closed_form(closed_form_kind(shaper), integer_of(inst, MOTION_ORDER), n_modes, omega, zeta, t, a,
                                       MAX_IMPULSES, work + 2 * MAX_IMPULSES);
            if (count < 0) {
                model_release(inst, work);
                return model_fail(inst, "%s: shaper %s for %d modes has more than %d impulses", function, shaper, n_modes,
                                 MAX_IMPULSES);
            }
        }
        times = t, amplitudes = a;
    }
    release_path(inst);
    g->storage = model_allocate(inst, MOTION_DOUBLES(count), sizeof(double));
    double *scratch = model_allocate(inst, 4 * (size_t)count, sizeof(double));
    if (g->storage == NULL || scratch == NULL) {
        model_release(inst, scratch);
        model_release(inst, work);
        return model_fail(inst, "%s: out of memory for the move", function);
    }
    motion_shaped_bang_bang(&g->path, g->storage, scratch, real_of(inst, MOTION_DISTANCE),
                            real_of(inst, MOTION_ACCELERATION_LIMIT), real_of(inst, MOTION_SPEED), times, amplitudes, count);
    model_release(inst, scratch);
    model_release(inst, work);
    return MODEL_OK;
}

static ModelStatus exit_initialization(ModelInstance *inst, const char *function) {
    Generator *g = generator_of(inst);
    if (motion_shaper.bang_bang && design(inst, function) != MODEL_OK) return MODEL_ERROR;
    g->has_start = 0;
    memset(&g->elapsed, 0, sizeof g->elapsed);
    maybe_start(inst, 0.0);
    update(inst, 0.0);
    g->started = 1;
    return MODEL_OK;
}


static ModelStatus do_step(ModelInstance *inst, double t, double h, const char *function) {
    (void)function;
    Generator *g = generator_of(inst);
    (void)t;
    maybe_start(inst, step_time_value(&g->elapsed));
    step_time_add(&g->elapsed, h);
    const double elapsed = step_time_value(&g->elapsed);
    if (!g->has_start && scheduled(inst, elapsed))
        g->has_start = 1, g->started_at = inst->reals[g->vr[MOTION_T_START]] - inst->start_time;
    update(inst, elapsed);
    return MODEL_OK;
}

/* ---------------------------------------------------------------- values */

static ModelStatus keeps(ModelInstance *inst, const VariableRow *v, const char *given, int same, const char *function) {
    if (same) return MODEL_OK;
    return twin_refuse(inst, v, given, "move is", "shapefmu build profile --native", function);
}

/* Whether the parameter of this meaning is re-designed in C (else it keeps its build value). */
static int redesigned(int m) {
    if (!motion_shaper.bang_bang) return 0;
    if (m == MOTION_DISTANCE || m == MOTION_SPEED || m == MOTION_ACCELERATION_LIMIT) return 1;
    return motion_shaper.closed_form && m >= MOTION_SHAPER && m <= MOTION_ZETA4;
}

static ModelStatus check_real(ModelInstance *inst, size_t vr, double value, const char *function) {
    const VariableRow *v = &motion_variables.rows[vr];
    const int m = v->meaning;
    if (!isfinite(value)) return model_fail(inst, "%s: %s must be finite, got %g", function, v->name, value);
    if (m == MOTION_T_START || m == MOTION_START || m >= MOTION_POSITION) return MODEL_OK;
    if (redesigned(m)) {
        const char *valid = (m == MOTION_DISTANCE || m == MOTION_ACCELERATION_LIMIT || (m >= MOTION_OMEGA1 && m <= MOTION_OMEGA4))
                            && !(value > 0.0) ? "> 0"
                            : m == MOTION_SPEED && !(value >= 0.0) ? ">= 0 (0: no speed limit)"
                            : m >= MOTION_ZETA1 && !(value >= 0.0 && value < 1.0) ? "in [0, 1)" : NULL;
        if (valid != NULL) return model_fail(inst, "%s: %s must be %s, got %g", function, v->name, valid, value);
        return MODEL_OK;
    }
    char given[32];
    snprintf(given, sizeof given, "%.17g", value);
    return keeps(inst, v, given, value == v->start, function);
}

static ModelStatus check_integer(ModelInstance *inst, size_t vr, int value, const char *function) {
    const VariableRow *v = &motion_variables.rows[vr];
    if (redesigned(v->meaning)) {
        if (v->meaning == MOTION_ORDER && (value < 0 || value > 62))
            return model_fail(inst, "%s: n must be an integer in [0, 62], got %d", function, value);
        if (v->meaning == MOTION_MODES && (value < 1 || value > MOTION_MAX_MODES))
            return model_fail(inst, "%s: n_modes must be in [1, %d], got %d", function, MOTION_MAX_MODES, value);
        return MODEL_OK;
    }
    char given[32];
    snprintf(given, sizeof given, "%d", value);
    return keeps(inst, v, given, value == (int)v->start, function);
}

static ModelStatus check_string(ModelInstance *inst, size_t vr, const char *value, const char *function) {
    const VariableRow *v = &motion_variables.rows[vr];
    if (redesigned(v->meaning)) {
        if (strcmp(value, "none") == 0 || closed_form_kind(value) != KIND_NOT_CLOSED_FORM) return MODEL_OK;
        return model_fail(inst, "%s: shaper must be none or a kind this FMU designs in C (zv, zvd, zvdd, zv_dn, mzv), "
                         "got %s; other kinds are designed at build time: shapefmu build profile --native --param "
                         "shaper=%s", function, value, value);
    }
    return keeps(inst, v, value, strcmp(value, v->string_start) == 0, function);
}

static void changed(ModelInstance *inst, size_t vr) {
    Generator *g = generator_of(inst);
    if (motion_variables.rows[vr].meaning != MOTION_START || !g->started || g->has_start) return;
    if (inst->reals[vr] >= 0.5) {
        g->has_start = 1, g->started_at = step_time_value(&g->elapsed);
        update(inst, g->started_at);
    }
}



/* ---------------------------------------------------------------- state */

#define STATE_MAGIC 0x4d4f54494f4eULL /* "MOTION" */

typedef struct {
    long long magic, started, has_start;
    double started_at;
    StepTime elapsed;
} StateBytes;

static size_t state_size(const ModelInstance *inst) {
    (void)inst;
    return sizeof(StateBytes);
}

static void save_state(const ModelInstance *inst, unsigned char *bytes) {
    const Generator *g = generator_of(inst);
    const StateBytes saved = {(long long)STATE_MAGIC, g->started, g->has_start, g->started_at, g->elapsed};
    memcpy(bytes, &saved, sizeof saved);
}

static int restore_state(ModelInstance *inst, const unsigned char *bytes, size_t size, const char *function) {
    Generator *g = generator_of(inst);
    StateBytes saved;
    if (size != sizeof saved) return -1;
    memcpy(&saved, bytes, sizeof saved);
    if (saved.magic != (long long)STATE_MAGIC || (saved.started != 0 && saved.started != 1)
        || (saved.has_start != 0 && saved.has_start != 1) || !isfinite(saved.started_at)
        || !(saved.elapsed.sum >= 0.0 && saved.elapsed.sum < INFINITY) || !isfinite(saved.elapsed.compensation))
        return -1;
    g->started = saved.started, g->has_start = saved.has_start, g->started_at = saved.started_at;
    g->elapsed = saved.elapsed;
    /* a re-designed move follows from the parameters the layer has just restored */
    if (saved.started && motion_shaper.bang_bang && design(inst, function) != MODEL_OK) return -1;
    return 0;
}

const ModelPart model_part = {
    .variables = &motion_variables, .instantiate = instantiate, .free = free_model, .reset = reset,
    .check_real = check_real, .check_integer = check_integer, .check_string = check_string, .changed = changed,
    .exit_initialization = exit_initialization, .do_step = do_step,
    .state_size = state_size, .save_state = save_state, .restore_state = restore_state,
};
