/* The contract between the generic FMI layers (FMI 2.0: fmi2_layer*.c, FMI 3.0: fmi3_layer*.c, both
 * over the version-neutral layer_core.c and layer_state.c) and a model part (the plants' plant_part.c,
 * the sampled filters' sampled_part.c, the twins' ekf_tuner_part.c, stos_part.c, motion_part.c,
 * table_part.c, scheduled_part.c and tracked_shaper_part.c), in no version's names.
 *
 * As in the FMI Reference FMUs, a layer owns everything FMI: instances and the host's memory
 * callbacks, the state machine (FMI 2.0.x sections 3.2.3 and 4.2.4; FMI 3.0 section 2.3), logging,
 * get/set dispatch with the causality and variability rules, FMU state get/set/serialise, argument
 * checks and the error state. A model part is one ModelPart (below): its variables and the hooks of
 * its numerics, NULL where the layer's default does what the part needs (the Reference FMUs'
 * config.h flags, as data). It is compiled the same for either FMI version: this header needs no FMI
 * header.
 *
 * Values live in one array per type, owned by the layer and read and written by the model:
 * value references are unique across types, in this order: Real 0 .. n_real-1, then Integer,
 * Boolean and String, each range following the previous one.
 */
#ifndef MODEL_H
#define MODEL_H

#include <stddef.h>

#include "sample_clock.h" /* GridPosition */

/* What a hook and a service return: the values of FMI 2.0's fmi2Status and FMI 3.0's fmi3Status. */
typedef enum { MODEL_OK, MODEL_WARNING, MODEL_DISCARD, MODEL_ERROR, MODEL_FATAL } ModelStatus;

/* Longest String value a variable holds by default (its valid values are names, e.g. a design
 * kind); a model part holding longer text (a signal table) declares its own string_capacity. */
#define MODEL_STRING_CAPACITY 63

typedef enum {
    MODE_INSTANTIATED = 1 << 0,
    MODE_INITIALIZATION = 1 << 1,
    MODE_EVENT = 1 << 2,
    MODE_CONTINUOUS_TIME = 1 << 3,
    MODE_STEP_COMPLETE = 1 << 4,
    MODE_TERMINATED = 1 << 5,
    MODE_ERROR = 1 << 6
} InstanceMode;

/* What may set a variable, and when (the layer enforces it). */
typedef enum {
    ROLE_NONE = 0,
    ROLE_COMPUTED,           /* outputs, derivatives, time, calculated parameters: never set */
    ROLE_STATE,              /* initial="exact" locals: set before initialisation ends */
    ROLE_INPUT,              /* set in any running mode */
    ROLE_PARAMETER_FIXED,    /* set before initialisation ends */
    ROLE_PARAMETER_TUNABLE   /* also in Event Mode / between Co-Simulation steps */
} VariableRole;

typedef enum { TYPE_REAL, TYPE_INTEGER, TYPE_BOOLEAN, TYPE_STRING } ValueType;

typedef struct {
    const char *guid;
    size_t n_real, n_integer, n_boolean, n_string;
    int model_exchange;          /* 1: the FMU also declares Model Exchange */
    int n_states;                /* Model Exchange: continuous states (0 for a Co-Simulation-only FMU) */
    size_t state_vr, derivative_vr; /* value references of the first state and its derivative */
    const double *state_nominal; /* n_states nominal values */
    size_t string_capacity;      /* longest String value; 0: MODEL_STRING_CAPACITY */
} ModelInfo;

typedef struct ModelInstance {
    unsigned long long live_tag;  /* first: fmu_liveness.h reads it through the bare instance pointer */
    ModelInfo info;
    int model_exchange;          /* instantiated for Model Exchange (else Co-Simulation) */
    InstanceMode mode;
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
    int previewing;              /* computing Initialization Mode's outputs (layer_state.c): a refusal is not an error yet */
    /* the layer's: the host's allocator (FMI 2.0) or the C library's (FMI 3.0), the logger that
     * reaches the host, and the layer's own data (its host callbacks, FMI 3.0's variable table) */
    void *(*allocate)(size_t count, size_t size);
    void (*release)(void *pointer);
    void (*emit)(const struct ModelInstance *inst, int error, const char *category, const char *message);
    void *layer;
} ModelInstance;

