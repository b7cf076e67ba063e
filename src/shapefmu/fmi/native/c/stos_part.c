/* The native STOS controller (paper 002) behind the generic FMI layers: the C twin of the
 * pythonfmu STOSController, with the same variables and sampled semantics.
 *
 * At the exit of initialisation the switching curves are designed in C (stos_law.c, runtime/stos.py's
 * stos_curves) for the rigid body b, U, damping and the shaper: re-designed by shaper_designs.c
 * from kind, n, n_modes, f[i], zeta[i] when the build's kind is closed-form (zv, zvd, zvdd, zv_dn,
 * mzv), else the build's impulses (stos_model.h), whose design parameters then keep their build
 * values (another value is refused with a message saying to rebuild). Every other parameter (b, U,
 * damping, Ts, the settle law's switch and gains) may change before initialisation, as in the
 * pythonfmu FMU.
 *
 * The law runs once per sample of the absolute grid t0 + k Ts (sample_clock.c) with the inputs in
 * effect at that instant. The output u feeds through: at a communication point it is the law
 * evaluated at the current sample's inputs from the committed state, which it leaves as it was
 * (the pythonfmu FMU's _preview); a step commits the samples.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "sample_clock.h"
#include "shaper_designs.h"
#include "stos_model.h"

#define PI 3.14159265358979323846
/* Impulses of a shaper re-designed in C (the product over the modes of each mode's). */
#define MAX_IMPULSES 4096

typedef struct {
    long long started, dirty, settle_on;
    StosSettle settle;
    StosState state;
    SampleClock clock;
    StosCurves curves;  /* its arrays in storage, designed at the exit of initialisation */
    double *storage;
    size_t vr[STOS_MEANINGS];
} Controller;

static Controller *controller_of(const ModelInstance *inst) { return (Controller *)inst->model; }


static double real_of(const ModelInstance *inst, StosMeaning meaning) {
    return inst->reals[controller_of(inst)->vr[meaning]];
}

/* The inputs of the current sample: latched, or as set now while it is open. */
static void current_inputs(const ModelInstance *inst, double *inputs) {
    const Controller *c = controller_of(inst);
    if (c->clock.latched) {
        memcpy(inputs, c->clock.v, 3 * sizeof(double));
    } else {
        inputs[0] = real_of(inst, STOS_TARGET), inputs[1] = real_of(inst, STOS_POSITION);
        inputs[2] = real_of(inst, STOS_VELOCITY);
    }
}

/* u for the current sample's inputs from the committed state, which stays as it was. */
static void preview(ModelInstance *inst) {
    Controller *c = controller_of(inst);
    double inputs[3];
    current_inputs(inst, inputs);
    StosState scratch = c->state;
    inst->reals[c->vr[STOS_OUTPUT]] = stos_control(&c->curves, c->settle_on ? &c->settle : NULL, &scratch,
                                                   inputs[0], inputs[1], inputs[2]);
    c->dirty = 0;
}

static void commit(void *context, const double *inputs) {
    Controller *c = context;
    stos_control(&c->curves, c->settle_on ? &c->settle : NULL, &c->state, inputs[0], inputs[1], inputs[2]);
}

/* ---------------------------------------------------------------- life cycle */



static void release_curves(ModelInstance *inst) {
    Controller *c = controller_of(inst);
    model_release(inst, c->storage);
    c->storage = NULL;
}

static void reset(ModelInstance *inst) {
    release_curves(inst);
    Controller *c = controller_of(inst);
    c->started = c->dirty = 0;
}

static int instantiate(ModelInstance *inst) {
    Controller *c = model_allocate(inst, 1, sizeof(Controller));
    if (c == NULL) return -1;
    memset(c, 0, sizeof *c);
    inst->model = c;
    twin_index(&stos_variables, c->vr, STOS_MEANINGS);
    return 0;
}

static void free_model(ModelInstance *inst) {
    if (inst->model == NULL) return;
    release_curves(inst);
    model_release(inst, inst->model);
    inst->model = NULL;
}

