/*
 * FMI 2.0 co-simulation front end of every shapefmu FMU: binaries/linux64/<modelIdentifier>.so,
 * compiled by builder.py from this file, fmu_states.c and python_runtime.c (the sources are kept in
 * the FMU's resources/shim/ for the record).
 *
 * Why it exists. pythonfmu's export library (shipped beside this file as <modelIdentifier>_pythonfmu.so)
 * embeds Python but is not linked against libpython, finalises the interpreter at process exit
 * while instances still live, reports every Python error as fmi2Fatal and a failed step as
 * fmi2Discard, while an FMU given bad input must answer fmi2Error and stay usable. This front end
 *
 *   1. makes libpython global, starts the interpreter and keeps it alive to the end of the process,
 *      then loads the export library (python_runtime.c says how and why);
 *   2. forwards every fmi2 call to the export library, which is loaded RTLD_LOCAL from this
 *      file's own directory, so two FMUs never share the symbols of each other's copy;
 *   3. intercepts the logger: the Python slave logs a message with status fmi2Error for bad
 *      parameters, NaN inputs and wrong call orders, and the front end turns the call in which it
 *      was logged into fmi2Error (the slave never raises, so the instance stays alive);
 *   4. refuses what the export library would crash on: a NULL instance or state, a serialisation
 *      buffer that is too small, a model-exchange instantiation, a foreign GUID, and any call once
 *      the process's interpreter is gone (finalised by a Python host at its exit, or by another
 *      party): fmi2Error, with the message on stderr -- the host's logger may be Python code
 *      then, which can no longer run. fmi2FreeInstance then frees the front end's part only;
 *   5. works around a defect of pythonfmu 0.7.0's export library that corrupts the heap of the
 *      process that hosts it (every FMU of the process shares that heap and its interpreter):
 *      a Python exception escaping the slave (reported as fmi2Fatal) releases the slave's class,
 *      instance and log queue at once, and fmi2FreeInstance releases them a second time. After
 *      fmi2Fatal the front end never calls the export library for that instance again: it only
 *      frees its own part (the FMI 2.0 host may call nothing but fmi2FreeInstance then). Its other
 *      defect, a library destructor that writes into a destroyed std::shared_ptr at exit, is
 *      defused in python_runtime.c;
 *   6. keeps the instance's FMI 2.0 state machine (FMI 2.0.x, 4.2.4; the native FMUs keep the
 *      same): a call not allowed in the current state is refused with fmi2Error and a message in
 *      the native FMUs' words ("fmi2Terminate: not allowed in Initialization Mode"), never
 *      forwarded. An initialisation call or fmi2Reset answering fmi2Error leaves the instance in
 *      the error state, where only the getters, fmi2SetFMUstate, fmi2Reset and fmi2FreeInstance
 *      are accepted; any other refusal (a bad value, a failed step) leaves the state as it was, so
 *      the instance stays usable. The getters are served in every state (FMI 2.0 does not list
 *      Instantiated): they only read. fmi2SetFMUstate brings back the state a saved state was
 *      taken in (fmu_states.c).
 *      Why: OMSimulator 3.0, after a failed fmi2ExitInitializationMode, goes through the instances
 *      with fmi2Terminate and, when that answers fmi2OK, fmi2FreeInstance, stops at the first that
 *      fails, and later runs the same round again with the handles it kept, freed ones included.
 *      The slave accepted fmi2Terminate after the failure, so the Shaper was freed; the plant
 *      refused; the second round's fmi2Terminate read the freed instance and jumped through a
 *      garbage pointer in the export library (SIGSEGV). Now the failed instance refuses, so it is
 *      not freed early, and fmi2FreeInstance keeps a pointer-sized Handle for the life of the
 *      process: a call on a freed instance (an instance that did terminate, freed in the first
 *      round) is refused with a message on stderr -- the host's logger environment may be gone
 *      with it -- and a second fmi2FreeInstance does nothing.
 */
#define _GNU_SOURCE
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2_shim.h"

