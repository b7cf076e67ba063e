/*
 * A small FMI 2.0 co-simulation host in C that behaves like the hosts we did not write: the FMU
 * compliance checker (fmuCheck) and OMSimulator. Compiled and run by tests/support/c_hosts.py.
 *
 *   fmi2_host [options] --fmu DIR IDENTIFIER GUID INPUT_VRS OUTPUT_VRS [--fmu ...]
 *
 * DIR is an extracted FMU; INPUT_VRS / OUTPUT_VRS are comma-separated Real value references ("-":
 * none). Options:
 *   --start T0           start time (default 0)
 *   --stop T --step H    keep time as t += h and trim the last step to land on T
 *                        (if t + h > T: h = T - t), which leaves tiny last steps after drift
 *   --stop T --steps N   the same with h = (T - T0) / N (fmuCheck's default is N = 500)
 *   --random SEED LO HI N GRID  N steps of random size, in turn: log-uniform in [LO, HI], uniform
 *                        in [LO, HI], and (GRID > 0) to a point t0 + m GRID 1 to 7 GRID ahead, so
 *                        that runs also stand on the grid of a sampled FMU (GRID = its Ts)
 *   --amplitude A --period P --square S   the inputs: u_j(t) = A (sin(2 pi t / P + j) + S q(t)),
 *                        where the square wave q is 1 on the first half of each period P and 0 on
 *                        the second (defaults A = 1, P = 0.05, S = 1)
 *   --instances N        instances of every FMU (default 1), all stepped side by side
 *   --teardown MODE      normal: fmi2Terminate, fmi2FreeInstance, dlclose at the end of main;
 *                        atexit: fmi2Terminate and fmi2FreeInstance from an exit handler registered
 *                        BEFORE the FMUs are loaded (so it runs after every handler they register);
 *                        atexit-terminate: only fmi2Terminate from that handler, never freed;
 *                        never: the instances are neither terminated nor freed
 *   --passes N           load, run and tear down N times in this process; every pass but the last
 *                        tears down normally and dlclose()s the FMUs (default 1)
 *   --probe H            first, one fmi2DoStep(T0, H) on every first instance, its status and
 *                        duration printed ("probe STATUS SECONDS"); it does not fail the run
 *   --csv PATH           one row per instance and communication point, after the inputs are set:
 *                        pass, fmu, instance, t, inputs..., outputs... (%.17g)
 *   --embed-python LIB   act as a Python host: load libpython LIB globally and start Python before
 *                        the FMUs, finalise it at the end of main (as a Python program's exit
 *                        does, before the C exit handlers). The exit-handler teardown then prints
 *                        "teardown STATUS" per fmi2Terminate instead of failing on a non-OK one.
 *   --set-real VR=VALUE  after an --fmu: set that FMU's Real VR to VALUE in initialization mode,
 *                        between fmi2EnterInitializationMode and fmi2ExitInitializationMode
 *                        (repeatable); every instance of every FMU enters initialization mode
 *                        before any leaves it, as in OMSimulator
 *   --on-error MODE      what a call answering anything but fmi2OK does (not in an exit handler):
 *                        exit: the process exits with status 2 (the default);
 *                        omsimulator: what OMSimulator 3.0 does when a run fails (oms_RunFile):
 *                        print "failed CALL STATUS"; terminate the system: every instance in turn
 *                        gets fmi2Terminate and, if that is fmi2OK, fmi2FreeInstance, and the first
 *                        one not fmi2OK ends the round (SystemWC::terminate,
 *                        ComponentFMUCS::terminate); if that round failed, terminate again with the
 *                        same handles, freed ones included (oms_terminate); if that failed too,
 *                        fmi2FreeInstance on every instance (deleting the model: ~ComponentFMUCS).
 *                        Each call is printed ("terminate NAME STATUS", "free NAME"), then "done",
 *                        and the process exits 0: only a crash fails it
 *   --calls LIST         instead of a run: instantiate one instance of the first FMU and make the
 *                        comma-separated calls in order, printing "CALL STATUS" for each (0..4),
 *                        then exit 0 (only a crash fails). CALL is one of setup, enter, set (the
 *                        --set-real values), exit, get (the outputs), step (h = --step, default
 *                        1e-3, from the time the host keeps), terminate, reset, free (printed as
 *                        "free -": it returns nothing). After free the host keeps the handle, as
 *                        OMSimulator does, so calls listed after it reach a freed instance
 * At every communication point the host sets the inputs, reads the outputs, then steps. Any call
 * that returns anything but fmi2OK makes the process exit with status 2 (3 from the exit handler).
 */
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "host_signals.h"

