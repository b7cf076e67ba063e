/* The native ScheduledShaper FMU of the bed (0 to 300 g) under memcheck: a command that moves and
 * rests while the scheduling input sweeps the table, so the shaper is re-designed at nearly every
 * sample, segments open and are folded (every buffer grows and shrinks), with steps of every kind;
 * the FMU state's round trip, refused calls (a scheduling value where the extrapolated law gives no
 * mode, a step over too many samples, a value that is not finite) with reset, and a run from t0 = 0.5. */
#include "driver_fmi2.h"

static int run(fmi2Component c, double *t, int steps, double *out) {
    static const double sizes[] = {5e-4, 2.5e-4, 1e-16, 3e-3, 7.5e-4, 5e-4};
    const fmi2ValueReference in[2] = {vr_of("u"), vr_of("scheduling")}, y = vr_of("y");
    for (int k = 0; k < steps; k++) {
        const double values[2] = {fmod(*t, 0.2) < 0.08 ? sin(40.0 * *t) : 1.0, 150.0 + 140.0 * sin(3.0 * *t)};
        CHECK(fmi2SetReal(c, in, 2, values));
        CHECK(fmi2DoStep(c, *t, sizes[k % 6], fmi2True));
        *t += sizes[k % 6];
        CHECK(fmi2GetReal(c, &y, 1, out));
    }
    return 0;
}

int main(void) {
    double out = 0.0, t = 0.0;
    fmi2Component c = initialising();
    if (c == NULL) return 1;
    const fmi2ValueReference kind = vr_of("kind"), extrapolate = vr_of("extrapolate");
    const fmi2ValueReference scheduling = vr_of("scheduling");
    const fmi2String zvd = "zvd";
    const fmi2Boolean on = fmi2True;
    CHECK(fmi2SetString(c, &kind, 1, &zvd));
    CHECK(fmi2SetBoolean(c, &extrapolate, 1, &on));
    CHECK(fmi2ExitInitializationMode(c));
    if (run(c, &t, 900, &out)) return 1;
    const double beyond = 1e9;  /* the law continued this far gives f < 0 */
    REFUSED(fmi2SetReal(c, &scheduling, 1, &beyond));
    CHECK(fmi2Reset(c));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    CHECK(fmi2ExitInitializationMode(c));
    t = 0.0;
    if (run(c, &t, 900, &out)) return 1;
    fmi2FMUstate state = NULL;
    CHECK(fmi2GetFMUstate(c, &state));
    if (run(c, &t, 900, &out)) return 1;
    if (restore_serialised(c, &state)) return 1;
    if (refuse_then_restart(c, t, 2e7, vr_of("u0"))) return 1;
    t = 0.5;
    if (run(c, &t, 300, &out)) return 1;
    CHECK(fmi2Terminate(c));
    fmi2FreeInstance(c);
    printf("ok %g\n", out);
    return 0;
}
