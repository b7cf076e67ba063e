/* A generated plant FMU (FMI 3.0) through a full Co-Simulation and Model Exchange run under memcheck,
 * as valgrind_plant.c for FMI 2.0: instantiation, a parameter change, initialisation, steps of
 * varying size, the FMU state's round trip, refused calls (a NaN input, a negative step, a variable
 * of another type, calls out of order) with reset, and a Model Exchange instance with derivatives
 * and a directional derivative. */
#include "fmi3Functions.h"
#include "driver.h"

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env; (void)category; (void)message;
    if (status == fmi3Error) errors_logged++;
}

int main(void) {
    const int nx = N_STATES;
    const fmi3ValueReference input = first_of("input")->vr, output = first_of("output")->vr;
    const fmi3ValueReference parameter = first_of("parameter")->vr;
    double y = 0.0, u, p, last;
    fmi3Boolean event, terminate, early;

    fmi3Instance cs = fmi3InstantiateCoSimulation("cs", FMU_GUID, "", fmi3False, fmi3True, fmi3False, fmi3False,
                                                  NULL, 0, NULL, logger, NULL);
    if (cs == NULL) return 1;
    REFUSED(fmi3DoStep(cs, 0.0, 1e-3, fmi3True, &event, &terminate, &early, &last));   /* before initialisation */
    CHECK(fmi3Reset(cs));
    p = atof(first_of("parameter")->start) * 1.01;
    CHECK(fmi3SetFloat64(cs, &parameter, 1, &p, 1));
    CHECK(fmi3EnterInitializationMode(cs, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    CHECK(fmi3ExitInitializationMode(cs));
    double t = 0.0;
    fmi3FMUState state = NULL;
    for (int k = 0; k < 20; k++) {
        const double h = 1e-4 * (1 + k % 3);
        u = 0.5 * k;
        CHECK(fmi3SetFloat64(cs, &input, 1, &u, 1));
        if (k == 10) CHECK(fmi3GetFMUState(cs, &state));
        CHECK(fmi3DoStep(cs, t, h, fmi3True, &event, &terminate, &early, &last));
        t += h;
        CHECK(fmi3GetFloat64(cs, &output, 1, &y, 1));
    }
    size_t size;
    CHECK(fmi3SerializedFMUStateSize(cs, state, &size));
    fmi3Byte *bytes = malloc(size);
    CHECK(fmi3SerializeFMUState(cs, state, bytes, size));
    fmi3FMUState copy = NULL;
    CHECK(fmi3DeserializeFMUState(cs, bytes, size, &copy));
    CHECK(fmi3SetFMUState(cs, copy));
    CHECK(fmi3FreeFMUState(cs, &copy));
    CHECK(fmi3FreeFMUState(cs, &state));
    free(bytes);
    const fmi3Int32 one = 1;
    REFUSED(fmi3SetInt32(cs, &input, 1, &one, 1));                                     /* no Int32 variables */
    u = NAN;
    REFUSED(fmi3SetFloat64(cs, &input, 1, &u, 1));
    CHECK(fmi3Reset(cs));
    CHECK(fmi3EnterInitializationMode(cs, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    CHECK(fmi3ExitInitializationMode(cs));
    REFUSED(fmi3DoStep(cs, 0.0, -1.0, fmi3True, &event, &terminate, &early, &last));
    fmi3FreeInstance(cs);

    fmi3Instance me = fmi3InstantiateModelExchange("me", FMU_GUID, "", fmi3False, fmi3False, NULL, logger);
    if (me == NULL) return 1;
    CHECK(fmi3EnterInitializationMode(me, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    CHECK(fmi3ExitInitializationMode(me));
    fmi3Boolean needed, nominals, values, defined;
    double next;
    CHECK(fmi3UpdateDiscreteStates(me, &needed, &terminate, &nominals, &values, &defined, &next));
    CHECK(fmi3EnterContinuousTimeMode(me));
    double *x = calloc((size_t)nx, sizeof(double)), *dx = calloc((size_t)nx, sizeof(double));
    for (int i = 0; i < nx; i++) x[i] = 0.1 * (i + 1);
    CHECK(fmi3SetTime(me, 0.5));
    CHECK(fmi3SetContinuousStates(me, x, (size_t)nx));
    CHECK(fmi3GetContinuousStateDerivatives(me, dx, (size_t)nx));
    CHECK(fmi3GetNominalsOfContinuousStates(me, x, (size_t)nx));
    const fmi3ValueReference unknown = FIRST_DERIVATIVE_VR, known = FIRST_STATE_VR;
    const double seed = 1.0;
    double derivative;
    CHECK(fmi3GetDirectionalDerivative(me, &unknown, 1, &known, 1, &seed, 1, &derivative, 1));
    CHECK(fmi3CompletedIntegratorStep(me, fmi3True, &event, &terminate));
    REFUSED(fmi3SetFloat64(me, &parameter, 1, &p, 1));                                 /* not in Continuous-Time Mode */
    CHECK(fmi3Reset(me));
    free(x);
    free(dx);
    fmi3FreeInstance(me);
    printf("ok %g %g\n", y, derivative);
    return 0;
}
