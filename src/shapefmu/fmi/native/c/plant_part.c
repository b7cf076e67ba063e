/* The plants' model part: what every generated plant (plant_model.h) does behind the generic layers
 * (fmi2_layer*.c or fmi3_layer*.c over layer_core.c; model.h). Written once, shared by all plants.
 *
 * It lays the plant's variables out in the layer's Real array (value references as plant_model.h
 * says: 0 time, states, derivatives, inputs, outputs, parameters), checks the parameter
 * constraints, computes derivatives and outputs from the generated model part on demand, and
 * steps a Co-Simulation instance: exact zero-order hold for linear plants (the matrix exponential
 * computed in C when the step size or a parameter changes), fixed-substep RK4 otherwise.
 */
#include <math.h>
#include <string.h>

#include "model.h"
#include "plant_expm.h"
#include "plant_model.h"

typedef struct {
    int derived_valid;         /* derivatives and outputs are those of the current x, u, p */
    int jacobians_valid;       /* A, B, C, D are those of the current p (linear) or x, u, p */
    double *A, *B, *C, *D;
    double *work;              /* scratch of the generated CasADi functions */
    /* exact zero-order hold of linear plants: Phi, Gamma for step zoh_step, cached */
    int zoh_valid;
    double zoh_step;
    double *augmented, *exponential, *Phi, *Gamma, *expm_work;
    int *expm_iwork;
    /* RK4 stages of nonlinear plants */
    double *k1, *k2, *k3, *k4, *x_stage, *x_next;
} Plant;

typedef enum { TIME, STATE, DERIVATIVE, INPUT, OUTPUT, PARAMETER, NO_VARIABLE } Role;

/* ---------------------------------------------------------------- layout */

static int nx(void) { return plant_model.n_states; }
static int nu(void) { return plant_model.n_inputs; }
static int ny(void) { return plant_model.n_outputs; }
static int np(void) { return plant_model.n_parameters; }
static size_t off_state(void) { return 1; }
static size_t off_derivative(void) { return 1 + (size_t)nx(); }
static size_t off_input(void) { return 1 + 2 * (size_t)nx(); }
static size_t off_output(void) { return off_input() + (size_t)nu(); }
static size_t off_parameter(void) { return off_output() + (size_t)ny(); }
static size_t n_values(void) { return off_parameter() + (size_t)np(); }

static Role role_of(size_t vr, int *index) {
    if (vr >= n_values()) return NO_VARIABLE;
    if (vr == 0) { *index = 0; return TIME; }
    if (vr < off_derivative()) { *index = (int)(vr - off_state()); return STATE; }
    if (vr < off_input()) { *index = (int)(vr - off_derivative()); return DERIVATIVE; }
    if (vr < off_output()) { *index = (int)(vr - off_input()); return INPUT; }
    if (vr < off_parameter()) { *index = (int)(vr - off_output()); return OUTPUT; }
    *index = (int)(vr - off_parameter());
    return PARAMETER;
}

static void describe(ModelInfo *info) {
    memset(info, 0, sizeof *info);
    info->guid = plant_model.guid;
    info->n_real = n_values();
    info->model_exchange = 1;
    info->n_states = nx();
    info->state_vr = off_state();
    info->derivative_vr = off_derivative();
    info->state_nominal = plant_model.state_nominal;
}

static VariableRole variable(const ModelInstance *inst, ValueType type, size_t vr, const char **name) {
    (void)inst;
    int i = 0;
    const Role role = type == TYPE_REAL ? role_of(vr, &i) : NO_VARIABLE;
    switch (role) {
    case TIME: *name = "time"; return ROLE_COMPUTED;
    case STATE: *name = plant_model.state_names[i]; return ROLE_STATE;
    case DERIVATIVE: *name = "a state derivative"; return ROLE_COMPUTED;
    case INPUT: *name = plant_model.input_names[i]; return ROLE_INPUT;
    case OUTPUT: *name = plant_model.output_names[i]; return ROLE_COMPUTED;
    case PARAMETER:
        *name = plant_model.parameters[i].name;
        return plant_model.parameters[i].tunable ? ROLE_PARAMETER_TUNABLE : ROLE_PARAMETER_FIXED;
    default: return ROLE_NONE;
    }
}