#ifndef SHIM_GUID
#error "compile with -DSHIM_GUID=\"{...}\""
#endif

#define EXPORT __attribute__((visibility("default")))

static void host_log(const fmi2CallbackFunctions* f, fmi2String name, fmi2Status status, const char* message)
{
    /* The host formats the message like printf (FMI 2.0): a '%' of a path or URI in it (%20) is
     * doubled, or the host would read arguments that were never passed. */
    char escaped[4096];
    size_t n = 0;
    if (f == NULL || f->logger == NULL) return;
    for (; *message != '\0' && n + 2 < sizeof(escaped); message++) {
        if (*message == '%') escaped[n++] = '%';
        escaped[n++] = *message;
    }
    escaped[n] = '\0';
    f->logger(f->componentEnvironment, name, status, status >= fmi2Error ? "logStatusError" : "logAll", escaped);
}

static void shim_logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category, fmi2String message, ...)
{
    Shim* s = (Shim*)env;
    if (s == NULL) return;
    if (status >= fmi2Error) s->error_logged = 1;
    /* Errors and warnings always reach the host; the rest only with debug logging on. The slave
     * never puts '%' in a message, so hosts that treat it as a format string print it verbatim. */
    if ((status >= fmi2Warning || s->logging_on) && s->host.logger != NULL) {
        s->host.logger(s->host.componentEnvironment, name, status, category, message);
    }
}

/* A failed step comes back from the export library as fmi2Discard; with an error logged it is an error. */
fmi2Status merge(Shim* s, fmi2Status status)
{
    if (status == fmi2Fatal) s->fatal = 1;
    if (s->error_logged && status < fmi2Error) status = fmi2Error;
    s->error_logged = 0;
    return status;
}

fmi2Status refuse(Shim* s, const char* message)
{
    if (s != NULL) host_log(&s->host, s->name, fmi2Error, message);
    return fmi2Error;
}

static fmi2Status refuse_after_fatal(Shim* s)
{
    host_log(&s->host, s->name, fmi2Fatal, "the instance returned fmi2Fatal before; only fmi2FreeInstance is allowed");
    return fmi2Fatal;
}

/* See 4.: after the interpreter is gone, the message goes to stderr, not to the host's logger. */
static fmi2Status refuse_without_python(const char* name, const char* call, const char* outcome)
{
    fprintf(stderr, "%s: %s: the Python interpreter of this process has been finalised (by the host at its "
        "exit, or by another component), so the FMU can no longer run; %s\n", name, call, outcome);
    fflush(stderr);
    return fmi2Error;
}

static const char* mode_name(Mode mode)
{
    switch (mode) {
    case INSTANTIATED: return "Instantiated";
    case INITIALIZATION: return "Initialization Mode";
    case STEP_COMPLETE: return "Step Complete";
    case TERMINATED: return "Terminated";
    default: return "Error";
    }
}

Shim* admit(fmi2Component c, int allowed, const char* function, fmi2Status* refusal)
{
    Handle* h = (Handle*)c;
    Shim* s = h != NULL ? h->shim : NULL;
    char message[256];
    *refusal = fmi2Error;
    if (h == NULL) return NULL;
    if (s == NULL) {
        fprintf(stderr, "%s: not allowed after fmi2FreeInstance (the host called an instance of the FMU %s that it "
            "had freed); refused with fmi2Error\n", function, SHIM_GUID);
        fflush(stderr);
        return NULL;
    }
    if (s->fatal) {
        *refusal = refuse_after_fatal(s);
        return NULL;
    }
    if (!runtime_alive()) {
        *refusal = refuse_without_python(s->name, function, "refused with fmi2Error");
        return NULL;
    }
    if (!(s->mode & allowed)) {
        if (s->mode == ERROR_STATE) {
            snprintf(message, sizeof(message), "%s: not allowed after an error (only the getters, fmi2SetFMUstate, "
                "fmi2Reset and fmi2FreeInstance are)", function);
        } else {
            snprintf(message, sizeof(message), "%s: not allowed in %s", function, mode_name(s->mode));
        }
        *refusal = refuse(s, message);
        return NULL;
    }
    s->error_logged = 0;
    return s;
}

