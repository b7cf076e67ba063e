/*
 * FMI 2.0 co-simulation front end of every shapefmu FMU: binaries/linux64/<modelIdentifier>.so.
 *
 * Why it exists. pythonfmu's export library (shipped beside this file as <modelIdentifier>_pythonfmu.so)
 * embeds Python but is not linked against libpython: in a host with no Python of its own (ecos,
 * libcosim, Simulink, Dymola) its Py* symbols are unresolved, and extension modules loaded later
 * need libpython's symbols in the global scope. It also reports every Python error as fmi2Fatal
 * and a failed step as fmi2Discard, while an FMU given bad input must answer fmi2Error and stay
 * usable. This front end
 *
 *   1. makes libpython global before the export library is loaded: if the process already has
 *      Python (fmpy, a Python host) nothing is loaded; otherwise the libpython recorded at build
 *      time (SHIM_LIBPYTHON) is dlopen()ed with RTLD_GLOBAL, falling back to the sonames
 *      libpython3.<minor>.so.1.0 for the minor versions in SHIM_FALLBACK_MINORS. The recorded
 *      library gets its own home (SHIM_PYTHONHOME, the build interpreter's base prefix) unless
 *      the host set PYTHONHOME: the export library starts the interpreter with the program name
 *      "./PythonFMU", from which Python cannot find its standard library and would take another
 *      installation's (e.g. /usr/lib/python3.11 without lib-dynload's math module);
 *   2. forwards every fmi2 call to the export library, which is loaded RTLD_LOCAL from this
 *      file's own directory, so two FMUs never share the symbols of each other's copy;
 *   3. intercepts the logger: the Python slave logs a message with status fmi2Error for bad
 *      parameters, NaN inputs and wrong call orders, and the front end turns the call in which it
 *      was logged into fmi2Error (the slave never raises, so the instance stays alive);
 *   4. refuses what the export library would crash on: a NULL instance or state, a serialisation
 *      buffer that is too small, a model-exchange instantiation, a foreign GUID;
 *   5. works around two defects of pythonfmu 0.7.0's export library that corrupt the heap of the
 *      process that hosts it (every FMU of the process shares that heap and its interpreter):
 *      - a Python exception escaping the slave (reported as fmi2Fatal) releases the slave's class,
 *        instance and log queue at once, and fmi2FreeInstance releases them a second time. After
 *        fmi2Fatal the front end never calls the export library for that instance again: it only
 *        frees its own part (the FMI 2.0 host may call nothing but fmi2FreeInstance then);
 *      - its library destructor (finalizePythonInterpreter) resets a static std::shared_ptr that
 *        the C++ exit handlers have already destroyed: a write into freed memory at process exit,
 *        seen as "corrupted double-linked list" aborts. Right after loading the export library
 *        the front end registers that same function as a process exit handler: exit handlers run
 *        in reverse order of registration, so it resets the pointer while it is still alive.
 *
 * The FMI 2.0 types below are those of fmi2TypesPlatform.h / fmi2FunctionTypes.h (FMI 2.0.x,
 * BSD-licensed standard headers), written out so that the FMU builds with a bare C compiler.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <wchar.h>

typedef void* fmi2Component;
typedef void* fmi2ComponentEnvironment;
typedef void* fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Char;
typedef const fmi2Char* fmi2String;
typedef char fmi2Byte;

typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum { fmi2DoStepStatus, fmi2PendingStatus, fmi2LastSuccessfulTime, fmi2Terminated } fmi2StatusKind;

typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...);
typedef void* (*fmi2CallbackAllocateMemory)(size_t, size_t);
typedef void (*fmi2CallbackFreeMemory)(void*);
typedef void (*fmi2StepFinished)(fmi2ComponentEnvironment, fmi2Status);

typedef struct {
    fmi2CallbackLogger logger;
    fmi2CallbackAllocateMemory allocateMemory;
    fmi2CallbackFreeMemory freeMemory;
    fmi2StepFinished stepFinished;
    fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

#define fmi2True 1
#define fmi2False 0

#ifndef SHIM_GUID
#error "compile with -DSHIM_GUID=\"{...}\""
#endif
#ifndef SHIM_LIBPYTHON
#define SHIM_LIBPYTHON ""
#endif
#ifndef SHIM_PYTHONHOME
#define SHIM_PYTHONHOME ""
#endif
#ifndef SHIM_INNER_NAME
#error "compile with -DSHIM_INNER_NAME=\"<modelIdentifier>_pythonfmu.so\""
#endif

#define EXPORT __attribute__((visibility("default")))

/* ---- the export library's entry points ------------------------------------------------------ */

