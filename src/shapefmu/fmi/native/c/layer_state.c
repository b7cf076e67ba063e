/* FMU states of the generic FMI layers (layer_core.h; FMI 2.0 and FMI 3.0 alike): get, set, free,
 * serialise and deserialise.
 *
 * A state is everything needed to resume exactly: the mode, the time, every variable's value and
 * the model part's own data (model_save_state: a filter's delay line, its sample clock). A state
 * carries the identity of the FMU that made it (a hash of its GUID, which names its build and design,
 * and its variable counts), in memory and in its serialised header: a state of another FMU, bytes
 * that are no state, or a truncated copy are refused with a logged error. The values a state would
 * restore pass the same checks as values set one by one (model_check_*), so a forged state cannot
 * bring in what fmi2SetReal would refuse (a NaN impulse time, a negative period).
 */
#include <math.h>
#include <string.h>

#include "layer_core.h"

#define SERIAL_MAGIC 0x73686170464d5532ULL   /* "shapFMU2" */
#define SNAPSHOT_MAGIC 0x7368617053746174ULL /* "shapStat" */

typedef struct {
    unsigned long long magic, identity;
    InstanceMode mode;
    double time, start_time, clock_ticks;
    GridPosition clock_position;
    double *reals;
    int *integers, *booleans;
    char *strings;
    unsigned char *model;
    size_t model_size;
} Snapshot;

static size_t string_bytes(const ModelInstance *inst) { return inst->info.n_string * (inst->info.string_capacity + 1); }

/* FNV-1a of this FMU's GUID and variable counts: the same for every instance of one FMU build. */
static unsigned long long identity(const ModelInstance *inst) {
    const ModelInfo *info = &inst->info;
    unsigned long long hash = 14695981039346656037ULL;
    for (const unsigned char *c = (const unsigned char *)info->guid; *c != '\0'; c++) hash = (hash ^ *c) * 1099511628211ULL;
    const size_t counts[4] = {info->n_real, info->n_integer, info->n_boolean, info->n_string};
    for (int i = 0; i < 4; i++) hash = (hash ^ (unsigned long long)counts[i]) * 1099511628211ULL;
    return hash;
}

/* Whether state is a snapshot this FMU made (a state of another FMU, or a pointer that is no state,
 * is refused rather than read). */
static int ours(const ModelInstance *inst, const void *state) {
    const Snapshot *s = state;
    return s->magic == SNAPSHOT_MAGIC && s->identity == identity(inst);
}

/* Whether every value of s passes the model's checks of a set call (see the file comment). */
static ModelStatus check_values(ModelInstance *inst, const Snapshot *s, const char *function) {
    const ModelInfo *info = &inst->info;
    const char *name;
    /* the clock's ticks are at most those its position has reached; its period is checked by the FMI 3.0 layer */
    if (!isfinite(s->time) || !isfinite(s->start_time) || !(s->clock_ticks >= 0.0 && s->clock_ticks <= 9e15)
        || s->clock_ticks != floor(s->clock_ticks) || !grid_valid(&s->clock_position, INFINITY)
        || s->clock_ticks > (double)s->clock_position.k + 1.0)
        return model_fail(inst, "%s: the state's time or clock tick count is not valid", function);
    for (size_t vr = 0; vr < info->n_real; vr++)
        if (model_variable(inst, TYPE_REAL, vr, &name) != ROLE_NONE
            && model_check_real(inst, vr, s->reals[vr], function) != MODEL_OK)
            return MODEL_ERROR;
    /* Value references run on across the types (fmi2_layer.c, type_range): Integer ones after the Reals. */
    for (size_t i = 0, vr = info->n_real; i < info->n_integer; i++, vr++)
        if (model_variable(inst, TYPE_INTEGER, vr, &name) != ROLE_NONE
            && model_check_integer(inst, vr, s->integers[i], function) != MODEL_OK)
            return MODEL_ERROR;
    for (size_t i = 0, vr = info->n_real + info->n_integer + info->n_boolean; i < info->n_string; i++, vr++)
        if (model_variable(inst, TYPE_STRING, vr, &name) != ROLE_NONE
            && model_check_string(inst, vr, s->strings + i * (inst->info.string_capacity + 1), function) != MODEL_OK)
            return MODEL_ERROR;
    return MODEL_OK;
}