typedef void* fmi2Component;
typedef unsigned int fmi2ValueReference;
typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef void (*Logger)(void*, const char*, int, const char*, const char*, ...);
typedef struct {
    Logger logger;
    void* (*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void*);
    void (*stepFinished)(void*, int);
    void* componentEnvironment;
} Callbacks;

typedef fmi2Component (*Instantiate)(const char*, int, const char*, const char*, const Callbacks*, int, int);
typedef fmi2Status (*Setup)(fmi2Component, int, double, double, int, double);
typedef fmi2Status (*Phase)(fmi2Component);
typedef void (*Free)(fmi2Component);
typedef fmi2Status (*Reals)(fmi2Component, const fmi2ValueReference*, size_t, double*);
typedef fmi2Status (*Step)(fmi2Component, double, double, int);

#define MAX_FMUS 32  /* every FMU `shapefmu build` writes, in one process */
#define MAX_INSTANCES 8
#define MAX_VRS 64

typedef struct {
    const char* dir;
    const char* identifier;
    const char* guid;
    fmi2ValueReference in[MAX_VRS], out[MAX_VRS], set[MAX_VRS];
    double set_values[MAX_VRS];
    size_t n_in, n_out, n_set;
    void* lib;
    Instantiate instantiate;
    Setup setup;
    Phase enter, exit_init, terminate, reset;
    Free free_instance;
    Reals set_real, get_real;
    Step do_step;
    fmi2Component c[MAX_INSTANCES];
} Fmu;

static Fmu fmus[MAX_FMUS];
static int n_fmus = 0, n_instances = 1;
static const char* teardown = "normal";
static Callbacks callbacks;
static const char* embed_python = NULL;
static const char* on_error = "exit";

static void omsimulator_teardown(void);

static void logger(void* env, const char* name, int status, const char* category, const char* message, ...)
{
    va_list args;
    (void)env;
    fprintf(stderr, "[%d %s] %s: ", status, category != NULL ? category : "", name != NULL ? name : "");
    va_start(args, message);
    vfprintf(stderr, message, args);
    va_end(args);
    fputc('\n', stderr);
}

static void check(fmi2Status status, const char* call, const Fmu* f, double t, int in_exit_handler)
{
    if (status == fmi2OK) return;
    fprintf(stderr, "FAIL %s of %s returned status %d at t = %.17g\n", call, f->identifier, (int)status, t);
    fflush(stderr);
    if (in_exit_handler) _exit(3); /* exit() from an exit handler is undefined */
    if (strcmp(on_error, "omsimulator") == 0) {
        printf("failed %s %d\n", call, (int)status);
        omsimulator_teardown();
        printf("done\n");
        fflush(stdout);
        exit(0);
    }
    exit(2);
}

static void* symbol(Fmu* f, const char* name)
{
    void* p = dlsym(f->lib, name);
    if (p == NULL) {
        fprintf(stderr, "FAIL %s lacks %s\n", f->identifier, name);
        exit(2);
    }
    return p;
}

static void load(Fmu* f)
{
    char path[4096];
    snprintf(path, sizeof(path), "%s/binaries/linux64/%s.so", f->dir, f->identifier);
    f->lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (f->lib == NULL) {
        fprintf(stderr, "FAIL dlopen %s: %s\n", path, dlerror());
        exit(2);
    }
    *(void**)&f->instantiate = symbol(f, "fmi2Instantiate");
    *(void**)&f->setup = symbol(f, "fmi2SetupExperiment");
    *(void**)&f->enter = symbol(f, "fmi2EnterInitializationMode");
    *(void**)&f->exit_init = symbol(f, "fmi2ExitInitializationMode");
    *(void**)&f->terminate = symbol(f, "fmi2Terminate");
    *(void**)&f->reset = symbol(f, "fmi2Reset");
    *(void**)&f->free_instance = symbol(f, "fmi2FreeInstance");
    *(void**)&f->set_real = symbol(f, "fmi2SetReal");
    *(void**)&f->get_real = symbol(f, "fmi2GetReal");
    *(void**)&f->do_step = symbol(f, "fmi2DoStep");
}

static void terminate_all(int free_too, int in_exit_handler)
{
    int i, j;
    for (i = 0; i < n_fmus; i++) {
        for (j = 0; j < n_instances; j++) {
            if (fmus[i].c[j] == NULL) continue;
            if (embed_python != NULL && in_exit_handler) {
                printf("teardown %d\n", (int)fmus[i].terminate(fmus[i].c[j]));
                fflush(stdout);
            } else {
                check(fmus[i].terminate(fmus[i].c[j]), "fmi2Terminate", &fmus[i], NAN, in_exit_handler);
            }
            if (free_too) {
                fmus[i].free_instance(fmus[i].c[j]);
                fmus[i].c[j] = NULL;
            }
        }
    }
}

