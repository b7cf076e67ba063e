/*
 * The Python part of the FMU's C front end (fmi2_shim.c and fmu_states.c have the FMI entry
 * points): finds libpython, starts the interpreter, loads pythonfmu's export library, and keeps
 * the interpreter alive for as long as the process runs.
 *
 * libpython. pythonfmu's export library embeds Python but is not linked against libpython: in a
 * host with no Python of its own (ecos, libcosim, OMSimulator, Simulink, Dymola) its Py* symbols
 * are unresolved, and extension modules loaded later need libpython's symbols in the global scope.
 * So libpython is made global before the export library is loaded: if the process already has
 * Python (fmpy, a Python host) nothing is loaded; otherwise the libpython recorded at build time
 * (SHIM_LIBPYTHON) is dlopen()ed with RTLD_GLOBAL, falling back to the sonames
 * libpython3.<minor>.so.1.0 for the minor versions in SHIM_FALLBACK_MINORS (the build's first).
 * The recorded library gets its own home (SHIM_PYTHONHOME, the build interpreter's base prefix)
 * unless the host set PYTHONHOME: started under the program name "./PythonFMU", Python cannot find
 * its standard library by itself and would take another installation's (e.g. /usr/lib/python3.11
 * without lib-dynload's math module). When none is found, fmi2Instantiate logs what was tried and
 * what to install, and returns NULL.
 *
 * The interpreter is started here and never finalised. pythonfmu 0.7.0 starts Python itself when
 * nobody has (from a thread of its own, its PyState) and finalises it as soon as its static
 * pointer to that state is reset -- instances hold no reference to it. The pointer is reset by the
 * exit handler below (registered when the export library is loaded) or by the library's
 * destructor. In a C/C++ host the interpreter was thus finalised at process exit while instances
 * still lived, and a host that terminates or frees them from an exit handler registered before it
 * loaded the FMU (exit handlers run in reverse order of registration, so that one runs after ours;
 * OMSimulator does this) crashed: fmi2Terminate -> PyGILState_Ensure -> PyThreadState_New with no
 * interpreter, SIGSEGV. Now this front end initialises Python before the export library's first
 * instance, so pythonfmu finds it running and never finalises it, and the front end never does:
 * fmi2Terminate and fmi2FreeInstance work from any exit handler, with instances never freed, after
 * dlclose and a second load. Nothing an FMU runs needs finalisation (the slaves hold no files,
 * threads or atexit hooks; the system reclaims the memory at exit). Should another party finalise
 * the interpreter (a Python host at its own exit, another FMU that started it), runtime_alive()
 * turns 0 and the front end refuses every call instead of entering the export library.
 *
 * Py_InitializeEx(0): Python installs no signal handlers, so Ctrl-C still stops a C host.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <wchar.h>

#include "fmi2_shim.h"

#ifndef SHIM_LIBPYTHON
#define SHIM_LIBPYTHON ""
#endif
#ifndef SHIM_PYTHONHOME
#define SHIM_PYTHONHOME ""
#endif
#ifndef SHIM_FALLBACK_MINORS
#error "compile with -DSHIM_FALLBACK_MINORS=<minor>,<minor>,..."
#endif
#ifndef SHIM_INNER_NAME
#error "compile with -DSHIM_INNER_NAME=\"<modelIdentifier>_pythonfmu.so\""
#endif

Inner inner;
static void* inner_handle = NULL;
static int inner_ready = 0; /* libpython global, Python running, export library loaded, entry points found */
static int (*is_initialized)(void) = NULL;
static pthread_mutex_t load_lock = PTHREAD_MUTEX_INITIALIZER;

int runtime_alive(void)
{
    return is_initialized != NULL && is_initialized();
}

/* Point a not yet initialised interpreter at the standard library it was built with. */
static void set_python_home(void)
{
    static wchar_t home[4096];
    void (*set_home)(const wchar_t*);
    const char* from_host = getenv("PYTHONHOME");
    if (SHIM_PYTHONHOME[0] == '\0' || (from_host != NULL && from_host[0] != '\0')) return;
    *(void**)(&set_home) = dlsym(RTLD_DEFAULT, "Py_SetPythonHome");
    if (set_home != NULL && mbstowcs(home, SHIM_PYTHONHOME, sizeof(home) / sizeof(home[0]) - 1) != (size_t)-1) {
        set_home(home);
    } else {
        setenv("PYTHONHOME", SHIM_PYTHONHOME, 0); /* Python >= 3.13 has no Py_SetPythonHome */
    }
}

