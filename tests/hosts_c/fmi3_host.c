/*
 * A small FMI 3.0 Co-Simulation host in C that behaves like the hosts we did not write (the FMI 3.0
 * twin of fmi2_host.c, with its time keeping, inputs and CSV, so the two hosts' rows of an FMI 2.0
 * FMU and of its FMI 3.0 twin compare line by line). Compiled and run by tests/test_native_fmi3.py,
 * for Linux (dlopen), and cross-compiled for Windows (LoadLibrary, run under Wine) and ARM Linux
 * (run under qemu), so that one FMU's libraries for the three platforms run the same simulation.
 *
 *   fmi3_host [options] --fmu DIR IDENTIFIER TOKEN INPUT_VRS OUTPUT_VRS
 *
 * DIR is an extracted FMU; INPUT_VRS / OUTPUT_VRS are comma-separated Float64 value references of
 * scalars ("-": none). Options:
 *   --stop T --steps N   keep time as t += h with h = T / N and trim the last step to land on T
 *                        (if t + h > T: h = T - t), as fmuCheck and OMSimulator do
 *   --random SEED LO HI N   N steps of random size as fmi2_host's --random SEED LO HI N 0 takes them:
 *                        in turn log-uniform, uniform and log-uniform in [LO, HI] (splitmix64)
 *   --amplitude A --period P   the inputs u_j(t) = A (sin(2 pi t / P + j) + q(t)), q the square wave
 *                        1 on the first half of each period (defaults A = 1, P = 0.05), as fmi2_host
 *   --set VR=V1[,V2...]  in initialization mode: set Float64 variable VR (an array takes its
 *                        elements in order; repeatable)
 *   --clock VR TS        the FMU's periodic input clock VR ticks every TS from t = 0: instantiate with
 *                        Event Mode, end every step at the next tick, and at each tick (t = 0 just
 *                        after initialisation included) set the inputs in Event Mode, fmi3SetClock,
 *                        fmi3UpdateDiscreteStates, fmi3EnterStepMode; inputs are set at ticks only
 *                        (they are clocked), the CSV's input columns still say u_j(t)
 *   --teardown MODE      normal: fmi3Terminate, fmi3FreeInstance, dlclose at the end of main;
 *                        atexit: fmi3Terminate and fmi3FreeInstance from an exit handler registered
 *                        before the FMU is loaded (so it runs after every handler the FMU registers)
 *   --library PATH       load this library (default DIR/binaries/x86_64-linux/IDENTIFIER.so)
 *   --csv PATH           one row per communication point, after the inputs are set:
 *                        0, 0, 0, t, inputs..., outputs... (%.17g), as fmi2_host writes them
 * Any call that returns anything but fmi3OK makes the process exit with status 2 (3 from the exit
 * handler).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3FunctionTypes.h"

#ifdef _WIN32
#include <windows.h>
static void *dlopen(const char *path, int flags) { (void)flags; return (void *)LoadLibraryA(path); }
static void *dlsym(void *library, const char *name) { return (void *)GetProcAddress((HMODULE)library, name); }
static int dlclose(void *library) { return FreeLibrary((HMODULE)library) ? 0 : 1; }
static const char *dlerror(void) { return "LoadLibrary failed"; }
#define RTLD_NOW 0
#define RTLD_LOCAL 0
#else
#include <dlfcn.h>
#include <unistd.h>
#endif

#include "host_signals.h"

#define MAX_VRS 64
#define MAX_SETS 32
#define MAX_ELEMENTS 4096

static void* lib;
static fmi3Instance instance;
static fmi3TerminateTYPE* terminate_;
static fmi3FreeInstanceTYPE* free_instance;

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message)
{
    (void)env;
    fprintf(stderr, "[%d %s] %s\n", (int)status, category != NULL ? category : "", message != NULL ? message : "");
}

static void check(fmi3Status status, const char* call, double t, int in_exit_handler)
{
    if (status == fmi3OK) return;
    fprintf(stderr, "FAIL %s returned status %d at t = %.17g\n", call, (int)status, t);
    fflush(stderr);
    if (in_exit_handler) _exit(3); /* exit() from an exit handler is undefined */
    exit(2);
}

static void* symbol(const char* name)
{
    void* p = dlsym(lib, name);
    if (p == NULL) {
        fprintf(stderr, "FAIL the FMU lacks %s\n", name);
        exit(2);
    }
    return p;
}

static void teardown_at_exit(void)
{
    check(terminate_(instance), "fmi3Terminate", NAN, 1);
    free_instance(instance);
    fprintf(stderr, "exit handler: atexit done\n");
}

static size_t parse_list(const char* text, double* values, size_t capacity)
{
    size_t n = 0;
    char* end;
    if (strcmp(text, "-") == 0) return 0;
    while (n < capacity) {
        values[n++] = strtod(text, &end);
        if (*end != ',') break;
        text = end + 1;
    }
    return n;
}

