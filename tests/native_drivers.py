"""What the tests of the native twins share (tests/test_native_{ekf,stos,profiles,reference}.py): the
variables an FMU declares, as compared with its pythonfmu twin's (``declared``); and for the valgrind
drivers the includes, a logger that counts errors, CHECK and REFUSED, and (TWIN_LOOKUP, for the twins
whose model.c is a VariableTable (model.h)) the value reference of a variable by name. Each driver is
PRELUDE [+ TWIN_LOOKUP] + its model header + its main()."""


def declared(fmu, units: bool = True) -> list[tuple]:
    """Each variable of ``fmu``: name, causality, variability, type, (unit,) start, sorted."""
    from fmpy import read_model_description

    return sorted((v.name, v.causality, v.variability, v.type, *((v.unit,) if units else ()), v.start)
                  for v in read_model_description(str(fmu)).modelVariables)

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

static fmi2ValueReference vr_in(const VariableTable *table, const char *name) {
    for (size_t vr = 0; vr < table->n_real + table->n_integer + table->n_boolean + table->n_string; vr++)
        if (strcmp(table->rows[vr].name, name) == 0) return (fmi2ValueReference)vr;
    fprintf(stderr, "no variable %s\n", name);
    exit(1);
}
"""


def twin_driver(model_header: str, table: str, main: str) -> str:
    """A driver for a twin whose variables are the VariableTable ``table`` of ``model_header``;
    ``main`` may call vr_of(name)."""
    return (PRELUDE + TWIN_LOOKUP + f'#include "{model_header}"\n#define vr_of(name) vr_in(&{table}, name)\n' + main)


def replayed_run(path, times, outputs, inputs, save_at=None, replay_inputs=None, parameters=None):
    """fmpy (``parameters`` set in initialisation) over the communication points ``times`` (a step
    from t_k to t_k+1), ``inputs(k)`` {name: value} set before step k, ``outputs`` read after it:
    (rows, replayed rows). With ``save_at``, the FMU state taken before step ``save_at`` (serialised
    and read back) is restored after the run, and the steps from ``save_at`` on run again with
    ``replay_inputs(k)``: the replayed rows."""
    from fmu_drivers import initialised

    slave, vr = initialised(path, parameters)
    state = None

    def run(first, values_at):
        rows = []
        for k in range(first, len(times) - 1):
            nonlocal state
            if k == save_at and state is None:
                taken = slave.getFMUstate()
                state = slave.deSerializeFMUstate(slave.serializeFMUstate(taken))
                slave.freeFMUstate(taken)
            for name, value in values_at(k).items():
                slave.setReal([vr[name]], [value])
            slave.doStep(times[k], times[k + 1] - times[k])
            rows.append(slave.getReal([vr[n] for n in outputs]))
        return rows

    rows, replayed = run(0, inputs), None
    if save_at is not None:
        slave.setFMUstate(state)
        replayed = run(save_at, replay_inputs)
        slave.freeFMUstate(state)
    slave.terminate()
    slave.freeInstance()
    return rows, replayed