/* ---------------------------------------------------------------- numerics */

static Plant *plant_of(ModelInstance *inst) { return (Plant *)inst->model; }
static double *x_of(ModelInstance *inst) { return inst->reals + off_state(); }
static double *u_of(ModelInstance *inst) { return inst->reals + off_input(); }
static double *p_of(ModelInstance *inst) { return inst->reals + off_parameter(); }

static int all_finite(const double *v, size_t n) {
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i])) return 0;
    return 1;
}

static void invalidate(Plant *plant) {
    plant->derived_valid = 0;
    plant->jacobians_valid = 0;
    plant->zoh_valid = 0;
}

static ModelStatus update(ModelInstance *inst, const char *function) {
    Plant *plant = plant_of(inst);
    inst->reals[0] = inst->time;
    if (plant->derived_valid) return MODEL_OK;
    double *dx = inst->reals + off_derivative(), *y = inst->reals + off_output();
    if (plant_derivatives_outputs(x_of(inst), u_of(inst), p_of(inst), dx, y, plant->work) != 0
        || !all_finite(dx, (size_t)nx()) || !all_finite(y, (size_t)ny()))
        return model_fail(inst, "%s: the model gives non-finite derivatives or outputs at time %g", function, inst->time);
    plant->derived_valid = 1;
    return MODEL_OK;
}

static ModelStatus update_jacobians(ModelInstance *inst, const char *function) {
    Plant *plant = plant_of(inst);
    if (plant->jacobians_valid) return MODEL_OK;
    const size_t n = (size_t)nx(), m = (size_t)nu(), p = (size_t)ny();
    if (plant_jacobians(x_of(inst), u_of(inst), p_of(inst), plant->A, plant->B, plant->C, plant->D, plant->work) != 0
        || !all_finite(plant->A, n * n) || !all_finite(plant->B, n * m) || !all_finite(plant->C, p * n)
        || !all_finite(plant->D, p * m))
        return model_fail(inst, "%s: the parameters give a non-finite Jacobian (state-space matrices)", function);
    /* A linear plant's Jacobians depend on p only: valid until a parameter changes. */
    plant->jacobians_valid = plant_model.linear;
    return MODEL_OK;
}

/* Phi = e^{A h}, Gamma = int_0^h e^{A s} ds B from expm([[A, B], [0, 0]] h) = [[Phi, Gamma], [0, I]]
 * (Van Loan, IEEE TAC 23(3), 1978): the exact zero-order-hold discretisation. */
static ModelStatus update_zoh(ModelInstance *inst, double h, const char *function) {
    Plant *plant = plant_of(inst);
    if (plant->zoh_valid && plant->zoh_step == h) return MODEL_OK;
    if (update_jacobians(inst, function) != MODEL_OK) return MODEL_ERROR;
    const int n = nx(), m = nu(), k = n + m;
    double *M = plant->augmented;
    memset(M, 0, (size_t)k * (size_t)k * sizeof(double));
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) M[(size_t)j * k + i] = plant->A[(size_t)j * n + i] * h;
    for (int j = 0; j < m; j++)
        for (int i = 0; i < n; i++) M[(size_t)(n + j) * k + i] = plant->B[(size_t)j * n + i] * h;
    if (plant_expm(k, M, plant->exponential, plant->expm_work, plant->expm_iwork) != 0)
        return model_fail(inst, "%s: the matrix exponential for step %g failed", function, h);
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) plant->Phi[(size_t)j * n + i] = plant->exponential[(size_t)j * k + i];
    for (int j = 0; j < m; j++)
        for (int i = 0; i < n; i++) plant->Gamma[(size_t)j * n + i] = plant->exponential[(size_t)(n + j) * k + i];
    plant->zoh_step = h;
    plant->zoh_valid = 1;
    model_debug(inst, "%s: zero-order-hold matrices computed for step %g", function, h);
    return MODEL_OK;
}

