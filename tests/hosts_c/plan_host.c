/* A minimal FMI 2.0 Co-Simulation host in C, compiled for Linux (dlopen) and cross-compiled for
 * Windows (LoadLibrary, run under Wine) and ARM Linux (run under qemu) by tests/support/cross_platform.py,
 * so that one FMU's linux64, win64 and aarch64-linux binaries run the same simulation and their outputs
 * can be compared.
 *
 * Usage: plan_host PLAN. The plan is a text file of lines, one FMU after another:
 *   fmu LIBRARY GUID          load the shared library, instantiate a Co-Simulation instance
 *   real VR VALUE             a Real start value (set in Initialization Mode); integer, string alike
 *   input VR SCALE            the input driven with SCALE * u_k (none without this line)
 *   output VR                 an output read after every step (repeatable)
 *   run STEPS H               initialise, then STEPS steps of H: set the input, doStep, read outputs
 * u_k = ((k * 7919) % 200) / 100 - 1 (exact in binary floating point, so both platforms see the
 * same inputs). Each run prints one line: the outputs after every step, %.17g, space-separated.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#ifdef _WIN32
#include <windows.h>
typedef HMODULE Library;
static Library open_library(const char *path) { return LoadLibraryA(path); }
static void *symbol(Library library, const char *name) { return (void *)GetProcAddress(library, name); }
static void close_library(Library library) { FreeLibrary(library); }
#else
#include <dlfcn.h>
typedef void *Library;
static Library open_library(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *symbol(Library library, const char *name) { return dlsym(library, name); }
static void close_library(Library library) { dlclose(library); }
#endif

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env; (void)category;
    va_list args;
    va_start(args, message);
    fprintf(stderr, "[%s %d] ", name, (int)status);
    vfprintf(stderr, message, args);
    fprintf(stderr, "\n");
    va_end(args);
}

#define MAX_ITEMS 16
#define CHECK(call) do { if ((call) > fmi2Warning) { fprintf(stderr, "failed: %s\n", #call); return 1; } } while (0)

typedef struct {
    Library library;
    fmi2Component c;
    fmi2SetRealTYPE *setReal;
    fmi2SetIntegerTYPE *setInteger;
    fmi2SetStringTYPE *setString;
    fmi2GetRealTYPE *getReal;
    fmi2DoStepTYPE *doStep;
    fmi2ValueReference input, outputs[MAX_ITEMS];
    double scale;
    int n_outputs, has_input;
} Host;

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: %s PLAN\n", argv[0]);
        return 2;
    }
    FILE *plan = fopen(argv[1], "r");
    if (plan == NULL) return 2;
    const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    Host host;
    memset(&host, 0, sizeof host);
    fmi2ExitInitializationModeTYPE *exit_ = NULL;
    fmi2FreeInstanceTYPE *free_instance = NULL;
    char word[32], text[1024], guid[128];
    while (fscanf(plan, "%31s", word) == 1) {
        if (strcmp(word, "fmu") == 0) {
            if (fscanf(plan, "%1023s %127s", text, guid) != 2) return 2;
            memset(&host, 0, sizeof host);
            host.library = open_library(text);
            if (host.library == NULL) { fprintf(stderr, "cannot load %s\n", text); return 1; }
            fmi2InstantiateTYPE *instantiate = (fmi2InstantiateTYPE *)symbol(host.library, "fmi2Instantiate");
            fmi2SetupExperimentTYPE *setup = (fmi2SetupExperimentTYPE *)symbol(host.library, "fmi2SetupExperiment");
            fmi2EnterInitializationModeTYPE *enter = (fmi2EnterInitializationModeTYPE *)symbol(host.library, "fmi2EnterInitializationMode");
            exit_ = (fmi2ExitInitializationModeTYPE *)symbol(host.library, "fmi2ExitInitializationMode");
            free_instance = (fmi2FreeInstanceTYPE *)symbol(host.library, "fmi2FreeInstance");
            host.setReal = (fmi2SetRealTYPE *)symbol(host.library, "fmi2SetReal");
            host.setInteger = (fmi2SetIntegerTYPE *)symbol(host.library, "fmi2SetInteger");
            host.setString = (fmi2SetStringTYPE *)symbol(host.library, "fmi2SetString");
            host.getReal = (fmi2GetRealTYPE *)symbol(host.library, "fmi2GetReal");
            host.doStep = (fmi2DoStepTYPE *)symbol(host.library, "fmi2DoStep");
            if (!instantiate || !setup || !enter || !exit_ || !free_instance || !host.setReal || !host.getReal
                || !host.doStep) { fprintf(stderr, "missing FMI functions in %s\n", text); return 1; }
            host.c = instantiate("host", fmi2CoSimulation, guid, "", &callbacks, fmi2False, fmi2False);
            if (host.c == NULL) return 1;
            CHECK(setup(host.c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
            CHECK(enter(host.c));
        } else if (strcmp(word, "real") == 0) {
            fmi2ValueReference vr;
            double value;
            if (fscanf(plan, "%u %lf", &vr, &value) != 2) return 2;
            CHECK(host.setReal(host.c, &vr, 1, &value));
        } else if (strcmp(word, "integer") == 0) {
            fmi2ValueReference vr;
            int value;
            if (fscanf(plan, "%u %d", &vr, &value) != 2) return 2;
            CHECK(host.setInteger(host.c, &vr, 1, &value));
        } else if (strcmp(word, "string") == 0) {
            fmi2ValueReference vr;
            if (fscanf(plan, "%u %1023s", &vr, text) != 2) return 2;
            const char *value = text;
            CHECK(host.setString(host.c, &vr, 1, &value));
        } else if (strcmp(word, "input") == 0) {
            if (fscanf(plan, "%u %lf", &host.input, &host.scale) != 2) return 2;
            host.has_input = 1;
        } else if (strcmp(word, "output") == 0) {
            if (host.n_outputs == MAX_ITEMS || fscanf(plan, "%u", &host.outputs[host.n_outputs]) != 1) return 2;
            host.n_outputs++;
        } else if (strcmp(word, "run") == 0) {
            long steps;
            double h;
            if (fscanf(plan, "%ld %lf", &steps, &h) != 2) return 2;
            CHECK(exit_(host.c));
            for (long k = 0; k < steps; k++) {
                const double u = host.scale * ((double)((k * 7919) % 200) / 100.0 - 1.0);
                if (host.has_input) CHECK(host.setReal(host.c, &host.input, 1, &u));
                CHECK(host.doStep(host.c, (double)k * h, h, fmi2True));
                double y[MAX_ITEMS];
                CHECK(host.getReal(host.c, host.outputs, (size_t)host.n_outputs, y));
                for (int i = 0; i < host.n_outputs; i++) printf("%.17g ", y[i]);
            }
            printf("\n");
            free_instance(host.c);
            close_library(host.library);
        } else {
            fprintf(stderr, "unknown plan line %s\n", word);
            return 2;
        }
    }
    fclose(plan);
    return 0;
}