typedef struct {
    fmi2Component (*Instantiate)(fmi2String, fmi2Type, fmi2String, fmi2String, const fmi2CallbackFunctions*, fmi2Boolean, fmi2Boolean);
    void (*FreeInstance)(fmi2Component);
    fmi2Status (*SetupExperiment)(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean, fmi2Real);
    fmi2Status (*EnterInitializationMode)(fmi2Component);
    fmi2Status (*ExitInitializationMode)(fmi2Component);
    fmi2Status (*Terminate)(fmi2Component);
    fmi2Status (*Reset)(fmi2Component);
    fmi2Status (*GetReal)(fmi2Component, const fmi2ValueReference*, size_t, fmi2Real*);
    fmi2Status (*GetInteger)(fmi2Component, const fmi2ValueReference*, size_t, fmi2Integer*);
    fmi2Status (*GetBoolean)(fmi2Component, const fmi2ValueReference*, size_t, fmi2Boolean*);
    fmi2Status (*GetString)(fmi2Component, const fmi2ValueReference*, size_t, fmi2String*);
    fmi2Status (*SetReal)(fmi2Component, const fmi2ValueReference*, size_t, const fmi2Real*);
    fmi2Status (*SetInteger)(fmi2Component, const fmi2ValueReference*, size_t, const fmi2Integer*);
    fmi2Status (*SetBoolean)(fmi2Component, const fmi2ValueReference*, size_t, const fmi2Boolean*);
    fmi2Status (*SetString)(fmi2Component, const fmi2ValueReference*, size_t, const fmi2String*);
    fmi2Status (*GetFMUstate)(fmi2Component, fmi2FMUstate*);
    fmi2Status (*SetFMUstate)(fmi2Component, fmi2FMUstate);
    fmi2Status (*FreeFMUstate)(fmi2Component, fmi2FMUstate*);
    fmi2Status (*SerializedFMUstateSize)(fmi2Component, fmi2FMUstate, size_t*);
    fmi2Status (*SerializeFMUstate)(fmi2Component, fmi2FMUstate, fmi2Byte*, size_t);
    fmi2Status (*DeSerializeFMUstate)(fmi2Component, const fmi2Byte*, size_t, fmi2FMUstate*);
    fmi2Status (*DoStep)(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean);
} Inner;

static Inner inner;
static void* inner_handle = NULL;
static int inner_ready = 0; /* loaded, exit handler registered, every entry point found */

/* One instance: the export library's instance, the host's callbacks, and ours. */
typedef struct {
    fmi2Component component;
    fmi2CallbackFunctions host;
    fmi2CallbackFunctions ours;
    fmi2Boolean logging_on;
    int error_logged; /* set by our logger when the slave logs fmi2Error or worse */
    int fatal;        /* the export library answered fmi2Fatal: its instance is released (see 5.) */
    char name[256];
} Shim;

