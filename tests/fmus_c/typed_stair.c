/* TypedStair: a small FMI 2.0 Model Exchange + Co-Simulation FMU for the master's tests, with a
 * variable of every FMI 2.0 type and a termination request at a parameterised time.
 *
 * Behaviour (closed forms the tests compare against; see tests/support/c_fmus.py for the variables):
 *   counter = sign(mode) * increment * floor(t / period)       Integer output, steps at t = j period
 *   level   = integral of x_in dt                              Real state (der(level) = x_in)
 *   x_out   = x_in + counter                                   Real, feeds through x_in
 *   n_out   = 2 n_in + counter                                 Integer, feeds through n_in
 *   e_out   = 3 - e_in (up <-> down)                           Enumeration Direction, feeds through e_in
 *   b_out   = b_in xor negate                                  Boolean, feeds through b_in
 *   s_out   = label ":" s_in                                   String, feeds through s_in
 *   r_out   = r_in + counter                                   Real discrete, feeds through r_in
 *   steps, provisional_steps: Co-Simulation steps taken, and those with noSetFMUStatePriorToCurrentPoint false
 * At t = stop_at the FMU asks to end the simulation, as the FMI Reference FMU "Stair" does at 9 s:
 * in Co-Simulation fmi2DoStep stops there and returns fmi2Discard, fmi2GetBooleanStatus(fmi2Terminated)
 * is then true and fmi2GetRealStatus(fmi2LastSuccessfulTime) is stop_at; in Model Exchange stop_at is
 * a time event whose fmi2NewDiscreteStates sets terminateSimulation.
 * Every refused call logs a message and returns fmi2Error; the host never crashes. The exporter
 * behaviours QUIRK_PROVISIONAL and QUIRK_RESET_IN_SETUP are described in typed_stair_model.h.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fmi2Functions.h"
#include "typed_stair_model.h"

#define GUID "{6f1c2b7e-typed-stair-0001}"

typedef struct {
    fmi2Type type;
    int mode;
    fmi2CallbackFunctions callbacks;
    char name[64];
    State s;
} Instance;

static void log_error(Instance *inst, const char *message) {
    if (inst->callbacks.logger != NULL)
        inst->callbacks.logger(inst->callbacks.componentEnvironment, inst->name, fmi2Error, "logStatusError", "%s",
                               message);
}

static fmi2Status refuse(Instance *inst, const char *function, const char *why) {
    char message[400];
    snprintf(message, sizeof message, "%s: %s", function, why);
    log_error(inst, message);
    return fmi2Error;
}

/* ------------------------------------------------------------------ life cycle */

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID, fmi2String location,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)location; (void)visible; (void)loggingOn;
    if (functions == NULL || functions->allocateMemory == NULL || functions->freeMemory == NULL) return NULL;
    if (instanceName == NULL || fmuGUID == NULL || strcmp(fmuGUID, GUID) != 0) {
        if (functions->logger != NULL)
            functions->logger(functions->componentEnvironment, instanceName ? instanceName : "?", fmi2Error,
                              "logStatusError", "fmi2Instantiate: fmuGUID does not match the modelDescription.xml");
        return NULL;
    }
    Instance *inst = functions->allocateMemory(1, sizeof(Instance));
    if (inst == NULL) return NULL;
    inst->type = fmuType;
    inst->mode = INSTANTIATED;
    inst->callbacks = *functions;
    snprintf(inst->name, sizeof inst->name, "%s", instanceName);
    start_values(&inst->s);
    return inst;
}

void fmi2FreeInstance(fmi2Component c) {
    Instance *inst = c;
    if (inst != NULL) inst->callbacks.freeMemory(inst);
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String categories[]) {
    (void)c; (void)on; (void)n; (void)categories;
    return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDefined, fmi2Real tol, fmi2Real start,
                               fmi2Boolean stopDefined, fmi2Real stop) {
    Instance *inst = c;
    (void)tolDefined; (void)tol; (void)stopDefined; (void)stop;
    if (inst == NULL) return fmi2Error;
#ifdef QUIRK_RESET_IN_SETUP
    start_values(&inst->s);
#endif
    inst->s.time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    Instance *inst = c;
    if (inst == NULL) return fmi2Error;
    inst->mode = INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Instance *inst = c;
    if (inst == NULL) return fmi2Error;
    if (!(inst->s.real[VR_PERIOD] > 0.0))
        return refuse(inst, "fmi2ExitInitializationMode", "parameter period must be > 0");
    initialized(&inst->s);
    inst->mode = inst->type == fmi2ModelExchange ? EVENT : STEPPING;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) { return c == NULL ? fmi2Error : fmi2OK; }

