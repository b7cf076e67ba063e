/* The contract between the generic FMI layers (FMI 2.0: fmi2_layer*.c, FMI 3.0: fmi3_layer*.c, both
 * over the version-neutral layer_core.c and layer_state.c) and a model part (the plant's plant_fmi2.c,
 * the sampled filters' sampled_fmi2.c, the twins' *_fmi2.c; the names keep the FMI 2.0 spelling the
 * contract was first written in).
 *
 * As in the FMI Reference FMUs, a layer owns everything FMI: instances and the host's memory
 * callbacks, the state machine (FMI 2.0.x sections 3.2.3 and 4.2.4; FMI 3.0 section 2.3), logging,
 * get/set dispatch with the causality and variability rules, FMU state get/set/serialise, argument
 * checks and the error state. A model part describes its variables and does its numerics through the
 * hooks below, and is compiled the same for either FMI version: this header needs no FMI header.
 *
 * Values live in one array per type, owned by the layer and read and written by the model:
 * value references are unique across types, in this order: Real 0 .. n_real-1, then Integer,
 * Boolean and String, each range following the previous one.
 */
#ifndef FMI2_MODEL_H
#define FMI2_MODEL_H

#include <stddef.h>

#include "model_status.h"
#include "sample_clock.h" /* GridPosition */

/* Longest String value a variable holds by default (its valid values are names, e.g. a design
 * kind); a model part holding longer text (a signal table) declares its own string_capacity. */
#define FMI2_STRING_CAPACITY 63

typedef enum {
    FMI2_INSTANTIATED = 1 << 0,
    FMI2_INITIALIZATION = 1 << 1,
    FMI2_EVENT_MODE = 1 << 2,
    FMI2_CONTINUOUS_TIME = 1 << 3,
    FMI2_STEP_COMPLETE = 1 << 4,
    FMI2_TERMINATED = 1 << 5,
    FMI2_ERROR_STATE = 1 << 6
} Fmi2Mode;

/* What may set a variable, and when (the layer enforces it). */
typedef enum {
    FMI2_NO_VARIABLE = 0,
    FMI2_COMPUTED,           /* outputs, derivatives, time, calculated parameters: never set */
    FMI2_STATE,              /* initial="exact" locals: set before initialisation ends */
    FMI2_INPUT,              /* set in any running mode */
    FMI2_PARAMETER_FIXED,    /* set before initialisation ends */
    FMI2_PARAMETER_TUNABLE   /* also in Event Mode / between Co-Simulation steps */
} Fmi2Role;

typedef enum { FMI2_REAL, FMI2_INTEGER, FMI2_BOOLEAN, FMI2_STRING } Fmi2Type;

typedef struct {
    const char *guid;
    size_t n_real, n_integer, n_boolean, n_string;
    int model_exchange;          /* 1: the FMU also declares Model Exchange */
    int n_states;                /* Model Exchange: continuous states (0 for a Co-Simulation-only FMU) */
    size_t state_vr, derivative_vr; /* value references of the first state and its derivative */
    const double *state_nominal; /* n_states nominal values */
    size_t string_capacity;      /* longest String value; 0: FMI2_STRING_CAPACITY */
} Fmi2ModelInfo;

typedef struct Fmi2Instance {
    unsigned long long live_tag;  /* first: fmu_liveness.h reads it through the bare instance pointer */
    Fmi2ModelInfo info;
    int model_exchange;          /* instantiated for Model Exchange (else Co-Simulation) */
    Fmi2Mode mode;
    char *name;
    int logging_on;
    double time;                 /* the FMU's time: start time, then the end of the last step */
    double start_time;           /* fmi2SetupExperiment's startTime (0 if not called) */
    double clock_ticks;          /* ticks of the FMI 3.0 layer's input clock taken (--clock builds) */
    GridPosition clock_position; /* and where the instance stands on the clock's grid, counted from its steps */
    double *reals;               /* every variable's value, indexed by value reference */
    int *integers, *booleans;
    char *strings;               /* n_string slots of info.string_capacity + 1 characters */
    void *model;                 /* the model part's own data */
    /* the layer's: the host's allocator (FMI 2.0) or the C library's (FMI 3.0), the logger that
     * reaches the host, and the layer's own data (its host callbacks, FMI 3.0's variable table) */
    void *(*allocate)(size_t count, size_t size);
    void (*release)(void *pointer);
    void (*emit)(const struct Fmi2Instance *inst, int error, const char *category, const char *message);
    void *layer;
} Fmi2Instance;

/* ---- services of the layer to the model part */

/* Log an error, enter the error state, return fmi2Error. */
fmi2Status fmi2_fail(Fmi2Instance *inst, const char *format, ...);
/* Log a debug message when logging is on. */
void fmi2_debug(const Fmi2Instance *inst, const char *format, ...);
/* count * size bytes from the host's allocator (NULL for count 0), and back. */
void *fmi2_allocate(Fmi2Instance *inst, size_t count, size_t size);
void fmi2_release(Fmi2Instance *inst, void *pointer);
/* The String slot of value reference vr, and the longest value a slot holds. */
char *fmi2_string(Fmi2Instance *inst, size_t vr);
size_t fmi2_string_capacity(const Fmi2Instance *inst);
const char *fmi2_mode_name(Fmi2Mode mode);

/* ---- hooks the model part implements */

void model_describe(Fmi2ModelInfo *info);
/* Allocate the model's data (inst->model) and set the start values; 0 on success. */
int model_instantiate(Fmi2Instance *inst);
void model_free(Fmi2Instance *inst);
/* Back to the start values (fmi2Reset). */
void model_reset(Fmi2Instance *inst);
/* Role and name of value reference vr of type type; FMI2_NO_VARIABLE if there is none. */
Fmi2Role model_variable(const Fmi2Instance *inst, Fmi2Type type, size_t vr, const char **name);
/* Whether value may be stored in vr now; logs (fmi2_fail) and returns fmi2Error if not. Called
 * for every value of a set call before any is stored, so that a refused call changes nothing. */
fmi2Status model_check_real(Fmi2Instance *inst, size_t vr, double value, const char *function);
fmi2Status model_check_integer(Fmi2Instance *inst, size_t vr, int value, const char *function);
fmi2Status model_check_string(Fmi2Instance *inst, size_t vr, const char *value, const char *function);
/* vr's value has changed (after it was stored). */
void model_changed(Fmi2Instance *inst, size_t vr);
/* Make computed values (outputs, derivatives) current before they are read. */
fmi2Status model_update(Fmi2Instance *inst, const char *function);
fmi2Status model_exit_initialization(Fmi2Instance *inst);
/* Advance from t to t + h (h > 0); the layer then sets inst->time = t + h. */
fmi2Status model_do_step(Fmi2Instance *inst, double t, double h);
/* Bytes of model data an FMU state holds besides the value arrays, and their copy and restore
 * (restore returns 0, or -1 if the bytes are not a state of this model). */
size_t model_state_size(const Fmi2Instance *inst);
void model_save_state(const Fmi2Instance *inst, unsigned char *bytes);
int model_restore_state(Fmi2Instance *inst, const unsigned char *bytes, size_t size);
/* Model Exchange: the states were set (fmi2SetContinuousStates). */
void model_states_changed(Fmi2Instance *inst);
/* d(unknown)/d(known) of the linearisation; logs and returns fmi2Error if not provided. */
fmi2Status model_partial_derivative(Fmi2Instance *inst, size_t unknown, size_t known, double *entry,
                                    const char *function);

#endif