/* One round of OMSimulator's system terminate (see --on-error): 1 if every instance was terminated. */
static int omsimulator_terminate_round(void)
{
    int i, j, status;
    for (i = 0; i < n_fmus; i++) {
        for (j = 0; j < n_instances; j++) {
            if (fmus[i].c[j] == NULL) continue; /* never instantiated */
            status = (int)fmus[i].terminate(fmus[i].c[j]);
            printf("terminate %s_%d %d\n", fmus[i].identifier, j, status);
            fflush(stdout);
            if (status != fmi2OK) return 0;
            fmus[i].free_instance(fmus[i].c[j]); /* the handle is kept, as OMSimulator keeps it */
            printf("free %s_%d\n", fmus[i].identifier, j);
            fflush(stdout);
        }
    }
    return 1;
}

static void omsimulator_teardown(void)
{
    int i, j;
    if (omsimulator_terminate_round() || omsimulator_terminate_round()) return;
    for (i = 0; i < n_fmus; i++) {
        for (j = 0; j < n_instances; j++) {
            if (fmus[i].c[j] == NULL) continue;
            fmus[i].free_instance(fmus[i].c[j]);
            printf("free %s_%d\n", fmus[i].identifier, j);
            fflush(stdout);
        }
    }
}

static void teardown_at_exit(void)
{
    terminate_all(strcmp(teardown, "atexit") == 0, 1);
    fprintf(stderr, "exit handler: %s done\n", teardown);
}

static size_t parse_vrs(const char* text, fmi2ValueReference* vrs)
{
    size_t n = 0;
    char* end;
    if (strcmp(text, "-") == 0) return 0;
    while (*text != '\0' && n < MAX_VRS) {
        vrs[n++] = (fmi2ValueReference)strtoul(text, &end, 10);
        text = *end == ',' ? end + 1 : end;
        if (end == text && *end != '\0') break;
    }
    return n;
}

static double square = 1.0;