static double input(double t, size_t j, double amplitude, double period)
{
    return host_input(t, j, amplitude, period, 1.0);
}

int main(int argc, char** argv)
{
    const char *dir = NULL, *identifier = NULL, *token = NULL, *teardown = "normal", *csv_path = NULL, *library = NULL;
    double stop = NAN, amplitude = 1.0, period = 0.05, lo = 0.0, hi = 0.0, buffer[MAX_VRS];
    long steps = 0, random_steps = 0;
    fmi3ValueReference in[MAX_VRS], out[MAX_VRS], set_vr[MAX_SETS];
    static double set_values[MAX_SETS][MAX_ELEMENTS];
    size_t n_in = 0, n_out = 0, n_set = 0, set_count[MAX_SETS], k;
    fmi3ValueReference clock_vr = 0;
    double clock_ts = 0.0;
    for (int a = 1; a < argc; a++) {
        const char* o = argv[a];
        int more = argc - 1 - a;
        if (more >= 1 && strcmp(o, "--stop") == 0) stop = atof(argv[++a]);
        else if (more >= 1 && strcmp(o, "--steps") == 0) steps = atol(argv[++a]);
        else if (more >= 4 && strcmp(o, "--random") == 0) {
            rng_state = strtoull(argv[++a], NULL, 10);
            lo = atof(argv[++a]), hi = atof(argv[++a]), random_steps = atol(argv[++a]);
        }
        else if (more >= 1 && strcmp(o, "--amplitude") == 0) amplitude = atof(argv[++a]);
        else if (more >= 1 && strcmp(o, "--period") == 0) period = atof(argv[++a]);
        else if (more >= 1 && strcmp(o, "--teardown") == 0) teardown = argv[++a];
        else if (more >= 2 && strcmp(o, "--clock") == 0) {
            clock_vr = (fmi3ValueReference)strtoul(argv[++a], NULL, 10);
            clock_ts = atof(argv[++a]);
        }
        else if (more >= 1 && strcmp(o, "--csv") == 0) csv_path = argv[++a];
        else if (more >= 1 && strcmp(o, "--library") == 0) library = argv[++a];
        else if (more >= 1 && strcmp(o, "--set") == 0 && n_set < MAX_SETS) {
            char* equals = strchr(argv[++a], '=');
            if (equals == NULL) return 64;
            set_vr[n_set] = (fmi3ValueReference)strtoul(argv[a], NULL, 10);
            set_count[n_set] = parse_list(equals + 1, set_values[n_set], MAX_ELEMENTS);
            n_set++;
        }
        else if (more >= 5 && strcmp(o, "--fmu") == 0) {
            dir = argv[++a], identifier = argv[++a], token = argv[++a];
            n_in = parse_list(argv[++a], buffer, MAX_VRS);
            for (k = 0; k < n_in; k++) in[k] = (fmi3ValueReference)buffer[k];
            n_out = parse_list(argv[++a], buffer, MAX_VRS);
            for (k = 0; k < n_out; k++) out[k] = (fmi3ValueReference)buffer[k];
        }
        else {
            fprintf(stderr, "usage: see the comment at the top of fmi3_host.c (at %s)\n", o);
            return 64;
        }
    }
    if (dir == NULL || (random_steps == 0 && (isnan(stop) || steps <= 0))) {
        fprintf(stderr, "usage: see the comment at the top of fmi3_host.c\n");
        return 64;
    }
    /* Registered before the FMU is loaded: it runs after every exit handler the FMU registers. */
    if (strcmp(teardown, "atexit") == 0) atexit(teardown_at_exit);
    FILE* csv = csv_path != NULL ? fopen(csv_path, "w") : NULL;
    char path[4096];
    if (library != NULL) snprintf(path, sizeof(path), "%s", library);
    else snprintf(path, sizeof(path), "%s/binaries/x86_64-linux/%s.so", dir, identifier);
    if ((lib = dlopen(path, RTLD_NOW | RTLD_LOCAL)) == NULL) {
        fprintf(stderr, "FAIL dlopen %s: %s\n", path, dlerror());
        return 2;
    }
    fmi3InstantiateCoSimulationTYPE* instantiate = (fmi3InstantiateCoSimulationTYPE*)symbol("fmi3InstantiateCoSimulation");
    fmi3EnterInitializationModeTYPE* enter = (fmi3EnterInitializationModeTYPE*)symbol("fmi3EnterInitializationMode");
    fmi3ExitInitializationModeTYPE* exit_init = (fmi3ExitInitializationModeTYPE*)symbol("fmi3ExitInitializationMode");
    fmi3SetFloat64TYPE* set_float64 = (fmi3SetFloat64TYPE*)symbol("fmi3SetFloat64");
    fmi3GetFloat64TYPE* get_float64 = (fmi3GetFloat64TYPE*)symbol("fmi3GetFloat64");
    fmi3DoStepTYPE* do_step = (fmi3DoStepTYPE*)symbol("fmi3DoStep");
    fmi3EnterEventModeTYPE* enter_event = (fmi3EnterEventModeTYPE*)symbol("fmi3EnterEventMode");
    fmi3SetClockTYPE* set_clock = (fmi3SetClockTYPE*)symbol("fmi3SetClock");
    fmi3UpdateDiscreteStatesTYPE* update = (fmi3UpdateDiscreteStatesTYPE*)symbol("fmi3UpdateDiscreteStates");
    fmi3EnterStepModeTYPE* enter_step = (fmi3EnterStepModeTYPE*)symbol("fmi3EnterStepMode");
    terminate_ = (fmi3TerminateTYPE*)symbol("fmi3Terminate");
    free_instance = (fmi3FreeInstanceTYPE*)symbol("fmi3FreeInstance");
    snprintf(path, sizeof(path), "%s/resources/", dir);
    instance = instantiate("host", token, path, fmi3False, fmi3False, clock_ts > 0.0, fmi3False, NULL, 0, NULL, logger, NULL);
    if (instance == NULL) {
        fprintf(stderr, "FAIL fmi3InstantiateCoSimulation returned NULL\n");
        return 2;
    }
    check(enter(instance, fmi3False, 0.0, 0.0, fmi3False, 0.0), "fmi3EnterInitializationMode", 0.0, 0);
    for (k = 0; k < n_set; k++) check(set_float64(instance, &set_vr[k], 1, set_values[k], set_count[k]), "fmi3SetFloat64", 0.0, 0);
    check(exit_init(instance), "fmi3ExitInitializationMode", 0.0, 0);
    double t = 0.0, h = steps > 0 ? stop / (double)steps : 0.0, u[MAX_VRS], y[MAX_VRS];
    long tick = 0;  /* the next tick, tick * clock_ts */
    for (long n = 0;; n++) {
        for (k = 0; k < n_in; k++) u[k] = input(t, k, amplitude, period);
        const int at_tick = clock_ts > 0.0 && fabs(t - (double)tick * clock_ts) <= 1e-6 * clock_ts;
        if (at_tick) {  /* after initialisation the FMU is in Event Mode already */
            if (n > 0) check(enter_event(instance), "fmi3EnterEventMode", t, 0);
            if (n_in) check(set_float64(instance, in, n_in, u, n_in), "fmi3SetFloat64", t, 0);
            const fmi3Clock active = fmi3True;
            check(set_clock(instance, &clock_vr, 1, &active), "fmi3SetClock", t, 0);
            fmi3Boolean more_updates, stop_now, nominals, values, defined;
            fmi3Float64 next_event;
            check(update(instance, &more_updates, &stop_now, &nominals, &values, &defined, &next_event),
                  "fmi3UpdateDiscreteStates", t, 0);
            check(enter_step(instance), "fmi3EnterStepMode", t, 0);
            tick++;
        } else if (n_in && clock_ts == 0.0) {
            check(set_float64(instance, in, n_in, u, n_in), "fmi3SetFloat64", t, 0);
        }
        if (n_out) check(get_float64(instance, out, n_out, y, n_out), "fmi3GetFloat64", t, 0);
        if (csv != NULL) {
            fprintf(csv, "0,0,0,%.17g", t);
            for (k = 0; k < n_in; k++) fprintf(csv, ",%.17g", u[k]);
            for (k = 0; k < n_out; k++) fprintf(csv, ",%.17g", y[k]);
            fputc('\n', csv);
        }
        double step = h;
        if (random_steps > 0) {
            if (n == random_steps) break;
            const double r = uniform01();
            step = n % 3 == 1 ? lo + (hi - lo) * r : lo * pow(hi / lo, r);
        } else {
            if (!(t < stop)) break;
            if (t + step > stop) step = stop - t; /* the trimmed last step of fmuCheck and OMSimulator */
        }
        /* a step that would pass the next tick ends there; one landing on it within 1e-6 Ts (the FMU's
         * tolerance, sample_clock.h) is kept, so t += h as fmi2_host keeps it */
        if (clock_ts > 0.0 && t + step > (double)tick * clock_ts + 1e-6 * clock_ts)
            step = (double)tick * clock_ts - t;
        fmi3Boolean event, terminate, early;
        fmi3Float64 last;
        check(do_step(instance, t, step, fmi3True, &event, &terminate, &early, &last), "fmi3DoStep", t, 0);
        t += step;
    }
    if (csv != NULL) fclose(csv);
    if (strcmp(teardown, "normal") == 0) {
        check(terminate_(instance), "fmi3Terminate", t, 0);
        free_instance(instance);
        if (dlclose(lib) != 0) return 2;
    }
    printf("done\n");
    fflush(stdout);
    return 0;
}