/* ---- services of the layer to the model part */

/* Log an error, enter the error state, return MODEL_ERROR. */
ModelStatus model_fail(ModelInstance *inst, const char *format, ...);
/* Log a debug message when logging is on. */
void model_debug(const ModelInstance *inst, const char *format, ...);
/* count * size bytes from the host's allocator (NULL for count 0), and back. */
void *model_allocate(ModelInstance *inst, size_t count, size_t size);
void model_release(ModelInstance *inst, void *pointer);
/* The String slot of value reference vr, and the longest value a slot holds. */
char *model_string(ModelInstance *inst, size_t vr);
size_t model_string_capacity(const ModelInstance *inst);
const char *mode_name(InstanceMode mode);

/* ---- the model part */

/* One variable of a part that lists its variables as a table (the twins' generated model.c): its
 * role, its meaning to the part (an enum of the part's) and its start value. */
typedef struct {
    const char *name;
    VariableRole role;
    int meaning;
    double start;              /* Real, Integer and Boolean start values */
    const char *string_start;  /* String start value, else NULL */
} VariableRow;

typedef struct {
    const char *guid;
    size_t n_real, n_integer, n_boolean, n_string;
    const VariableRow *rows;   /* by value reference */
} VariableTable;

/* The hooks a part provides; a NULL one is the layer's default, said beside it. Every hook that
 * refuses logs (model_fail) and returns MODEL_ERROR; `function` names the API call it serves. */
typedef struct {
    /* The part's variables as a table: then describe, variable and the reset of the values to their
     * start values are the layer's. */
    const VariableTable *variables;
    /* The model's sizes and GUID (NULL: from variables). */
    void (*describe)(ModelInfo *info);
    /* Role and name of value reference vr of type type; ROLE_NONE if there is none (NULL: from variables). */
    VariableRole (*variable)(const ModelInstance *inst, ValueType type, size_t vr, const char **name);
    /* Allocate the model's data (inst->model); 0 on success (NULL: it has none). The layer then resets. */
    int (*instantiate)(ModelInstance *inst);
    void (*free)(ModelInstance *inst);                    /* NULL: nothing to free */
    /* Back to the start values (fmi2Reset, fmi3Reset), after the layer reset the table's (NULL: nothing more). */
    void (*reset)(ModelInstance *inst);
    /* Whether value may be stored in vr now. Called for every value of a set call before any is
     * stored, so that a refused call changes nothing (NULL: a Real must be finite; any Integer, String). */
    ModelStatus (*check_real)(ModelInstance *inst, size_t vr, double value, const char *function);
    ModelStatus (*check_integer)(ModelInstance *inst, size_t vr, int value, const char *function);
    ModelStatus (*check_string)(ModelInstance *inst, size_t vr, const char *value, const char *function);
    void (*changed)(ModelInstance *inst, size_t vr);      /* vr's value has changed (NULL: nothing follows) */
    /* Make computed values (outputs, derivatives) current before they are read (NULL: they always are). */
    ModelStatus (*update)(ModelInstance *inst, const char *function);
    ModelStatus (*exit_initialization)(ModelInstance *inst, const char *function);  /* NULL: nothing to do */
    /* Advance from t to t + h (h > 0); the layer then sets inst->time = t + h. */
    ModelStatus (*do_step)(ModelInstance *inst, double t, double h, const char *function);
    /* Bytes of model data an FMU state holds besides the value arrays, their copy and their restore
     * (0, or -1 if the bytes are not a state of this model) (NULL: none). */
    size_t (*state_size)(const ModelInstance *inst);
    void (*save_state)(const ModelInstance *inst, unsigned char *bytes);
    int (*restore_state)(ModelInstance *inst, const unsigned char *bytes, size_t size, const char *function);
    /* Model Exchange: the continuous states were set (NULL: nothing follows). */
    void (*states_changed)(ModelInstance *inst);
    /* d(unknown)/d(known) of the linearisation (NULL: the FMU provides no directional derivatives). */
    ModelStatus (*partial_derivative)(ModelInstance *inst, size_t unknown, size_t known, double *entry,
                                      const char *function);
} ModelPart;

/* The one model part of an FMU (defined by the part). */
extern const ModelPart model_part;

#endif