fmi2Status fmi2Reset(fmi2Component c) {
    Instance *inst = c;
    if (inst == NULL) return fmi2Error;
    start_values(&inst->s);
    inst->mode = INSTANTIATED;
    return fmi2OK;
}

/* ------------------------------------------------------------------ get / set */

#define CHECK_VR(vr, n, function)                                                                   \
    if ((vr) >= (n)) return refuse(inst, function, "unknown value reference")

static int is_parameter_real(fmi2ValueReference vr) { return vr == VR_PERIOD || vr == VR_STOP_AT; }

/* Model Exchange in continuous-time mode: discrete inputs wait for event mode. */
#define CHECK_DISCRETE_INPUT(name, function)                                                        \
    if (inst->type == fmi2ModelExchange && inst->mode == CONTINUOUS)                                \
    return refuse(inst, function, "discrete input " name " can be set only in initialization mode or event mode")
static int is_parameter_integer(fmi2ValueReference vr) { return vr == VR_INCREMENT || vr == VR_MODE; }

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[]) {
    Instance *inst = c;
    if (inst == NULL) return fmi2Error;
    for (size_t i = 0; i < n; i++) {
        CHECK_VR(vr[i], N_REAL, "fmi2GetReal");
        value[i] = inst->s.real[vr[i]];
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real value[]) {
    Instance *inst = c;
    if (inst == NULL) return fmi2Error;
    for (size_t i = 0; i < n; i++) {
        CHECK_VR(vr[i], N_REAL, "fmi2SetReal");
        if (vr[i] != VR_X_IN && vr[i] != VR_R_IN && !is_parameter_real(vr[i]) && !(vr[i] == VR_LEVEL && !inst->s.initialized))
            return refuse(inst, "fmi2SetReal", "only x_in, r_in, level (before initialisation) and parameters can be set");
        if (vr[i] == VR_R_IN) CHECK_DISCRETE_INPUT("r_in", "fmi2SetReal");
        if (is_parameter_real(vr[i]) && inst->s.initialized)
            return refuse(inst, "fmi2SetReal", "parameters are fixed after initialisation");
        if (!isfinite(value[i])) return refuse(inst, "fmi2SetReal", "values must be finite");
        inst->s.real[vr[i]] = value[i];
    }
    compute(&inst->s);
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer value[]) {
    Instance *inst = c;
    if (inst == NULL) return fmi2Error;
    for (size_t i = 0; i < n; i++) {
        CHECK_VR(vr[i], N_INTEGER, "fmi2GetInteger");
        value[i] = inst->s.integer[vr[i]];
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer value[]) {
    Instance *inst = c;
    if (inst == NULL) return fmi2Error;
    for (size_t i = 0; i < n; i++) {
        CHECK_VR(vr[i], N_INTEGER, "fmi2SetInteger");
        if (vr[i] != VR_N_IN && vr[i] != VR_E_IN && !is_parameter_integer(vr[i]))
            return refuse(inst, "fmi2SetInteger", "outputs cannot be set");
        if (vr[i] == VR_N_IN) CHECK_DISCRETE_INPUT("n_in", "fmi2SetInteger");
        if (vr[i] == VR_E_IN) CHECK_DISCRETE_INPUT("e_in", "fmi2SetInteger");
        if (is_parameter_integer(vr[i]) && inst->s.initialized)
            return refuse(inst, "fmi2SetInteger", "parameters are fixed after initialisation");
        if ((vr[i] == VR_MODE || vr[i] == VR_E_IN) && value[i] != 1 && value[i] != 2)
            return refuse(inst, "fmi2SetInteger", "a Direction must be 1 (up) or 2 (down)");
        inst->s.integer[vr[i]] = value[i];
    }
    compute(&inst->s);
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean value[]) {
    Instance *inst = c;
    if (inst == NULL) return fmi2Error;
    for (size_t i = 0; i < n; i++) {
        CHECK_VR(vr[i], N_BOOLEAN, "fmi2GetBoolean");
        value[i] = inst->s.boolean[vr[i]];
    }
    return fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean value[]) {
    Instance *inst = c;
    if (inst == NULL) return fmi2Error;
    for (size_t i = 0; i < n; i++) {
        CHECK_VR(vr[i], N_BOOLEAN, "fmi2SetBoolean");
        if (vr[i] == VR_B_OUT) return refuse(inst, "fmi2SetBoolean", "b_out is an output");
        if (vr[i] == VR_B_IN) CHECK_DISCRETE_INPUT("b_in", "fmi2SetBoolean");
        if (vr[i] == VR_NEGATE && inst->s.initialized)
            return refuse(inst, "fmi2SetBoolean", "parameters are fixed after initialisation");
        inst->s.boolean[vr[i]] = value[i] != fmi2False;
    }
    compute(&inst->s);
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String value[]) {
    Instance *inst = c;
    if (inst == NULL) return fmi2Error;
    for (size_t i = 0; i < n; i++) {
        CHECK_VR(vr[i], N_STRING, "fmi2GetString");
        value[i] = inst->s.string[vr[i]];
    }
    return fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String value[]) {
    Instance *inst = c;
    if (inst == NULL) return fmi2Error;
    for (size_t i = 0; i < n; i++) {
        CHECK_VR(vr[i], N_STRING, "fmi2SetString");
        if (vr[i] == VR_S_OUT) return refuse(inst, "fmi2SetString", "s_out is an output");
        if (vr[i] == VR_S_IN) CHECK_DISCRETE_INPUT("s_in", "fmi2SetString");
        if (vr[i] == VR_LABEL && inst->s.initialized)
            return refuse(inst, "fmi2SetString", "parameters are fixed after initialisation");
        if (value[i] == NULL || strlen(value[i]) >= TEXT)
            return refuse(inst, "fmi2SetString", "a string must be non-NULL and shorter than 256 bytes");
        strcpy(inst->s.string[vr[i]], value[i]);
    }
    compute(&inst->s);
    return fmi2OK;
}

/* ------------------------------------------------------------------ FMU state */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    Instance *inst = c;
    if (inst == NULL || state == NULL) return fmi2Error;
    if (*state == NULL && (*state = inst->callbacks.allocateMemory(1, sizeof(State))) == NULL)
        return refuse(inst, "fmi2GetFMUstate", "out of memory");
    memcpy(*state, &inst->s, sizeof(State));
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    Instance *inst = c;
    if (inst == NULL || state == NULL) return fmi2Error;
    memcpy(&inst->s, state, sizeof(State));
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    Instance *inst = c;
    if (inst == NULL) return fmi2Error;
    if (state != NULL && *state != NULL) inst->callbacks.freeMemory(*state);
    if (state != NULL) *state = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    (void)c; (void)state;
    *size = sizeof(State);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    Instance *inst = c;
    if (inst == NULL || size != sizeof(State)) return fmi2Error;
    memcpy(bytes, state, sizeof(State));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate *state) {
    Instance *inst = c;
    if (inst == NULL || size != sizeof(State)) return fmi2Error;
    if (*state == NULL && (*state = inst->callbacks.allocateMemory(1, sizeof(State))) == NULL) return fmi2Error;
    memcpy(*state, bytes, sizeof(State));
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference k[], size_t nk, const fmi2Real dk[], fmi2Real du[]) {
    (void)u; (void)nu; (void)k; (void)nk; (void)dk; (void)du;
    return refuse(c, "fmi2GetDirectionalDerivative", "not provided");
}

/* ------------------------------------------------------------------ Model Exchange */

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    Instance *inst = c;
    if (inst == NULL) return fmi2Error;
    inst->mode = EVENT;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
    Instance *inst = c;
    if (inst == NULL || info == NULL) return fmi2Error;
    State *s = &inst->s;
    compute(s);
    info->newDiscreteStatesNeeded = fmi2False;
    info->terminateSimulation = reached(s, s->time) ? fmi2True : fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = fmi2False;
    info->nextEventTimeDefined = fmi2True;
    info->nextEventTime = fmin((double)(boundaries(s, s->time) + 1) * s->real[VR_PERIOD], s->real[VR_STOP_AT]);
    s->terminated = info->terminateSimulation;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    Instance *inst = c;
    if (inst == NULL) return fmi2Error;
    inst->mode = CONTINUOUS;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSet, fmi2Boolean *event, fmi2Boolean *stop) {
    (void)noSet;
    if (c == NULL || event == NULL || stop == NULL) return fmi2Error;
    *event = fmi2False;
    *stop = fmi2False;
    return fmi2OK;
}