static void host_log(const fmi2CallbackFunctions* f, fmi2String name, fmi2Status status, const char* message)
{
    if (f != NULL && f->logger != NULL) {
        f->logger(f->componentEnvironment, name, status, status >= fmi2Error ? "logStatusError" : "logAll", message);
    }
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

/* Point a not yet initialised interpreter at the standard library it was built with. */
static void set_python_home(void* libpython)
{
    static wchar_t home[4096];
    void (*set_home)(const wchar_t*);
    int (*is_initialized)(void);
    const char* from_host = getenv("PYTHONHOME");
    if (SHIM_PYTHONHOME[0] == '\0' || (from_host != NULL && from_host[0] != '\0')) return;
    *(void**)(&is_initialized) = dlsym(libpython, "Py_IsInitialized");
    if (is_initialized == NULL || is_initialized()) return;
    *(void**)(&set_home) = dlsym(libpython, "Py_SetPythonHome");
    if (set_home != NULL && mbstowcs(home, SHIM_PYTHONHOME, sizeof(home) / sizeof(home[0]) - 1) != (size_t)-1) {
        set_home(home);
    } else {
        setenv("PYTHONHOME", SHIM_PYTHONHOME, 0); /* Python >= 3.13 has no Py_SetPythonHome */
    }
}

/* 1 if libpython's symbols are (now) in the global scope. */
static int open_libpython(char* why, size_t why_size)
{
    static const int minors[] = {SHIM_FALLBACK_MINORS};
    char soname[64];
    void* handle;
    size_t i;
    /* A Python host (fmpy) already has libpython: loading a second copy would start a second
     * interpreter in the same process. */
    if (dlsym(RTLD_DEFAULT, "Py_IsInitialized") != NULL) return 1;
    if (SHIM_LIBPYTHON[0] != '\0') {
        handle = dlopen(SHIM_LIBPYTHON, RTLD_NOW | RTLD_GLOBAL);
        if (handle != NULL) {
            set_python_home(handle);
            return 1;
        }
        snprintf(why, why_size, "%s", dlerror());
    }
    for (i = 0; i < sizeof(minors) / sizeof(minors[0]); i++) {
        snprintf(soname, sizeof(soname), "libpython3.%d.so.1.0", minors[i]);
        handle = dlopen(soname, RTLD_NOW | RTLD_GLOBAL);
        if (handle != NULL) return 1;
    }
    return 0;
}

#define LOAD(field, symbol)                                                  \
    do {                                                                     \
        *(void**)(&inner.field) = dlsym(inner_handle, symbol);               \
        if (inner.field == NULL) {                                           \
            snprintf(why, why_size, "export library lacks %s", symbol);     \
            return 0;                                                        \
        }                                                                    \
    } while (0)

/* The C++ ABI's registration of exit handlers (glibc, musl). With d = NULL the handler belongs to
 * the program, not to this library: it runs at process exit, even after a host unloaded us. */
extern int __cxa_atexit(void (*handler)(void*), void* arg, void* d);

/* See 5. above: registered once per copy of the export library, right after it is loaded. The
 * handler lives in the export library, which is never unloaded (RTLD_NODELETE), so it is mapped at
 * exit; it takes no argument, and the one passed is ignored under the x86-64 calling convention. */
static int release_python_state_at_exit(char* why, size_t why_size, const char* path)
{
    void (*finalize)(void*);
    *(void**)(&finalize) = dlsym(inner_handle, "finalizePythonInterpreter");
    if (finalize == NULL || dlopen(path, RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE) == NULL
        || __cxa_atexit(finalize, NULL, NULL) != 0) {
        snprintf(why, why_size, "cannot register the exit handler of %s", path);
        return 0;
    }
    return 1;
}

static int load_inner(char* why, size_t why_size)
{
    Dl_info info;
    char path[4096];
    char* slash;
    int first_load;
    if (inner_ready) return 1;
    if (!open_libpython(why, why_size)) {
        snprintf(why + strlen(why), why_size - strlen(why),
            "; no libpython found: tried %s and libpython3.<minor>.so.1.0 on the library path. "
            "Install Python 3 or add its lib directory to LD_LIBRARY_PATH",
            SHIM_LIBPYTHON[0] ? SHIM_LIBPYTHON : "(none recorded)");
        return 0;
    }
    if (dladdr((void*)&load_inner, &info) == 0 || info.dli_fname == NULL) {
        snprintf(why, why_size, "cannot locate the FMU's binaries directory");
        return 0;
    }
    snprintf(path, sizeof(path), "%s", info.dli_fname);
    slash = strrchr(path, '/');
    if (slash == NULL) {
        snprintf(path, sizeof(path), "./%s", SHIM_INNER_NAME);
    } else {
        snprintf(slash + 1, sizeof(path) - (size_t)(slash + 1 - path), "%s", SHIM_INNER_NAME);
    }
    /* A copy loaded before (by an earlier load of this front end) has its exit handler already. */
    first_load = dlopen(path, RTLD_NOW | RTLD_NOLOAD) == NULL;
    inner_handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (inner_handle == NULL) {
        snprintf(why, why_size, "cannot load %s: %s", path, dlerror());
        return 0;
    }
    if (first_load && !release_python_state_at_exit(why, why_size, path)) return 0;
    LOAD(Instantiate, "fmi2Instantiate");
    LOAD(FreeInstance, "fmi2FreeInstance");
    LOAD(SetupExperiment, "fmi2SetupExperiment");
    LOAD(EnterInitializationMode, "fmi2EnterInitializationMode");
    LOAD(ExitInitializationMode, "fmi2ExitInitializationMode");
    LOAD(Terminate, "fmi2Terminate");
    LOAD(Reset, "fmi2Reset");
    LOAD(GetReal, "fmi2GetReal");
    LOAD(GetInteger, "fmi2GetInteger");
    LOAD(GetBoolean, "fmi2GetBoolean");
    LOAD(GetString, "fmi2GetString");
    LOAD(SetReal, "fmi2SetReal");
    LOAD(SetInteger, "fmi2SetInteger");
    LOAD(SetBoolean, "fmi2SetBoolean");
    LOAD(SetString, "fmi2SetString");
    LOAD(GetFMUstate, "fmi2GetFMUstate");
    LOAD(SetFMUstate, "fmi2SetFMUstate");
    LOAD(FreeFMUstate, "fmi2FreeFMUstate");
    LOAD(SerializedFMUstateSize, "fmi2SerializedFMUstateSize");
    LOAD(SerializeFMUstate, "fmi2SerializeFMUstate");
    LOAD(DeSerializeFMUstate, "fmi2DeSerializeFMUstate");
    LOAD(DoStep, "fmi2DoStep");
    inner_ready = 1;
    return 1;
}

/* The status of a forwarded call: fmi2Error if the slave logged an error during it. A failed
 * step comes back from the export library as fmi2Discard; with an error logged it is an error. */
static fmi2Status merge(Shim* s, fmi2Status status)
{
    if (status == fmi2Fatal) s->fatal = 1;
    if (s->error_logged && status < fmi2Error) status = fmi2Error;
    s->error_logged = 0;
    return status;
}

static fmi2Status refuse(Shim* s, const char* message)
{
    if (s != NULL) host_log(&s->host, s->name, fmi2Error, message);
    return fmi2Error;
}

static fmi2Status refuse_after_fatal(Shim* s)
{
    host_log(&s->host, s->name, fmi2Fatal, "the instance returned fmi2Fatal before; only fmi2FreeInstance is allowed");
    return fmi2Fatal;
}

#define BEGIN(c)                                        \
    Shim* s = (Shim*)(c);                               \
    if (s == NULL || s->component == NULL) return fmi2Error; \
    if (s->fatal) return refuse_after_fatal(s);         \
    s->error_logged = 0

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
    char why[1024] = "";
    char message[1400];
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
    if (!load_inner(why, sizeof(why))) {
        snprintf(message, sizeof(message), "cannot start the FMU's Python runtime: %s", why);
        host_log(functions, name, fmi2Fatal, message);
        return NULL;
    }
    s = (Shim*)calloc(1, sizeof(Shim));
    if (s == NULL) return NULL;
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
        return NULL;
    }
    return s;
}

