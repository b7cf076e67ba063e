/* A generated plant FMU (FMI 2.0) through a full Co-Simulation and Model Exchange run under memcheck:
 * instantiation, a parameter change, initialisation, steps of varying size, the FMU state's round
 * trip, refused calls (a NaN input, a negative step, calls out of order) with reset, and a Model
 * Exchange instance with derivatives and a directional derivative. */
#include "driver_fmi2.h"

int main(void) {
    const int nx = N_STATES;
    const fmi2ValueReference input = first_of("input")->vr, output = first_of("output")->vr;
    const fmi2ValueReference parameter = first_of("parameter")->vr;
    double y = 0.0, u, p;

    fmi2Component cs = fmi2Instantiate("cs", fmi2CoSimulation, FMU_GUID, "", &callbacks, fmi2False, fmi2True);
    if (cs == NULL) return 1;
    REFUSED(fmi2DoStep(cs, 0.0, 1e-3, fmi2True));               /* before initialisation */
    CHECK(fmi2Reset(cs));
    CHECK(fmi2SetupExperiment(cs, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    p = atof(first_of("parameter")->start) * 1.01;
    CHECK(fmi2SetReal(cs, &parameter, 1, &p));
    CHECK(fmi2EnterInitializationMode(cs));
    CHECK(fmi2ExitInitializationMode(cs));
    double t = 0.0;
    fmi2FMUstate state = NULL;
    for (int k = 0; k < 200; k++) {
        const double h = (k % 3 == 0 ? 2e-4 : 1e-4);
        u = sin(0.1 * k);
        CHECK(fmi2SetReal(cs, &input, 1, &u));
        CHECK(fmi2DoStep(cs, t, h, fmi2True));
        t += h;
        CHECK(fmi2GetReal(cs, &output, 1, &y));
        if (k == 100) CHECK(fmi2GetFMUstate(cs, &state));
    }
    if (restore_serialised(cs, &state)) return 1;
    u = NAN;
    REFUSED(fmi2SetReal(cs, &input, 1, &u));
    CHECK(fmi2Reset(cs));
    CHECK(fmi2SetupExperiment(cs, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(cs));
    CHECK(fmi2ExitInitializationMode(cs));
    REFUSED(fmi2DoStep(cs, 0.0, -1e-3, fmi2True));
    CHECK(fmi2Reset(cs));
    CHECK(fmi2EnterInitializationMode(cs));
    CHECK(fmi2ExitInitializationMode(cs));
    CHECK(fmi2DoStep(cs, 0.0, 1e-3, fmi2True));
    CHECK(fmi2Terminate(cs));
    REFUSED(fmi2DoStep(cs, 1e-3, 1e-3, fmi2True));               /* after termination */
    fmi2FreeInstance(cs);

    fmi2Component me = fmi2Instantiate("me", fmi2ModelExchange, FMU_GUID, "", &callbacks, fmi2False, fmi2False);
    if (me == NULL) return 1;
    CHECK(fmi2SetupExperiment(me, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(me));
    CHECK(fmi2ExitInitializationMode(me));
    fmi2EventInfo info;
    CHECK(fmi2NewDiscreteStates(me, &info));
    CHECK(fmi2EnterContinuousTimeMode(me));
    double *x = calloc((size_t)nx, sizeof(double)), *dx = calloc((size_t)nx, sizeof(double));
    for (int i = 0; i < nx; i++) x[i] = 0.1 * (i + 1);
    CHECK(fmi2SetTime(me, 0.5));
    CHECK(fmi2SetContinuousStates(me, x, (size_t)nx));
    CHECK(fmi2GetDerivatives(me, dx, (size_t)nx));
    CHECK(fmi2GetNominalsOfContinuousStates(me, x, (size_t)nx));
    const fmi2ValueReference unknown = FIRST_DERIVATIVE_VR, known = FIRST_STATE_VR;
    const double seed = 1.0;
    double derivative;
    CHECK(fmi2GetDirectionalDerivative(me, &unknown, 1, &known, 1, &seed, &derivative));
    fmi2Boolean enter, terminate;
    CHECK(fmi2CompletedIntegratorStep(me, fmi2True, &enter, &terminate));
    REFUSED(fmi2SetReal(me, &parameter, 1, &p));                 /* not in Continuous-Time Mode */
    CHECK(fmi2Reset(me));
    free(x);
    free(dx);
    fmi2FreeInstance(me);
    printf("ok %g %g\n", y, derivative);
    return 0;
}