static double input(double t, size_t j, double amplitude, double period)
{
    return host_input(t, j, amplitude, period, square);
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void record(FILE* csv, int pass, double t, double amplitude, double period)
{
    double u[MAX_VRS], y[MAX_VRS];
    size_t k;
    int i, j;
    for (i = 0; i < n_fmus; i++) {
        Fmu* f = &fmus[i];
        for (k = 0; k < f->n_in; k++) u[k] = input(t, k, amplitude, period);
        for (j = 0; j < n_instances; j++) {
            if (f->n_in) check(f->set_real(f->c[j], f->in, f->n_in, u), "fmi2SetReal", f, t, 0);
            if (f->n_out) check(f->get_real(f->c[j], f->out, f->n_out, y), "fmi2GetReal", f, t, 0);
            if (csv == NULL) continue;
            fprintf(csv, "%d,%d,%d,%.17g", pass, i, j, t);
            for (k = 0; k < f->n_in; k++) fprintf(csv, ",%.17g", u[k]);
            for (k = 0; k < f->n_out; k++) fprintf(csv, ",%.17g", y[k]);
            fputc('\n', csv);
        }
    }
}

static void step_all(double t, double h)
{
    int i, j;
    for (i = 0; i < n_fmus; i++) {
        for (j = 0; j < n_instances; j++) check(fmus[i].do_step(fmus[i].c[j], t, h, 1), "fmi2DoStep", &fmus[i], t, 0);
    }
}

/* --calls: the listed calls on one instance of the first FMU, each status printed; 0 unless a
 * call is unknown (64) or the instance cannot be made (2). A crash is the host's signal. */
static int run_calls(char* list, double t0, double h)
{
    Fmu* f = &fmus[0];
    char uri[4200];
    double t = t0, y[MAX_VRS];
    char* call;
    int status;
    load(f);
    snprintf(uri, sizeof(uri), "file://%s/resources", f->dir);
    f->c[0] = f->instantiate(f->identifier, 1, f->guid, uri, &callbacks, 0, 0);
    if (f->c[0] == NULL) {
        fprintf(stderr, "FAIL fmi2Instantiate of %s returned NULL\n", f->identifier);
        return 2;
    }
    for (call = strtok(list, ","); call != NULL; call = strtok(NULL, ",")) {
        if (strcmp(call, "free") == 0) {
            f->free_instance(f->c[0]);
            printf("free -\n");
            fflush(stdout);
            continue;
        }
        if (strcmp(call, "setup") == 0) status = f->setup(f->c[0], 0, 0.0, t0, 0, 0.0);
        else if (strcmp(call, "enter") == 0) status = f->enter(f->c[0]);
        else if (strcmp(call, "set") == 0) status = f->set_real(f->c[0], f->set, f->n_set, f->set_values);
        else if (strcmp(call, "exit") == 0) status = f->exit_init(f->c[0]);
        else if (strcmp(call, "get") == 0) status = f->get_real(f->c[0], f->out, f->n_out, y);
        else if (strcmp(call, "terminate") == 0) status = f->terminate(f->c[0]);
        else if (strcmp(call, "reset") == 0) status = f->reset(f->c[0]);
        else if (strcmp(call, "step") == 0) {
            status = f->do_step(f->c[0], t, h, 1);
            if (status == fmi2OK) t += h;
        } else {
            fprintf(stderr, "usage: unknown call %s in --calls\n", call);
            return 64;
        }
        printf("%s %d\n", call, status);
        fflush(stdout);
    }
    return 0;
}

/* Start (start = 1) or finalise (0) the Python of --embed-python. */
static void python_host(int start)
{
    static void* lib = NULL;
    void (*call)(int);
    if (start) {
        lib = dlopen(embed_python, RTLD_NOW | RTLD_GLOBAL);
        if (lib == NULL) {
            fprintf(stderr, "FAIL dlopen %s: %s\n", embed_python, dlerror());
            exit(2);
        }
        *(void**)&call = dlsym(lib, "Py_InitializeEx");
        call(0);
    } else {
        *(void**)&call = dlsym(lib, "Py_FinalizeEx");
        ((int (*)(void))(void*)call)();
    }
}

int main(int argc, char** argv)
{
    double t0 = 0.0, stop = NAN, step = NAN, lo = 0.0, hi = 0.0, grid = 0.0, amplitude = 1.0, period = 0.05, probe = NAN;
    long steps = 0, random_steps = 0;
    int passes = 1, pass, a, i, j;
    const char* csv_path = NULL;
    char* calls = NULL;
    FILE* csv = NULL;
    for (a = 1; a < argc; a++) {
        const char* o = argv[a];
        int more = argc - a - 1;
        if (strcmp(o, "--fmu") == 0 && more >= 5 && n_fmus < MAX_FMUS) {
            Fmu* f = &fmus[n_fmus++];
            f->dir = argv[a + 1];
            f->identifier = argv[a + 2];
            f->guid = argv[a + 3];
            f->n_in = parse_vrs(argv[a + 4], f->in);
            f->n_out = parse_vrs(argv[a + 5], f->out);
            a += 5;
        } else if (strcmp(o, "--random") == 0 && more >= 5) {
            rng_state = strtoull(argv[a + 1], NULL, 10);
            lo = atof(argv[a + 2]);
            hi = atof(argv[a + 3]);
            random_steps = atol(argv[a + 4]);
            grid = atof(argv[a + 5]);
            a += 5;
        } else if (more >= 1 && strcmp(o, "--start") == 0) t0 = atof(argv[++a]);
        else if (more >= 1 && strcmp(o, "--stop") == 0) stop = atof(argv[++a]);
        else if (more >= 1 && strcmp(o, "--step") == 0) step = atof(argv[++a]);
        else if (more >= 1 && strcmp(o, "--steps") == 0) steps = atol(argv[++a]);
        else if (more >= 1 && strcmp(o, "--amplitude") == 0) amplitude = atof(argv[++a]);
        else if (more >= 1 && strcmp(o, "--period") == 0) period = atof(argv[++a]);
        else if (more >= 1 && strcmp(o, "--square") == 0) square = atof(argv[++a]);
        else if (more >= 1 && strcmp(o, "--instances") == 0) n_instances = atoi(argv[++a]);
        else if (more >= 1 && strcmp(o, "--teardown") == 0) teardown = argv[++a];
        else if (more >= 1 && strcmp(o, "--passes") == 0) passes = atoi(argv[++a]);
        else if (more >= 1 && strcmp(o, "--probe") == 0) probe = atof(argv[++a]);
        else if (more >= 1 && strcmp(o, "--csv") == 0) csv_path = argv[++a];
        else if (more >= 1 && strcmp(o, "--embed-python") == 0) embed_python = argv[++a];
        else if (more >= 1 && strcmp(o, "--on-error") == 0) on_error = argv[++a];
        else if (more >= 1 && strcmp(o, "--calls") == 0) calls = argv[++a];
        else if (more >= 1 && strcmp(o, "--set-real") == 0 && n_fmus > 0 && fmus[n_fmus - 1].n_set < MAX_VRS
                 && strchr(argv[a + 1], '=') != NULL) {
            Fmu* f = &fmus[n_fmus - 1];
            f->set[f->n_set] = (fmi2ValueReference)strtoul(argv[++a], NULL, 10);
            f->set_values[f->n_set++] = atof(strchr(argv[a], '=') + 1);
        }
        else {
            fprintf(stderr, "usage: see the comment at the top of fmi2_host.c (bad argument %s)\n", o);
            return 64;
        }
    }
    callbacks.logger = logger;
    callbacks.allocateMemory = calloc;
    callbacks.freeMemory = free;
    if (calls != NULL && n_fmus > 0) return run_calls(calls, t0, isnan(step) ? 1e-3 : step);
    if (n_fmus == 0 || n_instances < 1 || n_instances > MAX_INSTANCES || passes < 1
        || (random_steps == 0 && (isnan(stop) || (isnan(step) && steps <= 0)))) {
        fprintf(stderr, "usage: see the comment at the top of fmi2_host.c\n");
        return 64;
    }
    if (steps > 0) step = (stop - t0) / (double)steps;
    /* Registered before any FMU is loaded: it runs after every exit handler the FMUs register. */
    if (strncmp(teardown, "atexit", 6) == 0) atexit(teardown_at_exit);
    if (csv_path != NULL && (csv = fopen(csv_path, "w")) == NULL) {
        perror(csv_path);
        return 2;
    }
    if (embed_python != NULL) python_host(1);
    for (pass = 0; pass < passes; pass++) {
        double t = t0, h;
        long k;
        for (i = 0; i < n_fmus; i++) {
            Fmu* f = &fmus[i];
            char uri[4200], name[64];
            load(f);
            snprintf(uri, sizeof(uri), "file://%s/resources", f->dir);
            for (j = 0; j < n_instances; j++) {
                snprintf(name, sizeof(name), "%s_%d", f->identifier, j);
                f->c[j] = f->instantiate(name, 1, f->guid, uri, &callbacks, 0, 0);
                if (f->c[j] == NULL) {
                    fprintf(stderr, "FAIL fmi2Instantiate of %s returned NULL\n", f->identifier);
                    return 2;
                }
                check(f->setup(f->c[j], 0, 0.0, t0, 0, 0.0), "fmi2SetupExperiment", f, t0, 0);
                check(f->enter(f->c[j]), "fmi2EnterInitializationMode", f, t0, 0);
                if (f->n_set > 0) check(f->set_real(f->c[j], f->set, f->n_set, f->set_values), "fmi2SetReal", f, t0, 0);
            }
        }
        /* As OMSimulator does: every instance is made and in initialization mode before any leaves it. */
        for (i = 0; i < n_fmus; i++) {
            for (j = 0; j < n_instances; j++) check(fmus[i].exit_init(fmus[i].c[j]), "fmi2ExitInitializationMode", &fmus[i], t0, 0);
        }
        if (!isnan(probe)) {
            for (i = 0; i < n_fmus; i++) {
                double begin = now();
                fmi2Status status = fmus[i].do_step(fmus[i].c[0], t0, probe, 1);
                printf("probe %d %.6f\n", (int)status, now() - begin);
            }
        }
        record(csv, pass, t, amplitude, period);
        if (random_steps > 0) {
            for (k = 0; k < random_steps; k++) {
                double r = uniform01();
                if (k % 3 == 1) {
                    h = lo + (hi - lo) * r;
                } else if (k % 3 == 2 && grid > 0.0) {
                    h = t0 + (floor((t - t0) / grid) + 1.0 + floor(7.0 * r)) * grid - t;
                } else {
                    h = lo * pow(hi / lo, r);
                }
                step_all(t, h);
                t += h;
                record(csv, pass, t, amplitude, period);
            }
        } else {
            while (t < stop) {
                h = step;
                if (t + h > stop) h = stop - t; /* the trimmed last step of fmuCheck and OMSimulator */
                step_all(t, h);
                t += h;
                record(csv, pass, t, amplitude, period);
            }
        }
        if (pass < passes - 1 || strcmp(teardown, "normal") == 0) {
            terminate_all(1, 0);
            for (i = 0; i < n_fmus; i++) {
                if (dlclose(fmus[i].lib) != 0) {
                    fprintf(stderr, "FAIL dlclose %s: %s\n", fmus[i].identifier, dlerror());
                    return 2;
                }
                fmus[i].lib = NULL;
            }
        }
    }
    if (csv != NULL) fclose(csv);
    if (embed_python != NULL) python_host(0);
    printf("done\n");
    fflush(stdout);
    return 0;
}
