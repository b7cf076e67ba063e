/* The native EKFTuner FMU under memcheck: a 10 Hz ring-down at Ts = 1 ms and a command that moves and
 * rests, so the EKF converges and a shaper is designed and switched in (every buffer used); steps of
 * every kind, the FMU state's round trip, refused calls (a step before initialisation, over too many
 * samples, a value that is not finite) with reset, and a run from t0 = 0.5. */
#include "driver_fmi2.h"

static int run(fmi2Component c, double *t, int steps, double *out) {
    static const double sizes[] = {1e-3, 2.5e-4, 1e-16, 3e-3, 7.5e-4, 1e-3};
    const fmi2ValueReference in[2] = {vr_of("u"), vr_of("vibration")};
    const fmi2ValueReference y[2] = {vr_of("y"), vr_of("converged")};
    for (int k = 0; k < steps; k++) {
        const double values[2] = {*t > 0.05 && *t < 0.3 ? 1.0 : *t > 1.5 ? 2.0 : 0.0,
                                  exp(-1.2566 * *t) * sin(62.83 * *t)};
        CHECK(fmi2SetReal(c, in, 2, values));
        CHECK(fmi2DoStep(c, *t, sizes[k % 6], fmi2True));
        *t += sizes[k % 6];
        CHECK(fmi2GetReal(c, y, 2, out));
    }
    return 0;
}

int main(void) {
    double out[2] = {0.0, 0.0}, t = 0.0;
    fmi2Component c = initialising();
    if (c == NULL) return 1;
    const fmi2ValueReference kind = vr_of("kind");
    const fmi2String mzv = "mzv";
    CHECK(fmi2SetString(c, &kind, 1, &mzv));
    CHECK(fmi2ExitInitializationMode(c));
    if (run(c, &t, 900, out)) return 1;
    fmi2FMUstate state = NULL;
    CHECK(fmi2GetFMUstate(c, &state));
    if (run(c, &t, 1500, out)) return 1;
    if (out[1] != 1.0) { fprintf(stderr, "the EKF did not converge\n"); return 1; }
    if (restore_serialised(c, &state)) return 1;
    if (refuse_then_restart(c, t, 2e7, vr_of("omega0"))) return 1;
    t = 0.5;
    if (run(c, &t, 300, out)) return 1;
    CHECK(fmi2Terminate(c));
    fmi2FreeInstance(c);
    printf("ok %g\n", out[0]);
    return 0;
}