static ModelStatus step_zoh(ModelInstance *inst, double h, const char *function) {
    if (update_zoh(inst, h, function) != MODEL_OK) return MODEL_ERROR;
    Plant *plant = plant_of(inst);
    const int n = nx(), m = nu();
    double *x = x_of(inst), *next = plant->x_next;
    const double *u = u_of(inst);
    for (int i = 0; i < n; i++) {
        double s = 0.0;
        for (int j = 0; j < n; j++) s += plant->Phi[(size_t)j * n + i] * x[j];
        for (int j = 0; j < m; j++) s += plant->Gamma[(size_t)j * n + i] * u[j];
        next[i] = s;
    }
    memcpy(x, next, (size_t)n * sizeof(double));
    return MODEL_OK;
}

static int rhs(ModelInstance *inst, const double *x, double *dx) {
    /* Outputs are not needed inside a stage: write them to the output slots, recomputed later. */
    return plant_derivatives_outputs(x, u_of(inst), p_of(inst), dx, inst->reals + off_output(), plant_of(inst)->work);
}

/* Classic fourth-order Runge-Kutta with the input held over the step, in equal substeps no longer
 * than the substep parameter. */
static ModelStatus step_rk4(ModelInstance *inst, double t, double h, const char *function) {
    Plant *plant = plant_of(inst);
    const int n = nx();
    const double substep = p_of(inst)[plant_model.substep_parameter];
    const long substeps = plant_substeps(h, substep);
    if (substeps == 0)
        return model_fail(inst, "%s: a step of %g s in RK4 substeps of at most substep = %g s needs more than the "
                         "%ld substeps allowed per step; take shorter steps or a longer substep", function, h, substep,
                         PLANT_MAX_SUBSTEPS);
    const double dt = h / (double)substeps;
    double *x = x_of(inst);
    for (long s = 0; s < substeps; s++) {
        int status = rhs(inst, x, plant->k1);
        for (int i = 0; i < n; i++) plant->x_stage[i] = x[i] + 0.5 * dt * plant->k1[i];
        status |= rhs(inst, plant->x_stage, plant->k2);
        for (int i = 0; i < n; i++) plant->x_stage[i] = x[i] + 0.5 * dt * plant->k2[i];
        status |= rhs(inst, plant->x_stage, plant->k3);
        for (int i = 0; i < n; i++) plant->x_stage[i] = x[i] + dt * plant->k3[i];
        status |= rhs(inst, plant->x_stage, plant->k4);
        for (int i = 0; i < n; i++)
            plant->x_next[i] = x[i] + dt / 6.0 * (plant->k1[i] + 2.0 * plant->k2[i] + 2.0 * plant->k3[i] + plant->k4[i]);
        if (status != 0 || !all_finite(plant->x_next, (size_t)n))
            return model_fail(inst, "%s: the state became non-finite in the substep at time %g", function,
                             t + (double)s * dt);
        memcpy(x, plant->x_next, (size_t)n * sizeof(double));
    }
    return MODEL_OK;
}

static ModelStatus do_step(ModelInstance *inst, double t, double h, const char *function) {
    Plant *plant = plant_of(inst);
    const ModelStatus status = plant_model.linear ? step_zoh(inst, h, function) : step_rk4(inst, t, h, function);
    if (status != MODEL_OK) return status;
    inst->time = t + h;
    plant->derived_valid = 0;
    if (!plant_model.linear) plant->jacobians_valid = 0;
    return update(inst, function);
}

