/* A native Shaper or ShapeFilter FMU through full runs under memcheck: a closed-form re-design in C (a
 * Shaper's), initialisation, steps of every kind (whole samples, off the grid, 1e-16 s, several
 * samples), impulses tuned between steps, the FMU state's round trip, refused calls (a bad
 * parameter, a step over too many samples, a call out of order) with reset, and a second
 * initialisation. */
#include "driver_fmi2.h"

static int run(fmi2Component c, fmi2ValueReference u, fmi2ValueReference y, double *t, int steps, double *out) {
    static const double sizes[] = {1e-3, 2.5e-4, 1e-16, 3e-3, 7.3e-4, 1e-3};
    for (int k = 0; k < steps; k++) {
        const double value = (double)((k * 31) % 17) - 8.0, h = sizes[k % 6];
        CHECK(fmi2SetReal(c, &u, 1, &value));
        CHECK(fmi2DoStep(c, *t, h, fmi2True));
        *t += h;
        CHECK(fmi2GetReal(c, &y, 1, out));
    }
    return 0;
}

int main(void) {
    const fmi2ValueReference u = vr_of("u"), y = vr_of("y");
    const int impulses = declares("impulse_amplitude[1]");  /* a Shaper: an impulse train, else FIR taps */
    double out = 0.0, t = 0.0, value;
    fmi2Component c = initialising();
    if (c == NULL) return 1;
    if (impulses) {
        const fmi2ValueReference f1 = vr_of("f[1]"), kind = vr_of("kind");
        const fmi2String mzv = "mzv";
        value = 11.0;
        CHECK(fmi2SetReal(c, &f1, 1, &value));
        CHECK(fmi2SetString(c, &kind, 1, &mzv));
    }
    CHECK(fmi2ExitInitializationMode(c));
    if (run(c, u, y, &t, 150, &out)) return 1;
    fmi2FMUstate state = NULL;
    CHECK(fmi2GetFMUstate(c, &state));
    if (impulses) {
        const fmi2ValueReference a1 = vr_of("impulse_amplitude[1]");
        value = 0.5;
        CHECK(fmi2SetReal(c, &a1, 1, &value));                         /* tuned between steps */
    }
    if (run(c, u, y, &t, 150, &out)) return 1;
    if (restore_serialised(c, &state)) return 1;
    if (refuse_then_restart(c, t, 2e7, vr_of("u0"))) return 1;
    t = 0.5;
    if (run(c, u, y, &t, 100, &out)) return 1;
    CHECK(fmi2Terminate(c));
    fmi2FreeInstance(c);
    printf("ok %g\n", out);
    return 0;
}