/* The shaper's impulses (re-designed, or the build's) and the curves for the rigid body now. */
static ModelStatus design(ModelInstance *inst, const char *function) {
    Controller *c = controller_of(inst);
    double omega[STOS_MAX_MODES], zeta[STOS_MAX_MODES];
    int count = stos_shaper.count;
    const double *t = stos_shaper.times, *a = stos_shaper.amplitudes;
    double *work = NULL; /* times, amplitudes and the design's scratch of a re-design */
    if (stos_shaper.closed_form) {
        work = model_allocate(inst, 4 * MAX_IMPULSES, sizeof(double));
        if (work == NULL) return model_fail(inst, "%s: out of memory for the shaper's design", function);
        double *times = work, *amplitudes = work + MAX_IMPULSES, *scratch = work + 2 * MAX_IMPULSES;
        const char *kind = model_string(inst, c->vr[STOS_KIND]);
        const int n = inst->integers[c->vr[STOS_ORDER] - stos_variables.n_real];
        const int n_modes = inst->integers[c->vr[STOS_MODES] - stos_variables.n_real];
        for (int j = 0; j < n_modes; j++) {
            omega[j] = 2.0 * PI * inst->reals[c->vr[STOS_F1 + j]];
            zeta[j] = inst->reals[c->vr[STOS_ZETA1 + j]];
        }
        count = design_closed_form(closed_form_kind(kind), n, n_modes, omega, zeta, times, amplitudes, MAX_IMPULSES,
                                   scratch);
        if (count < 0) {
            model_release(inst, work);
            return model_fail(inst, "%s: kind %s with n = %d for n_modes = %d has more than %d impulses", function, kind,
                             n, n_modes, MAX_IMPULSES);
        }
        t = times, a = amplitudes;
    }
    release_curves(inst);
    c->storage = model_allocate(inst, STOS_CURVE_DOUBLES(count), sizeof(double));
    const char *unsuited = c->storage == NULL ? "out of memory for the switching curves"
                           : stos_design_curves(&c->curves, c->storage, inst->reals[c->vr[STOS_B]],
                                                inst->reals[c->vr[STOS_U]], inst->reals[c->vr[STOS_DAMPING]], t, a, count);
    model_release(inst, work);
    if (unsuited != NULL) return model_fail(inst, "%s: %s", function, unsuited);
    return MODEL_OK;
}

static ModelStatus exit_initialization(ModelInstance *inst, const char *function) {
    Controller *c = controller_of(inst);
    const double ts = real_of(inst, STOS_PERIOD);
    c->settle_on = inst->booleans[c->vr[STOS_SETTLE] - stos_variables.n_real - stos_variables.n_integer];
    if (c->settle_on) {
        const StosSettle s = {real_of(inst, STOS_KP), real_of(inst, STOS_KD), real_of(inst, STOS_KI), ts,
                              real_of(inst, STOS_X_ENTER), real_of(inst, STOS_V_ENTER), real_of(inst, STOS_X_EXIT),
                              real_of(inst, STOS_V_EXIT)};
        const struct { const char *name; double value; int ok; const char *valid; } checks[] = {
            {"kp", s.kp, s.kp > 0.0, "> 0"}, {"kd", s.kd, s.kd > 0.0, "> 0"}, {"ki", s.ki, s.ki >= 0.0, ">= 0"},
            {"x_enter", s.x_enter, s.x_enter > 0.0, "> 0"}, {"v_enter", s.v_enter, s.v_enter > 0.0, "> 0"},
            {"x_exit", s.x_exit, s.x_exit >= s.x_enter, ">= x_enter"}, {"v_exit", s.v_exit, s.v_exit >= s.v_enter, ">= v_enter"}};
        for (size_t i = 0; i < sizeof checks / sizeof checks[0]; i++)
            if (!checks[i].ok)
                return model_fail(inst, "%s: with settle on, %s must be %s, got %g", function, checks[i].name,
                                 checks[i].valid, checks[i].value);
        c->settle = s;
    }
    if (design(inst, function) != MODEL_OK) return MODEL_ERROR;
    c->state.settling = 0.0, c->state.integral = 0.0;
    clock_start(&c->clock, ts);
    c->started = 1;
    preview(inst);
    return MODEL_OK;
}

static ModelStatus update(ModelInstance *inst, const char *function) {
    (void)function;
    Controller *c = controller_of(inst);
    if (c->started && c->dirty) preview(inst);
    return MODEL_OK;
}

static ModelStatus do_step(ModelInstance *inst, double t, double h, const char *function) {
    Controller *c = controller_of(inst);
    const double inputs[3] = {real_of(inst, STOS_TARGET), real_of(inst, STOS_POSITION), real_of(inst, STOS_VELOCITY)};
    if (twin_clock_step(inst, &c->clock, t, h, inputs, 3, commit, c, function) != MODEL_OK) return MODEL_ERROR;
    preview(inst);
    return MODEL_OK;
}

/* ---------------------------------------------------------------- values */

static ModelStatus keeps(ModelInstance *inst, const VariableRow *v, const char *given, int same, const char *function) {
    if (same) return MODEL_OK;
    return twin_refuse(inst, v, given, "shaper is", "shapefmu build stos-controller --native", function);
}

static int shaper_parameter(int meaning) { return meaning >= STOS_KIND && meaning <= STOS_ZETA4; }