/* The status of an initialisation call, fmi2Terminate or fmi2Reset, and the state it leads to:
 * `next` when it succeeded, the error state when it failed (fmi2Fatal: see 5.). */
static fmi2Status advance(Shim* s, fmi2Status status, Mode next)
{
    status = merge(s, status);
    if (status <= fmi2Warning) {
        s->mode = next;
    } else if (status < fmi2Fatal) {
        s->mode = ERROR_STATE;
    }
    return status;
}

/* The export library reads <resources>/slavemodule.txt and crashes if it is missing: check first,
 * decoding the URI the way it does (file:// prefix, %20 as space). */
static int resources_present(fmi2String uri)
{
    char path[4096];
    const char* in = uri;
    size_t n = 0;
    FILE* f;
    if (strncmp(in, "file://", 7) == 0) in += 7;
    while (*in != '\0' && n + 1 < sizeof(path)) {
        if (strncmp(in, "%20", 3) == 0) {
            path[n++] = ' ';
            in += 3;
        } else {
            path[n++] = *in++;
        }
    }
    path[n] = '\0';
    if (n + sizeof("/slavemodule.txt") >= sizeof(path)) return 0;
    strcat(path, "/slavemodule.txt");
    f = fopen(path, "r");
    if (f == NULL) return 0;
    fclose(f);
    return 1;
}

/* ---- FMI 2.0 API ------------------------------------------------------------------------------ */

EXPORT const char* fmi2GetTypesPlatform(void) { return "default"; }
EXPORT const char* fmi2GetVersion(void) { return "2.0"; }

EXPORT fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
    fmi2String fmuResourceLocation, const fmi2CallbackFunctions* functions, fmi2Boolean visible, fmi2Boolean loggingOn)
{
    char why[2048] = "";
    char message[2400];
    Handle* h;
    Shim* s;
    fmi2String name = instanceName != NULL ? instanceName : "";
    if (functions == NULL) return NULL;
    if (fmuType != fmi2CoSimulation) {
        host_log(functions, name, fmi2Error, "this FMU supports co-simulation only (fmuType must be fmi2CoSimulation)");
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, SHIM_GUID) != 0) {
        snprintf(message, sizeof(message), "GUID mismatch: the FMU is %s, the host asked for %s", SHIM_GUID,
            fmuGUID != NULL ? fmuGUID : "(null)");
        host_log(functions, name, fmi2Error, message);
        return NULL;
    }
    if (fmuResourceLocation == NULL) {
        host_log(functions, name, fmi2Error, "fmuResourceLocation is NULL");
        return NULL;
    }
    if (!resources_present(fmuResourceLocation)) {
        snprintf(message, sizeof(message), "fmuResourceLocation %s is not this FMU's resources directory "
            "(no slavemodule.txt in it)", fmuResourceLocation);
        host_log(functions, name, fmi2Error, message);
        return NULL;
    }
    if (!runtime_load(why, sizeof(why))) {
        snprintf(message, sizeof(message), "cannot start the FMU's Python runtime: %s", why);
        host_log(functions, name, fmi2Error, message);
        return NULL;
    }
    if (!runtime_alive()) {
        refuse_without_python(name, "fmi2Instantiate", "no instance (NULL)");
        return NULL;
    }
    h = (Handle*)calloc(1, sizeof(Handle));
    s = (Shim*)calloc(1, sizeof(Shim));
    if (h == NULL || s == NULL) {
        free(h);
        free(s);
        return NULL;
    }
    s->mode = INSTANTIATED;
    s->host = *functions;
    s->ours = *functions;
    s->ours.logger = shim_logger;
    s->ours.componentEnvironment = s;
    s->logging_on = loggingOn;
    snprintf(s->name, sizeof(s->name), "%s", name);
    /* The export library logs through s->ours (it keeps the pointer), with logging on so that
     * our logger sees every error; shim_logger filters for the host. */
    s->component = inner.Instantiate(name, fmuType, fmuGUID, fmuResourceLocation, &s->ours, visible, fmi2True);
    if (s->component == NULL) {
        free(s);
        free(h);
        return NULL;
    }
    h->shim = s;
    return h;
}

