/* The native STOSController FMU under memcheck: the closed loop around the rigid body x'' = b u with
 * steps of every kind, a design parameter refused, the FMU state's round trip, and a step over too
 * many samples refused. */
#include "driver_fmi2.h"

static int run(fmi2Component c, double *t, double *x, double *v, int steps) {
    static const double sizes[] = {1e-5, 2.5e-6, 1e-16, 3e-5, 7.5e-6, 1e-5};
    const fmi2ValueReference in[3] = {vr_of("target"), vr_of("x_r"), vr_of("x_r_dot")}, out = vr_of("u");
    for (int k = 0; k < steps; k++) {
        const double values[3] = {1e-3, *x, *v}, h = sizes[k % 6];
        double u;
        CHECK(fmi2SetReal(c, in, 3, values));
        CHECK(fmi2GetReal(c, &out, 1, &u));
        CHECK(fmi2DoStep(c, *t, h, fmi2True));
        *t += h;
        *x += *v * h + 0.5 * 2.7e3 * u * h * h;
        *v += 2.7e3 * u * h;
    }
    return 0;
}

int main(void) {
    double t = 0.0, x = 0.0, v = 0.0, value;
    fmi2Component c = initialising();
    if (c == NULL) return 1;
    const fmi2ValueReference f1 = vr_of("f[1]");
    value = 2100.0;
    REFUSED(fmi2SetReal(c, &f1, 1, &value));                           /* a design parameter */
    CHECK(fmi2Reset(c));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    CHECK(fmi2ExitInitializationMode(c));
    if (run(c, &t, &x, &v, 300)) return 1;
    fmi2FMUstate state = NULL;
    CHECK(fmi2GetFMUstate(c, &state));
    if (run(c, &t, &x, &v, 300)) return 1;
    if (restore_serialised(c, &state)) return 1;
    REFUSED(fmi2DoStep(c, t, 2e3, fmi2True));                          /* too many samples */
    CHECK(fmi2Reset(c));                                                /* out of the error state */
    fmi2FreeInstance(c);
    printf("ok %g\n", x);
    return 0;
}