static ModelStatus check_real(ModelInstance *inst, size_t vr, double value, const char *function) {
    const VariableRow *v = &stos_variables.rows[vr];
    const int m = v->meaning;
    const char *valid = !isfinite(value) ? "finite"
                        : (m == STOS_PERIOD || m == STOS_B || m == STOS_U || (m >= STOS_F1 && m <= STOS_F4)) && !(value > 0.0) ? "> 0"
                        : m == STOS_DAMPING && !(value >= 0.0) ? ">= 0"
                        : m >= STOS_ZETA1 && m <= STOS_ZETA4 && !(value >= 0.0 && value < 1.0) ? "in [0, 1)" : NULL;
    if (valid != NULL) return model_fail(inst, "%s: %s must be %s, got %g", function, v->name, valid, value);
    if (shaper_parameter(m) && !stos_shaper.closed_form) {
        char given[32];
        snprintf(given, sizeof given, "%.17g", value);
        return keeps(inst, v, given, value == v->start, function);
    }
    return MODEL_OK;
}

static ModelStatus check_integer(ModelInstance *inst, size_t vr, int value, const char *function) {
    const VariableRow *v = &stos_variables.rows[vr];
    if (v->meaning == STOS_ORDER && (value < 0 || value > 62))
        return model_fail(inst, "%s: n must be an integer in [0, 62], got %d", function, value);
    if (v->meaning == STOS_MODES && (value < 1 || value > STOS_MAX_MODES))
        return model_fail(inst, "%s: n_modes must be in [1, %d], got %d", function, STOS_MAX_MODES, value);
    if (!shaper_parameter(v->meaning) || stos_shaper.closed_form) return MODEL_OK; /* settle, a Boolean, too */
    char given[32];
    snprintf(given, sizeof given, "%d", value);
    return keeps(inst, v, given, value == (int)v->start, function);
}

static ModelStatus check_string(ModelInstance *inst, size_t vr, const char *value, const char *function) {
    const VariableRow *v = &stos_variables.rows[vr];
    if (stos_shaper.closed_form && closed_form_kind(value) != KIND_NOT_CLOSED_FORM) return MODEL_OK;
    if (stos_shaper.closed_form)
        return model_fail(inst, "%s: kind must be a kind this FMU designs in C (zv, zvd, zvdd, zv_dn, mzv), got %s; "
                         "other kinds are designed at build time: shapefmu build stos-controller --native --param "
                         "kind=%s", function, value, value);
    return keeps(inst, v, value, strcmp(value, v->string_start) == 0, function);
}

static void changed(ModelInstance *inst, size_t vr) {
    Controller *c = controller_of(inst);
    const StosMeaning meaning = stos_variables.rows[vr].meaning;
    if (meaning == STOS_TARGET || meaning == STOS_POSITION || meaning == STOS_VELOCITY) c->dirty = 1;
}



/* ---------------------------------------------------------------- state: the Controller's plain data */

#define STATE_MAGIC 0x53544f5355ULL /* "STOSU" */

typedef struct {
    long long magic, started, dirty, settle_on;
    StosSettle settle;
    StosState state;
    SampleClock clock;
} StateBytes;

static size_t state_size(const ModelInstance *inst) {
    (void)inst;
    return sizeof(StateBytes);
}

static void save_state(const ModelInstance *inst, unsigned char *bytes) {
    const Controller *c = controller_of(inst);
    StateBytes saved;
    memset(&saved, 0, sizeof saved);
    saved.magic = (long long)STATE_MAGIC, saved.started = c->started, saved.dirty = c->dirty;
    saved.settle_on = c->settle_on, saved.settle = c->settle, saved.state = c->state, saved.clock = c->clock;
    memcpy(bytes, &saved, sizeof saved);
}

static int restore_state(ModelInstance *inst, const unsigned char *bytes, size_t size, const char *function) {
    Controller *c = controller_of(inst);
    StateBytes saved;
    if (size != sizeof saved) return -1;
    memcpy(&saved, bytes, sizeof saved);
    if (saved.magic != (long long)STATE_MAGIC || (saved.started | saved.dirty | saved.settle_on) > 1
        || saved.started < 0 || saved.dirty < 0 || saved.settle_on < 0
        || (saved.state.settling != 0.0 && saved.state.settling != 1.0) || !isfinite(saved.state.integral)
        || (saved.started && !clock_valid(&saved.clock, 3)))
        return -1;
    c->started = saved.started, c->dirty = saved.dirty, c->settle_on = saved.settle_on;
    c->settle = saved.settle, c->state = saved.state, c->clock = saved.clock;
    /* the curves follow from the parameters the layer has just restored */
    if (saved.started && design(inst, function) != MODEL_OK) return -1;
    return 0;
}

const ModelPart model_part = {
    .variables = &stos_variables, .instantiate = instantiate, .free = free_model, .reset = reset,
    .check_real = check_real, .check_integer = check_integer, .check_string = check_string, .changed = changed,
    .update = update, .exit_initialization = exit_initialization, .do_step = do_step,
    .state_size = state_size, .save_state = save_state, .restore_state = restore_state,
};