static void free_snapshot(ModelInstance *inst, Snapshot *s) {
    void *buffers[] = {s->reals, s->integers, s->booleans, s->strings, s->model};
    for (size_t i = 0; i < sizeof buffers / sizeof buffers[0]; i++) model_release(inst, buffers[i]);
    inst->release(s);
}

/* A snapshot with room for the value arrays and model_size bytes of model data. */
static Snapshot *new_snapshot(ModelInstance *inst, size_t model_size) {
    Snapshot *s = model_allocate(inst, 1, sizeof(Snapshot));
    if (s == NULL) return NULL;
    memset(s, 0, sizeof *s);
    s->magic = SNAPSHOT_MAGIC;
    s->identity = identity(inst);
    const ModelInfo *info = &inst->info;
    s->reals = model_allocate(inst, info->n_real, sizeof(double));
    s->integers = model_allocate(inst, info->n_integer, sizeof(int));
    s->booleans = model_allocate(inst, info->n_boolean, sizeof(int));
    s->strings = model_allocate(inst, string_bytes(inst), 1);
    s->model = model_allocate(inst, model_size, 1);
    s->model_size = model_size;
    if ((info->n_real && !s->reals) || (info->n_integer && !s->integers) || (info->n_boolean && !s->booleans)
        || (info->n_string && !s->strings) || (model_size && !s->model)) {
        free_snapshot(inst, s);
        return NULL;
    }
    return s;
}

/* A snapshot to write into: *FMUstate if it has the right size, else a new one (the old freed). */
static Snapshot *writable(ModelInstance *inst, void **FMUstate, size_t model_size) {
    Snapshot *s = *FMUstate;
    if (s != NULL && s->model_size == model_size) return s;
    if (s != NULL) free_snapshot(inst, s);
    *FMUstate = NULL;
    return new_snapshot(inst, model_size);
}

static void copy_values(const ModelInstance *inst, double *reals, int *integers, int *booleans, char *strings,
                        const double *from_reals, const int *from_integers, const int *from_booleans,
                        const char *from_strings) {
    const ModelInfo *info = &inst->info;
    if (info->n_real) memcpy(reals, from_reals, info->n_real * sizeof(double));
    if (info->n_integer) memcpy(integers, from_integers, info->n_integer * sizeof(int));
    if (info->n_boolean) memcpy(booleans, from_booleans, info->n_boolean * sizeof(int));
    if (info->n_string) memcpy(strings, from_strings, string_bytes(inst));
}

ModelStatus core_get_state(ModelInstance *inst, void **FMUstate, const char *function) {
    if (FMUstate == NULL) return model_fail(inst, "%s: FMUstate is NULL", function);
    if (*FMUstate != NULL && !ours(inst, *FMUstate))
        return model_fail(inst, "%s: *FMUstate is neither NULL nor a state of this FMU", function);
    Snapshot *s = writable(inst, FMUstate, model_state_size(inst));
    if (s == NULL) return model_fail(inst, "%s: out of memory", function);
    s->mode = inst->mode;
    s->time = inst->time;
    s->start_time = inst->start_time;
    s->clock_ticks = inst->clock_ticks;
    s->clock_position = inst->clock_position;
    copy_values(inst, s->reals, s->integers, s->booleans, s->strings, inst->reals, inst->integers, inst->booleans,
                inst->strings);
    model_save_state(inst, s->model);
    *FMUstate = s;
    return MODEL_OK;
}

/* Back to snapshot s, whose values are known to be valid. */
static ModelStatus restore(ModelInstance *inst, const Snapshot *s, const char *function) {
    copy_values(inst, inst->reals, inst->integers, inst->booleans, inst->strings, s->reals, s->integers, s->booleans,
                s->strings);
    inst->time = s->time;
    inst->start_time = s->start_time;
    inst->clock_ticks = s->clock_ticks;
    inst->clock_position = s->clock_position;
    inst->mode = s->mode;
    if (model_restore_state(inst, s->model, s->model_size, function) != 0)
        return model_fail(inst, "%s: the state does not fit this instance's model data", function);
    return MODEL_OK;
}

