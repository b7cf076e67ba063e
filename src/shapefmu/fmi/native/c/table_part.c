/* The native reference player behind the generic FMI layers: the C twin of the pythonfmu
 * ReferencePlayer, runtime/reference_player.py's SignalTable operation for operation.
 *
 * Variables (value references): Real 0 y, the table's value at the communication point (right-
 * continuous at switches), Real 1 y_mean, its exact mean over the last step; String 2 table, the
 * JSON text the table was parsed from at build time, which keeps its build value (another one is
 * refused with a message saying to rebuild). No inputs: outputs change only in a step.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "table_model.h"

enum { VR_Y, VR_Y_MEAN, VR_TABLE, VARIABLES };

/* The first index whose time is >= t (left) or > t (right), as Python's bisect. */
static size_t bisect(double t, int right) {
    size_t low = 0, high = table_model.n_times;
    while (low < high) {
        const size_t mid = low + (high - low) / 2;
        if (right ? table_model.times[mid] <= t : table_model.times[mid] < t) low = mid + 1;
        else high = mid;
    }
    return low;
}

/* t, or the table time it lies within rounding of. */
static double snap(double t) {
    const size_t j = bisect(t, 0);
    if (j >= 1 && fabs(table_model.times[j - 1] - t) <= table_model.tolerance) return table_model.times[j - 1];
    if (j < table_model.n_times && fabs(table_model.times[j] - t) <= table_model.tolerance) return table_model.times[j];
    return t;
}

/* j with times[j] <= t < times[j + 1]: -1 before the table, the last index after it. */
static long segment(double t) { return (long)bisect(t, 1) - 1; }

static double value(double t) {
    t = snap(t);
    const long j = segment(t);
    if (j < 0) return table_model.before;
    const double *times = table_model.times, *left = table_model.left, *right = table_model.right;
    if ((size_t)j == table_model.n_times - 1 || table_model.hold) return right[j];
    const double fraction = (t - times[j]) / (times[j + 1] - times[j]);
    return right[j] + (left[j + 1] - right[j]) * fraction;
}

static double integral(double t) {
    t = snap(t);
    const long j = segment(t);
    const double *times = table_model.times, *left = table_model.left, *right = table_model.right;
    if (j < 0) return (t - times[0]) * table_model.before;
    const double s = t - times[j];
    if ((size_t)j == table_model.n_times - 1 || table_model.hold) return table_model.integral[j] + s * right[j];
    const double slope = (left[j + 1] - right[j]) / (times[j + 1] - times[j]);
    return table_model.integral[j] + s * right[j] + 0.5 * slope * s * s;
}

/* As SignalTable.average: one segment's own mean, else the part inside the table by its integral and
 * the parts before and after it by their share of the step (finite for any finite step). */
static double average(double t_start, double t_end) {
    const double a = snap(t_start), b = snap(t_end);
    if (b == a) return value(a);
    const long j = segment(a);
    const size_t n = table_model.n_times;
    if (j == segment(b)) {
        if (j < 0) return table_model.before;
        if ((size_t)j == n - 1 || table_model.hold) return table_model.right[j];
        return 0.5 * (value(a) + value(b));
    }
    const double first = fmax(a, table_model.times[0]), last = fmin(b, table_model.times[n - 1]), width = b - a;
    return (integral(last) - integral(first)) / width + (first - a) / width * table_model.before
           + (b - last) / width * table_model.right[n - 1];
}

/* ---------------------------------------------------------------- the table's text, in pieces */

static size_t text_length(void) {
    size_t length = 0;
    for (size_t i = 0; i < table_model.n_text_pieces; i++) length += strlen(table_model.table_text[i]);
    return length;
}

static void copy_text(char *to) {
    for (size_t i = 0; i < table_model.n_text_pieces; i++) {
        const size_t length = strlen(table_model.table_text[i]);
        memcpy(to, table_model.table_text[i], length);
        to += length;
    }
    *to = '\0';
}

static int is_text(const char *text) {
    for (size_t i = 0; i < table_model.n_text_pieces; i++) {
        const size_t length = strlen(table_model.table_text[i]);
        if (strncmp(text, table_model.table_text[i], length) != 0) return 0;
        text += length;
    }
    return *text == '\0';
}

/* ---------------------------------------------------------------- the part's hooks */

static void describe(ModelInfo *info) {
    info->guid = table_model.guid;
    info->n_real = 2;
    info->n_string = 1;
    const size_t length = text_length();
    info->string_capacity = length > MODEL_STRING_CAPACITY ? length : MODEL_STRING_CAPACITY;
}

static VariableRole variable(const ModelInstance *inst, ValueType type, size_t vr, const char **name) {
    static const char *const names[] = {"y", "y_mean", "table"};
    (void)inst, (void)type;
    if (vr >= VARIABLES) return ROLE_NONE;
    *name = names[vr];
    return vr == VR_TABLE ? ROLE_PARAMETER_FIXED : ROLE_COMPUTED;
}

static void reset(ModelInstance *inst) {
    inst->reals[VR_Y] = inst->reals[VR_Y_MEAN] = 0.0;
    copy_text(model_string(inst, VR_TABLE));
}

static ModelStatus exit_initialization(ModelInstance *inst, const char *function) {
    (void)function;
    inst->reals[VR_Y] = inst->reals[VR_Y_MEAN] = value(inst->start_time);
    return MODEL_OK;
}

static ModelStatus do_step(ModelInstance *inst, double t, double h, const char *function) {
    if (!isfinite(t + h))
        return model_fail(inst, "%s: t + h = %g + %g overflows; the step's end must be a finite time", function, t, h);
    inst->reals[VR_Y] = value(t + h);
    inst->reals[VR_Y_MEAN] = average(t, t + h);
    return MODEL_OK;
}

static ModelStatus check_string(ModelInstance *inst, size_t vr, const char *text, const char *function) {
    (void)vr;
    if (is_text(text)) return MODEL_OK;
    return model_fail(inst, "%s: table is the signal table this native FMU was built with (parsed at build time); got "
                     "another one of %zu characters (rebuild it with shapefmu build reference TABLE --native for it)",
                     function, strlen(text));
}

/* The outputs are values the layer saves and checks finite (the default); the table is constant: no
 * state of its own, no other check. */
const ModelPart model_part = {
    .describe = describe, .variable = variable, .reset = reset,
    .check_string = check_string,
    .exit_initialization = exit_initialization, .do_step = do_step,
};