/* The counter changes only at time events, in fmi2NewDiscreteStates: between events, a time that
 * has crossed a boundary (before the event is handled) keeps the counter of the left limit. */
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    Instance *inst = c;
    if (inst == NULL) return fmi2Error;
    inst->s.time = time;
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t n) {
    Instance *inst = c;
    if (inst == NULL || n != 1) return fmi2Error;
    inst->s.real[VR_LEVEL] = x[0];
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t n) {
    Instance *inst = c;
    if (inst == NULL || n != 1) return fmi2Error;
    dx[0] = inst->s.real[VR_X_IN];
    return fmi2OK;
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t n) {
    (void)z;
    return c == NULL || n != 0 ? fmi2Error : fmi2OK;
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t n) {
    Instance *inst = c;
    if (inst == NULL || n != 1) return fmi2Error;
    x[0] = inst->s.real[VR_LEVEL];
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x[], size_t n) {
    if (c == NULL || n != 1) return fmi2Error;
    x[0] = 1.0;
    return fmi2OK;
}

/* ------------------------------------------------------------------ Co-Simulation */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr; (void)order; (void)value;
    return n == 0 ? fmi2OK : refuse(c, "fmi2SetRealInputDerivatives", "canInterpolateInputs is false");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr; (void)order; (void)value;
    return n == 0 ? fmi2OK : refuse(c, "fmi2GetRealOutputDerivatives", "maxOutputDerivativeOrder is 0");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSet) {
    Instance *inst = c;
    if (inst == NULL) return fmi2Error;
    State *s = &inst->s;
    if (s->terminated) return refuse(inst, "fmi2DoStep", "the simulation was terminated at stop_at");
    if (!(h >= 0.0) || fabs(t - s->time) > 1e-9 * fmax(1.0, fabs(t)))
        return refuse(inst, "fmi2DoStep", "the step must start at the FMU's time and have h >= 0");
    double end = t + h;
    if (reached(s, end)) {  /* stop at stop_at, as a time event inside the step would */
        end = fmax(t, s->real[VR_STOP_AT]);
        s->terminated = 1;
    }
    begin_step(s, noSet != fmi2False);
    s->real[VR_LEVEL] += s->real[VR_X_IN] * (end - t);
    s->time = end;
    compute(s);
    return s->terminated ? fmi2Discard : fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) { return refuse(c, "fmi2CancelStep", "fmi2DoStep never returns fmi2Pending"); }

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind k, fmi2Status *v) {
    (void)k; (void)v;
    return refuse(c, "fmi2GetStatus", "not provided");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind k, fmi2Real *v) {
    Instance *inst = c;
    if (inst == NULL || v == NULL) return fmi2Error;
    if (k != fmi2LastSuccessfulTime) return refuse(inst, "fmi2GetRealStatus", "only fmi2LastSuccessfulTime");
    *v = inst->s.time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind k, fmi2Integer *v) {
    (void)k; (void)v;
    return refuse(c, "fmi2GetIntegerStatus", "not provided");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind k, fmi2Boolean *v) {
    Instance *inst = c;
    if (inst == NULL || v == NULL) return fmi2Error;
    if (k != fmi2Terminated) return refuse(inst, "fmi2GetBooleanStatus", "only fmi2Terminated");
    *v = inst->s.terminated ? fmi2True : fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind k, fmi2String *v) {
    (void)k; (void)v;
    return refuse(c, "fmi2GetStringStatus", "not provided");
}