EXPORT void fmi2FreeInstance(fmi2Component c)
{
    Handle* h = (Handle*)c;
    Shim* s = h != NULL ? h->shim : NULL;
    /* The handle stays (see 6.): a second fmi2FreeInstance finds nothing left to free. */
    if (s == NULL) return;
    h->shim = NULL;
    /* After fmi2Fatal the export library has released the instance's Python objects already; its
     * fmi2FreeInstance would release them again. Without an interpreter it cannot release them at
     * all. Either way its small C++ part is left allocated instead. */
    if (s->component != NULL && !s->fatal) {
        if (runtime_alive()) {
            inner.FreeInstance(s->component);
        } else {
            refuse_without_python(s->name, "fmi2FreeInstance", "only the front end's part of the instance is freed");
        }
    }
    free(s);
}

EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories, const fmi2String categories[])
{
    Handle* h = (Handle*)c;
    (void)nCategories;
    (void)categories;
    if (h == NULL || h->shim == NULL) return fmi2Error;
    h->shim->logging_on = loggingOn;
    return fmi2OK;
}

EXPORT fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
    fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    BEGIN(c, INSTANTIATED);
    return advance(s, inner.SetupExperiment(s->component, toleranceDefined, tolerance, startTime, stopTimeDefined, stopTime),
        INSTANTIATED);
}

/* The transitions without arguments: called in mode `from`, in mode `to` once the model agrees. */
#define TRANSITION(Name, from, to)                                                                 \
    EXPORT fmi2Status fmi2##Name(fmi2Component c)                                                  \
    {                                                                                              \
        BEGIN(c, from);                                                                            \
        return advance(s, inner.Name(s->component), to);                                           \
    }
TRANSITION(EnterInitializationMode, INSTANTIATED, INITIALIZATION)
TRANSITION(ExitInitializationMode, INITIALIZATION, STEP_COMPLETE)
TRANSITION(Terminate, STEP_COMPLETE, TERMINATED)
TRANSITION(Reset, ANY_MODE, INSTANTIATED)

/* The setters: before, in and after initialisation, not once terminated or after an error. */
#define SETTABLE (INSTANTIATED | INITIALIZATION | STEP_COMPLETE)

