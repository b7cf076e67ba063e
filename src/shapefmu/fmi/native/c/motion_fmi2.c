/* The native profile generator behind the generic FMI 2.0 layer: the C twin of the pythonfmu
 * ProfileGenerator, runtime/motion.py's PiecewiseAcceleration.state operation for operation.
 *
 * The move (twin-pulse, time-frequency or shaped bang-bang) is designed at build time
 * (motion_model.h), so every design parameter keeps its build value (another value is refused with
 * a message saying to rebuild); t_start may change before initialisation. The move starts at
 * t_start, or earlier at the first communication point where the input start is >= 0.5 (a rising
 * start latches); the outputs at a communication point t are the move's exact state at t minus its
 * start. Setting start high after initialisation starts the move at that instant, where the
 * acceleration jumps to its first level: the acceleration depends on start (ModelStructure).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "motion_model.h"

typedef struct {
    long long started, has_start;  /* initialised; the move has started, at started_at */
    double started_at;
    size_t vr[MOTION_MEANINGS];
} Generator;

static Generator *generator_of(const Fmi2Instance *inst) { return (Generator *)inst->model; }


/* (position, velocity, acceleration) at t; the acceleration is right-continuous. */
static void state_at(double t, double *out) {
    const double *breaks = motion_path.breaks;
    const size_t n = motion_path.n_levels;
    /* k = bisect_right(breaks, t + tolerance) - 1 */
    const double key = t + motion_path.tolerance;
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
        out[0] = motion_path.position[n] + motion_path.velocity[n] * s, out[1] = motion_path.velocity[n], out[2] = 0.0;
        return;
    }
    const double s = t - breaks[k], a = motion_path.levels[k], v = motion_path.velocity[k];
    out[0] = motion_path.position[k] + v * s + 0.5 * a * s * s, out[1] = v + a * s, out[2] = a;
}

static void update(Fmi2Instance *inst, double t) {
    const Generator *g = generator_of(inst);
    double out[3] = {0.0, 0.0, 0.0};
    if (g->has_start) state_at(t - g->started_at, out);
    inst->reals[g->vr[MOTION_POSITION]] = out[0];
    inst->reals[g->vr[MOTION_VELOCITY]] = out[1];
    inst->reals[g->vr[MOTION_ACCELERATION]] = out[2];
}

static void maybe_start(Fmi2Instance *inst, double t) {
    Generator *g = generator_of(inst);
    if (g->has_start) return;
    const double t_start = inst->reals[g->vr[MOTION_T_START]];
    if (inst->reals[g->vr[MOTION_START]] >= 0.5) g->has_start = 1, g->started_at = t;
    else if (0.0 <= t_start && t_start <= t) g->has_start = 1, g->started_at = t_start;
}

/* ---------------------------------------------------------------- life cycle */

void model_describe(Fmi2ModelInfo *info) {
    memset(info, 0, sizeof *info);
    twin_describe(&motion_variables, info);
}

Fmi2Role model_variable(const Fmi2Instance *inst, Fmi2Type type, size_t vr, const char **name) {
    (void)inst, (void)type;
    return twin_variable(&motion_variables, vr, name);
}

void model_reset(Fmi2Instance *inst) {
    twin_reset(&motion_variables, inst);
    Generator *g = generator_of(inst);
    g->started = g->has_start = 0;
    g->started_at = 0.0;
}

int model_instantiate(Fmi2Instance *inst) {
    Generator *g = fmi2_allocate(inst, 1, sizeof(Generator));
    if (g == NULL) return -1;
    memset(g, 0, sizeof *g);
    inst->model = g;
    twin_index(&motion_variables, g->vr, MOTION_MEANINGS);
    model_reset(inst);
    return 0;
}

void model_free(Fmi2Instance *inst) {
    fmi2_release(inst, inst->model);
    inst->model = NULL;
}

fmi2Status model_exit_initialization(Fmi2Instance *inst) {
    Generator *g = generator_of(inst);
    g->has_start = 0;
    maybe_start(inst, inst->time);
    update(inst, inst->time);
    g->started = 1;
    return fmi2OK;
}