/* 1 if libpython's symbols are (now) in the global scope; else 0 and why (what was tried, what to do). */
static int open_libpython(char* why, size_t why_size)
{
    static const int minors[] = {SHIM_FALLBACK_MINORS};
    char recorded[1024] = "none was recorded (the build interpreter has no shared libpython)";
    char tried[512] = "";
    char soname[64];
    void* handle;
    size_t i;
    /* A Python host (fmpy), or an earlier load of a front end, has libpython global already:
     * loading a second copy would start a second interpreter in the same process. */
    if (dlsym(RTLD_DEFAULT, "Py_IsInitialized") != NULL) return 1;
    if (SHIM_LIBPYTHON[0] != '\0') {
        handle = dlopen(SHIM_LIBPYTHON, RTLD_NOW | RTLD_GLOBAL);
        if (handle != NULL) {
            set_python_home();
            return 1;
        }
        snprintf(recorded, sizeof(recorded), "the one recorded at build time failed to load (%s)", dlerror());
    }
    for (i = 0; i < sizeof(minors) / sizeof(minors[0]); i++) {
        snprintf(soname, sizeof(soname), "libpython3.%d.so.1.0", minors[i]);
        handle = dlopen(soname, RTLD_NOW | RTLD_GLOBAL);
        if (handle != NULL) return 1;
        snprintf(tried + strlen(tried), sizeof(tried) - strlen(tried), "%s%s", i ? ", " : "", soname);
    }
    snprintf(why, why_size,
        "no usable libpython: %s, and none of the sonames %s is on the library path (ld.so.cache, "
        "LD_LIBRARY_PATH). Install the shared library of Python 3.%d (e.g. Debian/Ubuntu: apt install "
        "libpython3.%d) or add the directory that holds libpython3.%d.so.1.0 to LD_LIBRARY_PATH",
        recorded, tried, minors[0], minors[0], minors[0]);
    return 0;
}

/* Start the interpreter unless it runs already (a Python host, another FMU); see the top comment. */
static int start_python(char* why, size_t why_size)
{
    void (*initialize)(int);
    void* (*save_thread)(void);
    void (*set_program_name)(const wchar_t*);
    *(void**)(&is_initialized) = dlsym(RTLD_DEFAULT, "Py_IsInitialized");
    *(void**)(&initialize) = dlsym(RTLD_DEFAULT, "Py_InitializeEx");
    *(void**)(&save_thread) = dlsym(RTLD_DEFAULT, "PyEval_SaveThread");
    *(void**)(&set_program_name) = dlsym(RTLD_DEFAULT, "Py_SetProgramName");
    if (is_initialized == NULL || initialize == NULL || save_thread == NULL) {
        snprintf(why, why_size, "the libpython found lacks Py_IsInitialized, Py_InitializeEx or PyEval_SaveThread");
        return 0;
    }
    if (is_initialized()) return 1;
    /* The program name pythonfmu gives it, so that Python finds its prefix as it always did here. */
    if (set_program_name != NULL) set_program_name(L"./PythonFMU");
    initialize(0);
    /* Release the GIL: the export library takes it with PyGILState_Ensure in every call, from
     * whichever thread the host calls. The thread state is kept for good (never finalised). */
    save_thread();
    return 1;
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

/* pythonfmu 0.7.0's library destructor (finalizePythonInterpreter) resets a static
 * std::shared_ptr that the C++ exit handlers have already destroyed: a write into freed memory at
 * process exit, seen as "corrupted double-linked list" aborts. Right after loading the export
 * library the front end registers that same function as a process exit handler: exit handlers run
 * in reverse order of registration, so it resets the pointer while it is still alive (with the
 * interpreter started here, resetting it finalises nothing). Registered once per copy of the export
 * library; the handler lives in it, and it is never unloaded (RTLD_NODELETE), so it is mapped at
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

static int load_locked(char* why, size_t why_size)
{
    Dl_info info;
    char path[4096];
    char* slash;
    int first_load;
    if (!open_libpython(why, why_size) || !start_python(why, why_size)) return 0;
    if (dladdr((void*)&load_locked, &info) == 0 || info.dli_fname == NULL) {
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

int runtime_load(char* why, size_t why_size)
{
    int ready;
    /* Hosts may instantiate from several threads at once (libcosim, OMSimulator). */
    pthread_mutex_lock(&load_lock);
    ready = inner_ready || load_locked(why, why_size);
    pthread_mutex_unlock(&load_lock);
    return ready;
}