static ModelStatus exit_initialization(ModelInstance *inst, const char *function) {
    if (update_jacobians(inst, function) != MODEL_OK) return MODEL_ERROR;
    return update(inst, function);
}

/* d(unknown)/d(known) from the Jacobians: unknowns are derivatives or outputs, knowns states or inputs. */
static ModelStatus partial_derivative(ModelInstance *inst, size_t unknown, size_t known, double *entry,
                                    const char *function) {
    if (update_jacobians(inst, function) != MODEL_OK) return MODEL_ERROR;
    const Plant *plant = plant_of(inst);
    int r = 0, k = 0;
    const Role ru = role_of(unknown, &r), rk = role_of(known, &k);
    const int n = nx(), p = ny();
    if (ru == DERIVATIVE && rk == STATE) *entry = plant->A[(size_t)k * n + r];
    else if (ru == DERIVATIVE && rk == INPUT) *entry = plant->B[(size_t)k * n + r];
    else if (ru == OUTPUT && rk == STATE) *entry = plant->C[(size_t)k * p + r];
    else if (ru == OUTPUT && rk == INPUT) *entry = plant->D[(size_t)k * p + r];
    else {
        const char *unknown_name = "(no variable)", *known_name = "(no variable)";
        variable(inst, TYPE_REAL, unknown, &unknown_name);
        variable(inst, TYPE_REAL, known, &known_name);
        return model_fail(inst, "%s: unknowns must be state derivatives or outputs and knowns states or inputs, "
                         "got %s with respect to %s", function, unknown_name, known_name);
    }
    return MODEL_OK;
}

/* ---------------------------------------------------------------- values */

static ModelStatus check_real(ModelInstance *inst, size_t vr, double value, const char *function) {
    int i = 0;
    if (role_of(vr, &i) != PARAMETER) {
        if (isfinite(value)) return MODEL_OK;
        const char *name = "?";
        variable(inst, TYPE_REAL, vr, &name);
        return model_fail(inst, "%s: %s must be finite, got %g", function, name, value);
    }
    const PlantParameter *parameter = &plant_model.parameters[i];
    const char *range = NULL;
    switch (parameter->constraint) {
    case PLANT_ANY: if (!isfinite(value)) range = "a finite number"; break;
    case PLANT_POSITIVE: if (!(isfinite(value) && value > 0.0)) range = "> 0"; break;
    case PLANT_NONNEGATIVE: if (!(isfinite(value) && value >= 0.0)) range = ">= 0"; break;
    case PLANT_NONZERO: if (!(isfinite(value) && value != 0.0)) range = "finite and != 0"; break;
    case PLANT_DAMPING_RATIO: if (!(isfinite(value) && value >= 0.0 && value < 1.0)) range = "in [0, 1)"; break;
    }
    if (range != NULL) return model_fail(inst, "%s: parameter %s must be %s, got %g", function, parameter->name, range, value);
    return MODEL_OK;
}

static ModelStatus check_integer(ModelInstance *inst, size_t vr, int value, const char *function) {
    (void)value;
    return model_fail(inst, "%s: a plant has only Real variables (value reference %zu)", function, vr);
}

static ModelStatus check_string(ModelInstance *inst, size_t vr, const char *value, const char *function) {
    (void)value;
    return model_fail(inst, "%s: a plant has only Real variables (value reference %zu)", function, vr);
}

static void changed(ModelInstance *inst, size_t vr) {
    Plant *plant = plant_of(inst);
    int i = 0;
    plant->derived_valid = 0;
    if (role_of(vr, &i) == PARAMETER) invalidate(plant);
    else if (!plant_model.linear) plant->jacobians_valid = 0;
}

static void states_changed(ModelInstance *inst) {
    Plant *plant = plant_of(inst);
    plant->derived_valid = 0;
    if (!plant_model.linear) plant->jacobians_valid = 0;
}