EXPORT void fmi2FreeInstance(fmi2Component c)
{
    Shim* s = (Shim*)c;
    if (s == NULL) return;
    /* After fmi2Fatal the export library has released the instance's Python objects already; its
     * fmi2FreeInstance would release them again. Its small C++ part is left allocated instead. */
    if (s->component != NULL && !s->fatal) inner.FreeInstance(s->component);
    free(s);
}

EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories, const fmi2String categories[])
{
    Shim* s = (Shim*)c;
    (void)nCategories;
    (void)categories;
    if (s == NULL) return fmi2Error;
    s->logging_on = loggingOn;
    return fmi2OK;
}

EXPORT fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
    fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    BEGIN(c);
    return merge(s, inner.SetupExperiment(s->component, toleranceDefined, tolerance, startTime, stopTimeDefined, stopTime));
}

EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    BEGIN(c);
    return merge(s, inner.EnterInitializationMode(s->component));
}

EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    BEGIN(c);
    return merge(s, inner.ExitInitializationMode(s->component));
}

EXPORT fmi2Status fmi2Terminate(fmi2Component c)
{
    BEGIN(c);
    return merge(s, inner.Terminate(s->component));
}

EXPORT fmi2Status fmi2Reset(fmi2Component c)
{
    BEGIN(c);
    return merge(s, inner.Reset(s->component));
}