ModelStatus core_set_state(ModelInstance *inst, const void *FMUstate, const char *function) {
    if (FMUstate == NULL) return model_fail(inst, "%s: FMUstate is NULL", function);
    const Snapshot *s = FMUstate;
    if (!ours(inst, s))
        return model_fail(inst, "%s: the state is not one of this FMU (another FMU's, or no state at all)", function);
    if (check_values(inst, s, function) != MODEL_OK) return MODEL_ERROR;
    return restore(inst, s, function);
}

ModelStatus core_free_state(ModelInstance *inst, void **FMUstate, const char *function) {
    if (FMUstate == NULL || *FMUstate == NULL) return MODEL_OK;
    const Snapshot *s = *FMUstate;
    if (!ours(inst, s))
        return model_fail(inst, "%s: the state is not one of this FMU (another FMU's, or no state at all)", function);
    free_snapshot(inst, *FMUstate);
    *FMUstate = NULL;
    return MODEL_OK;
}

/* Serialised layout: a header of 8 uint64 (magic, identity, the four counts, mode, model bytes), the
 * time, the start time and the clock ticks, the clock's position, then the Real, Integer, Boolean and
 * String values and the model bytes. */
enum { HEADER_WORDS = 8 };

static size_t serial_size(const ModelInstance *inst, size_t model_size) {
    const ModelInfo *info = &inst->info;
    return HEADER_WORDS * sizeof(unsigned long long) + (3 + info->n_real) * sizeof(double) + sizeof(GridPosition)
           + (info->n_integer + info->n_boolean) * sizeof(int) + string_bytes(inst) + model_size;
}

ModelStatus core_serialized_size(ModelInstance *inst, const void *FMUstate, size_t *size, const char *function) {
    if (FMUstate == NULL || size == NULL) return model_fail(inst, "%s: NULL FMUstate or size", function);
    if (!ours(inst, FMUstate)) return model_fail(inst, "%s: the state is not one of this FMU", function);
    *size = serial_size(inst, ((const Snapshot *)FMUstate)->model_size);
    return MODEL_OK;
}

static unsigned char *put(unsigned char *to, const void *from, size_t bytes) {
    if (bytes) memcpy(to, from, bytes);
    return to + bytes;
}

static const unsigned char *take(void *to, const unsigned char *from, size_t bytes) {
    if (bytes) memcpy(to, from, bytes);
    return from + bytes;
}

ModelStatus core_serialize(ModelInstance *inst, const void *FMUstate, unsigned char serializedState[], size_t size,
                          const char *function) {
    if (FMUstate == NULL || serializedState == NULL)
        return model_fail(inst, "%s: NULL FMUstate or buffer", function);
    const Snapshot *s = FMUstate;
    if (!ours(inst, s)) return model_fail(inst, "%s: the state is not one of this FMU", function);
    if (size != serial_size(inst, s->model_size))
        return model_fail(inst, "%s: buffer holds %zu bytes, the state needs %zu", function, size,
                         serial_size(inst, s->model_size));
    const ModelInfo *info = &inst->info;
    const unsigned long long header[HEADER_WORDS] = {SERIAL_MAGIC, identity(inst), info->n_real, info->n_integer,
                                                     info->n_boolean, info->n_string, (unsigned long long)s->mode,
                                                     s->model_size};
    const double times[3] = {s->time, s->start_time, s->clock_ticks};
    unsigned char *p = put((unsigned char *)serializedState, header, sizeof header);
    p = put(p, times, sizeof times);
    p = put(p, &s->clock_position, sizeof s->clock_position);
    p = put(p, s->reals, info->n_real * sizeof(double));
    p = put(p, s->integers, info->n_integer * sizeof(int));
    p = put(p, s->booleans, info->n_boolean * sizeof(int));
    p = put(p, s->strings, string_bytes(inst));
    put(p, s->model, s->model_size);
    return MODEL_OK;
}

