"""What the valgrind drivers of the native twins share (tests/test_native_{ekf,stos,profiles,reference}.py):
the includes, a logger that counts errors, CHECK and REFUSED, and (TWIN_LOOKUP, for the twins whose
model.c is a TwinVariables table) the value reference of a variable by name. Each driver is
PRELUDE [+ TWIN_LOOKUP] + its model header + its main()."""

PRELUDE = r"""
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "fmi2Functions.h"

static int errors_logged = 0;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env; (void)name; (void)category; (void)message;
    if (status == fmi2Error) errors_logged++;
}

#define CHECK(call) do { if ((call) != fmi2OK) { fprintf(stderr, "failed: %s\n", #call); return 1; } } while (0)
#define REFUSED(call) do { int before = errors_logged; \
    if ((call) != fmi2Error || errors_logged != before + 1) { fprintf(stderr, "not refused: %s\n", #call); return 1; } \
    } while (0)
"""

TWIN_LOOKUP = r"""
#include "twin_variables.h"

static fmi2ValueReference vr_in(const TwinVariables *table, const char *name) {
    for (size_t vr = 0; vr < table->n_real + table->n_integer + table->n_boolean + table->n_string; vr++)
        if (strcmp(table->variables[vr].name, name) == 0) return (fmi2ValueReference)vr;
    fprintf(stderr, "no variable %s\n", name);
    exit(1);
}
"""


def twin_driver(model_header: str, table: str, main: str) -> str:
    """A driver for a twin whose variables are the TwinVariables ``table`` of ``model_header``;
    ``main`` may call vr_of(name)."""
    return (PRELUDE + TWIN_LOOKUP + f'#include "{model_header}"\n#define vr_of(name) vr_in(&{table}, name)\n' + main)