fmi2Status model_update(Fmi2Instance *inst, const char *function) {
    (void)inst, (void)function;
    return fmi2OK;
}

fmi2Status model_do_step(Fmi2Instance *inst, double t, double h) {
    Generator *g = generator_of(inst);
    maybe_start(inst, t);
    if (!g->has_start) {
        const double t_start = inst->reals[g->vr[MOTION_T_START]];
        if (0.0 <= t_start && t_start <= t + h) g->has_start = 1, g->started_at = t_start;
    }
    update(inst, t + h);
    return fmi2OK;
}

/* ---------------------------------------------------------------- values */

static fmi2Status keeps(Fmi2Instance *inst, const TwinVariable *v, const char *given, int same, const char *function) {
    if (same) return fmi2OK;
    return twin_refuse(inst, v, given, "move is", "shapefmu build profile --native", function);
}

fmi2Status model_check_real(Fmi2Instance *inst, size_t vr, double value, const char *function) {
    const TwinVariable *v = &motion_variables.variables[vr];
    if (!isfinite(value)) return fmi2_fail(inst, "%s: %s must be finite, got %g", function, v->name, value);
    if (v->meaning != MOTION_DESIGN) return fmi2OK;
    char given[32];
    snprintf(given, sizeof given, "%.17g", value);
    return keeps(inst, v, given, value == v->start, function);
}

fmi2Status model_check_integer(Fmi2Instance *inst, size_t vr, int value, const char *function) {
    const TwinVariable *v = &motion_variables.variables[vr];
    char given[32];
    snprintf(given, sizeof given, "%d", value);
    return keeps(inst, v, given, value == (int)v->start, function);
}

fmi2Status model_check_string(Fmi2Instance *inst, size_t vr, const char *value, const char *function) {
    const TwinVariable *v = &motion_variables.variables[vr];
    return keeps(inst, v, value, strcmp(value, v->string_start) == 0, function);
}

void model_changed(Fmi2Instance *inst, size_t vr) {
    Generator *g = generator_of(inst);
    if (motion_variables.variables[vr].meaning != MOTION_START || !g->started || g->has_start) return;
    if (inst->reals[vr] >= 0.5) {
        g->has_start = 1, g->started_at = inst->time;
        update(inst, inst->time);
    }
}

void model_states_changed(Fmi2Instance *inst) { (void)inst; }

fmi2Status model_partial_derivative(Fmi2Instance *inst, size_t unknown, size_t known, double *entry,
                                    const char *function) {
    (void)unknown, (void)known, (void)entry;
    return fmi2_fail(inst, "%s: this FMU provides no directional derivatives", function);
}

/* ---------------------------------------------------------------- state */

#define STATE_MAGIC 0x4d4f54494f4eULL /* "MOTION" */

typedef struct {
    long long magic, started, has_start;
    double started_at;
} StateBytes;

size_t model_state_size(const Fmi2Instance *inst) {
    (void)inst;
    return sizeof(StateBytes);
}

void model_save_state(const Fmi2Instance *inst, unsigned char *bytes) {
    const Generator *g = generator_of(inst);
    const StateBytes saved = {(long long)STATE_MAGIC, g->started, g->has_start, g->started_at};
    memcpy(bytes, &saved, sizeof saved);
}

int model_restore_state(Fmi2Instance *inst, const unsigned char *bytes, size_t size) {
    Generator *g = generator_of(inst);
    StateBytes saved;
    if (size != sizeof saved) return -1;
    memcpy(&saved, bytes, sizeof saved);
    if (saved.magic != (long long)STATE_MAGIC || (saved.started != 0 && saved.started != 1)
        || (saved.has_start != 0 && saved.has_start != 1) || !isfinite(saved.started_at))
        return -1;
    g->started = saved.started, g->has_start = saved.has_start, g->started_at = saved.started_at;
    return 0;
}