ModelStatus core_deserialize(ModelInstance *inst, const unsigned char serializedState[], size_t size, void **FMUstate,
                            const char *function) {
    if (serializedState == NULL || FMUstate == NULL)
        return model_fail(inst, "%s: NULL buffer or FMUstate", function);
    if (*FMUstate != NULL && !ours(inst, *FMUstate))
        return model_fail(inst, "%s: *FMUstate is neither NULL nor a state of this FMU", function);
    unsigned long long header[HEADER_WORDS];
    if (size < sizeof header)
        return model_fail(inst, "%s: got %zu bytes, fewer than a state's header", function, size);
    const unsigned char *p = take(header, (const unsigned char *)serializedState, sizeof header);
    const ModelInfo *info = &inst->info;
    const int mode_ok = header[6] != 0 && (header[6] & ~(unsigned long long)ANY_MODE) == 0;
    if (header[0] != SERIAL_MAGIC || header[1] != identity(inst) || header[2] != info->n_real
        || header[3] != info->n_integer || header[4] != info->n_boolean || header[5] != info->n_string || !mode_ok
        || header[7] > size)
        return model_fail(inst, "%s: the bytes are not a serialised state of this FMU", function);
    const size_t model_size = (size_t)header[7];
    if (size != serial_size(inst, model_size))
        return model_fail(inst, "%s: got %zu bytes, a state of this FMU has %zu", function, size,
                         serial_size(inst, model_size));
    Snapshot *s = writable(inst, FMUstate, model_size);
    if (s == NULL) return model_fail(inst, "%s: out of memory", function);
    double times[3];
    s->mode = (InstanceMode)header[6];
    p = take(times, p, sizeof times);
    s->time = times[0];
    s->start_time = times[1];
    s->clock_ticks = times[2];
    p = take(&s->clock_position, p, sizeof s->clock_position);
    p = take(s->reals, p, info->n_real * sizeof(double));
    p = take(s->integers, p, info->n_integer * sizeof(int));
    p = take(s->booleans, p, info->n_boolean * sizeof(int));
    p = take(s->strings, p, string_bytes(inst));
    take(s->model, p, model_size);
    /* Strings are read back as C strings: make every slot end inside itself. */
    for (size_t i = 0; i < info->n_string; i++) s->strings[i * (inst->info.string_capacity + 1) + inst->info.string_capacity] = '\0';
    *FMUstate = s;
    return MODEL_OK;
}

/* ---------------------------------------------------------------- Initialization Mode's outputs */

/* The computed values of snapshot made into the instance, every other value left. */
static void keep_computed(ModelInstance *inst, const Snapshot *made) {
    const ValueType types[3] = {TYPE_REAL, TYPE_INTEGER, TYPE_BOOLEAN};
    const int *made_integers[3] = {NULL, made->integers, made->booleans};
    for (int t = 0; t < 3; t++) {
        size_t first, count;
        core_type_range(inst, types[t], &first, &count);
        for (size_t vr = first; vr < first + count; vr++) {
            const char *name;
            if (model_variable(inst, types[t], vr, &name) != ROLE_COMPUTED) continue;
            if (types[t] == TYPE_REAL) inst->reals[vr] = made->reals[vr];
            else core_integer_values(inst, types[t])[vr - first] = made_integers[t][vr - first];
        }
    }
}

/* FMI 2.0 (section 2.2.7, initial="calculated") and FMI 3.0 (its Initialization Mode, section 2.3) let a
 * host get a computed variable in Initialization Mode, computed from the parameters and inputs set so
 * far; a master propagating values before the first step passes them on. They are what the exit of
 * initialisation makes them: the instance is saved, the model part's exit run, its computed values kept
 * and the rest restored, so the exit still starts the run and a later set still changes what the next
 * get gives. Parameters the exit would refuse leave the computed values at their start values, with a
 * debug message only: the refusal, logged as an error, stays at the exit, where a host expects it and
 * where parameters set one at a time are complete. */
ModelStatus core_preview_initialization(ModelInstance *inst, const char *function) {
    if (inst->mode != MODE_INITIALIZATION || model_part.exit_initialization == NULL) return MODEL_OK;
    void *before = NULL;
    if (core_get_state(inst, &before, function) != MODEL_OK) return MODEL_ERROR;
    Snapshot *made = new_snapshot(inst, 0);
    if (made == NULL) {
        core_free_state(inst, &before, function);
        return model_fail(inst, "%s: out of memory", function);
    }
    inst->previewing = 1;
    if (model_part.exit_initialization(inst, function) != MODEL_OK) model_reset(inst);
    inst->previewing = 0;
    copy_values(inst, made->reals, made->integers, made->booleans, made->strings, inst->reals, inst->integers,
                inst->booleans, inst->strings);
    const ModelStatus status = restore(inst, before, function);
    core_free_state(inst, &before, function);
    if (status == MODEL_OK) keep_computed(inst, made);
    free_snapshot(inst, made);
    return status;
}