#define VALUES(Kind, Type)                                                                         \
    EXPORT fmi2Status fmi2Get##Kind(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, Type value[]) \
    {                                                                                              \
        BEGIN(c);                                                                                  \
        if (nvr == 0) return fmi2OK;                                                               \
        if (vr == NULL || value == NULL) return refuse(s, "fmi2Get" #Kind ": NULL array");          \
        return merge(s, inner.Get##Kind(s->component, vr, nvr, value));                            \
    }                                                                                              \
    EXPORT fmi2Status fmi2Set##Kind(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const Type value[]) \
    {                                                                                              \
        BEGIN(c);                                                                                  \
        if (nvr == 0) return fmi2OK;                                                               \
        if (vr == NULL || value == NULL) return refuse(s, "fmi2Set" #Kind ": NULL array");          \
        return merge(s, inner.Set##Kind(s->component, vr, nvr, value));                            \
    }

VALUES(Real, fmi2Real)
VALUES(Integer, fmi2Integer)
VALUES(Boolean, fmi2Boolean)

EXPORT fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[])
{
    BEGIN(c);
    if (nvr == 0) return fmi2OK;
    if (vr == NULL || value == NULL) return refuse(s, "fmi2GetString: NULL array");
    return merge(s, inner.GetString(s->component, vr, nvr, value));
}

EXPORT fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[])
{
    size_t i;
    BEGIN(c);
    if (nvr == 0) return fmi2OK;
    if (vr == NULL || value == NULL) return refuse(s, "fmi2SetString: NULL array");
    for (i = 0; i < nvr; i++) {
        if (value[i] == NULL) return refuse(s, "fmi2SetString: NULL string");
    }
    return merge(s, inner.SetString(s->component, vr, nvr, value));
}

EXPORT fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* state)
{
    BEGIN(c);
    if (state == NULL) return refuse(s, "fmi2GetFMUstate: NULL state pointer");
    /* FMI 2.0: a non-NULL *state is a state to update; ours are immutable Python objects, so the
     * old one is freed and a new one returned. */
    if (*state != NULL) {
        inner.FreeFMUstate(s->component, state);
        *state = NULL;
    }
    return merge(s, inner.GetFMUstate(s->component, state));
}

EXPORT fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state)
{
    BEGIN(c);
    if (state == NULL) return refuse(s, "fmi2SetFMUstate: NULL state");
    return merge(s, inner.SetFMUstate(s->component, state));
}

EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* state)
{
    BEGIN(c);
    if (state == NULL || *state == NULL) return fmi2OK;
    return merge(s, inner.FreeFMUstate(s->component, state));
}

EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t* size)
{
    BEGIN(c);
    if (state == NULL || size == NULL) return refuse(s, "fmi2SerializedFMUstateSize: NULL state or size");
    return merge(s, inner.SerializedFMUstateSize(s->component, state, size));
}

EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte serializedState[], size_t size)
{
    size_t needed = 0;
    fmi2Status status;
    BEGIN(c);
    if (state == NULL || serializedState == NULL) return refuse(s, "fmi2SerializeFMUstate: NULL state or buffer");
    status = inner.SerializedFMUstateSize(s->component, state, &needed);
    if (status > fmi2Warning) return merge(s, status);
    if (size < needed) return refuse(s, "fmi2SerializeFMUstate: buffer smaller than fmi2SerializedFMUstateSize");
    return merge(s, inner.SerializeFMUstate(s->component, state, serializedState, needed));
}

EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size, fmi2FMUstate* state)
{
    BEGIN(c);
    if (serializedState == NULL || state == NULL) return refuse(s, "fmi2DeSerializeFMUstate: NULL buffer or state");
    return merge(s, inner.DeSerializeFMUstate(s->component, serializedState, size, state));
}

EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference a[], size_t na,
    const fmi2ValueReference b[], size_t nb, const fmi2Real d[], fmi2Real r[])
{
    (void)a; (void)na; (void)b; (void)nb; (void)d; (void)r;
    return refuse((Shim*)c, "fmi2GetDirectionalDerivative is not provided (providesDirectionalDerivative=false)");
}

EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
    const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return refuse((Shim*)c, "fmi2SetRealInputDerivatives is not supported (canInterpolateInputs=false)");
}

EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
    const fmi2Integer order[], fmi2Real value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return refuse((Shim*)c, "fmi2GetRealOutputDerivatives is not supported (maxOutputDerivativeOrder=0)");
}

EXPORT fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
    fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    BEGIN(c);
    return merge(s, inner.DoStep(s->component, currentCommunicationPoint, communicationStepSize, noSetFMUStatePriorToCurrentPoint));
}

EXPORT fmi2Status fmi2CancelStep(fmi2Component c)
{
    return refuse((Shim*)c, "fmi2CancelStep: doStep never runs asynchronously here");
}

EXPORT fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Status* value)
{
    (void)kind; (void)value;
    return refuse((Shim*)c, "fmi2GetStatus: doStep never runs asynchronously here");
}

EXPORT fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Real* value)
{
    (void)kind; (void)value;
    return refuse((Shim*)c, "fmi2GetRealStatus: doStep never runs asynchronously here");
}

EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Integer* value)
{
    (void)kind; (void)value;
    return refuse((Shim*)c, "fmi2GetIntegerStatus: doStep never runs asynchronously here");
}

EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Boolean* value)
{
    (void)kind; (void)value;
    return refuse((Shim*)c, "fmi2GetBooleanStatus: doStep never runs asynchronously here");
}

EXPORT fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind kind, fmi2String* value)
{
    (void)kind; (void)value;
    return refuse((Shim*)c, "fmi2GetStringStatus: doStep never runs asynchronously here");
}