#define VALUES(Kind, Type)                                                                         \
    EXPORT fmi2Status fmi2Get##Kind(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, Type value[]) \
    {                                                                                              \
        BEGIN(c, ANY_MODE);                                                                        \
        if (nvr == 0) return fmi2OK;                                                               \
        if (vr == NULL || value == NULL) return refuse(s, "fmi2Get" #Kind ": NULL array");          \
        return merge(s, inner.Get##Kind(s->component, vr, nvr, value));                            \
    }                                                                                              \
    EXPORT fmi2Status fmi2Set##Kind(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const Type value[]) \
    {                                                                                              \
        BEGIN(c, SETTABLE);                                                                        \
        if (nvr == 0) return fmi2OK;                                                               \
        if (vr == NULL || value == NULL) return refuse(s, "fmi2Set" #Kind ": NULL array");          \
        return merge(s, inner.Set##Kind(s->component, vr, nvr, value));                            \
    }

VALUES(Real, fmi2Real)
VALUES(Integer, fmi2Integer)
VALUES(Boolean, fmi2Boolean)

EXPORT fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[])
{
    BEGIN(c, ANY_MODE);
    if (nvr == 0) return fmi2OK;
    if (vr == NULL || value == NULL) return refuse(s, "fmi2GetString: NULL array");
    return merge(s, inner.GetString(s->component, vr, nvr, value));
}

/* Whether `text` is well-formed UTF-8 (RFC 3629: no overlong forms, surrogates or code points past
 * U+10FFFF). The export library decodes it into a Python str, and a failed decoding is a Python error,
 * which it reports as fmi2Fatal: a string a host got wrong is refused here with fmi2Error instead. */
static int is_utf8(const unsigned char* text)
{
    while (*text) {
        const unsigned char c = *text++;
        int more;
        unsigned long code;
        if (c < 0x80) continue;
        if (c >= 0xC2 && c <= 0xDF) { more = 1; code = c & 0x1F; }
        else if (c >= 0xE0 && c <= 0xEF) { more = 2; code = c & 0x0F; }
        else if (c >= 0xF0 && c <= 0xF4) { more = 3; code = c & 0x07; }
        else return 0;
        for (; more > 0; more--, text++) {
            if ((*text & 0xC0) != 0x80) return 0;
            code = (code << 6) | (*text & 0x3F);
        }
        if ((c == 0xE0 && code < 0x800) || (code >= 0xD800 && code <= 0xDFFF) || (c == 0xF0 && code < 0x10000)
            || code > 0x10FFFF)
            return 0;
    }
    return 1;
}

EXPORT fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[])
{
    size_t i;
    BEGIN(c, SETTABLE);
    if (nvr == 0) return fmi2OK;
    if (vr == NULL || value == NULL) return refuse(s, "fmi2SetString: NULL array");
    for (i = 0; i < nvr; i++) {
        if (value[i] == NULL) return refuse(s, "fmi2SetString: NULL string");
        if (!is_utf8((const unsigned char*)value[i])) return refuse(s, "fmi2SetString: a string that is not UTF-8 text");
    }
    return merge(s, inner.SetString(s->component, vr, nvr, value));
}

/* A function this FMU does not provide: fmi2Error, logged while the instance lives. */
static fmi2Status unsupported(fmi2Component c, const char* message)
{
    Handle* h = (Handle*)c;
    return refuse(h != NULL ? h->shim : NULL, message);
}

EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference a[], size_t na,
    const fmi2ValueReference b[], size_t nb, const fmi2Real d[], fmi2Real r[])
{
    (void)a; (void)na; (void)b; (void)nb; (void)d; (void)r;
    return unsupported(c, "fmi2GetDirectionalDerivative is not provided (providesDirectionalDerivative=false)");
}

EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
    const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return unsupported(c, "fmi2SetRealInputDerivatives is not supported (canInterpolateInputs=false)");
}

EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
    const fmi2Integer order[], fmi2Real value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return unsupported(c, "fmi2GetRealOutputDerivatives is not supported (maxOutputDerivativeOrder=0)");
}

EXPORT fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
    fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    BEGIN(c, STEP_COMPLETE);
    return merge(s, inner.DoStep(s->component, currentCommunicationPoint, communicationStepSize, noSetFMUStatePriorToCurrentPoint));
}

EXPORT fmi2Status fmi2CancelStep(fmi2Component c)
{
    return unsupported(c, "fmi2CancelStep: doStep never runs asynchronously here");
}

/* The status getters: doStep never runs asynchronously, so there is no status to give. */
#define UNSUPPORTED_STATUS(function, type)                                                           \
    EXPORT fmi2Status function(fmi2Component c, const fmi2StatusKind kind, type* value)            \
    {                                                                                               \
        (void)kind; (void)value;                                                                    \
        return unsupported(c, #function ": doStep never runs asynchronously here");                 \
    }
UNSUPPORTED_STATUS(fmi2GetStatus, fmi2Status)
UNSUPPORTED_STATUS(fmi2GetRealStatus, fmi2Real)
UNSUPPORTED_STATUS(fmi2GetIntegerStatus, fmi2Integer)
UNSUPPORTED_STATUS(fmi2GetBooleanStatus, fmi2Boolean)
UNSUPPORTED_STATUS(fmi2GetStringStatus, fmi2String)
