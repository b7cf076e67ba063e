/* What the valgrind drivers (valgrind_*.c) share, whatever their FMI version. tests/support/valgrind.py
 * compiles a driver with an FMU's own sources and fmu_description.h, which it writes from the FMU's
 * modelDescription.xml: FMU_GUID (the GUID, or the FMI 3.0 instantiation token), N_STATES, and
 * VARIABLES, each variable's name, value reference, causality and start value as declared. A driver
 * knows the FMU only through those and the FMI API, as a host does.
 *
 * CHECK(call): the call returns OK (fmi2OK, fmi3OK: 0), or the driver fails naming it.
 * REFUSED(call): the call returns Error (fmi2Error, fmi3Error: 3) after logging exactly one error.
 * The driver's logger counts the errors in errors_logged.
 */
#ifndef DRIVER_H
#define DRIVER_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmu_description.h"

static int errors_logged = 0;

#define CHECK(call) do { if ((call) != 0) { fprintf(stderr, "failed: %s\n", #call); return 1; } } while (0)
#define REFUSED(call) do { int before = errors_logged; \
    if ((call) != 3 || errors_logged != before + 1) { fprintf(stderr, "not refused: %s\n", #call); return 1; } \
    } while (0)

static const Variable *variable_named(const char *name) {
    for (size_t i = 0; i < sizeof VARIABLES / sizeof VARIABLES[0]; i++)
        if (strcmp(VARIABLES[i].name, name) == 0) return &VARIABLES[i];
    fprintf(stderr, "no variable %s\n", name);
    exit(1);
}

static unsigned int vr_of(const char *name) { return variable_named(name)->vr; }

static int declares(const char *name) {
    for (size_t i = 0; i < sizeof VARIABLES / sizeof VARIABLES[0]; i++)
        if (strcmp(VARIABLES[i].name, name) == 0) return 1;
    return 0;
}

/* The first variable of a causality ("input", "output", "parameter"), in the order declared. */
static const Variable *first_of(const char *causality) {
    for (size_t i = 0; i < sizeof VARIABLES / sizeof VARIABLES[0]; i++)
        if (strcmp(VARIABLES[i].causality, causality) == 0) return &VARIABLES[i];
    fprintf(stderr, "no %s variable\n", causality);
    exit(1);
}

#endif