/* The plant's FMU state is its variables (no bytes of its own): the caches are recomputed after a restore. */
static int restore_state(ModelInstance *inst, const unsigned char *bytes, size_t size, const char *function) {
    (void)bytes, (void)function;
    invalidate(plant_of(inst));
    return size == 0 ? 0 : -1;
}

/* ---------------------------------------------------------------- life cycle */

static void reset(ModelInstance *inst) {
    memset(inst->reals, 0, n_values() * sizeof(double));
    memcpy(x_of(inst), plant_model.state_start, (size_t)nx() * sizeof(double));
    memcpy(u_of(inst), plant_model.input_start, (size_t)nu() * sizeof(double));
    for (int i = 0; i < np(); i++) p_of(inst)[i] = plant_model.parameters[i].start;
    invalidate(plant_of(inst));
}

static void free_model(ModelInstance *inst) {
    Plant *plant = plant_of(inst);
    if (plant == NULL) return;
    void *buffers[] = {plant->A, plant->B, plant->C, plant->D, plant->work, plant->augmented, plant->exponential,
                       plant->Phi, plant->Gamma, plant->expm_work, plant->expm_iwork, plant->k1, plant->k2,
                       plant->k3, plant->k4, plant->x_stage, plant->x_next};
    for (size_t i = 0; i < sizeof buffers / sizeof buffers[0]; i++) model_release(inst, buffers[i]);
    model_release(inst, plant);
    inst->model = NULL;
}

static int instantiate(ModelInstance *inst) {
    Plant *plant = model_allocate(inst, 1, sizeof(Plant));
    if (plant == NULL) return -1;
    memset(plant, 0, sizeof *plant);
    inst->model = plant;
    const size_t n = (size_t)nx(), m = (size_t)nu(), p = (size_t)ny(), k = n + m;
    plant->A = model_allocate(inst, n * n, sizeof(double));
    plant->B = model_allocate(inst, n * m, sizeof(double));
    plant->C = model_allocate(inst, p * n, sizeof(double));
    plant->D = model_allocate(inst, p * m, sizeof(double));
    plant->work = model_allocate(inst, plant_model.work_size + 1, sizeof(double));
    plant->x_next = model_allocate(inst, n, sizeof(double));
    int complete = plant->A && plant->B && plant->C && plant->D && plant->work && plant->x_next;
    if (plant_model.linear) {
        plant->augmented = model_allocate(inst, k * k, sizeof(double));
        plant->exponential = model_allocate(inst, k * k, sizeof(double));
        plant->Phi = model_allocate(inst, n * n, sizeof(double));
        plant->Gamma = model_allocate(inst, n * m, sizeof(double));
        plant->expm_work = model_allocate(inst, PLANT_EXPM_WORK(k), sizeof(double));
        plant->expm_iwork = model_allocate(inst, PLANT_EXPM_IWORK(k), sizeof(int));
        complete = complete && plant->augmented && plant->exponential && plant->Phi && plant->Gamma
                   && plant->expm_work && plant->expm_iwork;
    } else {
        plant->k1 = model_allocate(inst, n, sizeof(double));
        plant->k2 = model_allocate(inst, n, sizeof(double));
        plant->k3 = model_allocate(inst, n, sizeof(double));
        plant->k4 = model_allocate(inst, n, sizeof(double));
        plant->x_stage = model_allocate(inst, n, sizeof(double));
        complete = complete && plant->k1 && plant->k2 && plant->k3 && plant->k4 && plant->x_stage;
    }
    if (!complete) return -1;
    return 0;
}

const ModelPart model_part = {
    .describe = describe, .variable = variable, .instantiate = instantiate, .free = free_model, .reset = reset,
    .check_real = check_real, .check_integer = check_integer, .check_string = check_string, .changed = changed,
    .update = update, .exit_initialization = exit_initialization, .do_step = do_step,
    .restore_state = restore_state,
    .states_changed = states_changed, .partial_derivative = partial_derivative,
};
