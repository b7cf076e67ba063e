/* Any native FMU's outputs got in Initialization Mode under memcheck: every input set and every output
 * got (the layer runs the model part's exit on a saved instance and restores it), an input changed and
 * the outputs got again; a shaper's also with Ts = 1e-9 s, which its exit would refuse (the layer then
 * resets the saved instance for the start values), and with Ts back; then the exit, a step, the outputs
 * once more and the instance freed. Every input and output of the native kinds and plants is Real. */
#include "driver_fmi2.h"

/* Every variable of causality, value set (set != 0) or got, summed into *sum. */
static int each(fmi2Component c, const char *causality, int set, double value, double *sum) {
    for (size_t i = 0; i < sizeof VARIABLES / sizeof VARIABLES[0]; i++) {
        if (strcmp(VARIABLES[i].causality, causality) != 0) continue;
        const fmi2ValueReference vr = VARIABLES[i].vr;
        double got = 0.0;
        if (set) CHECK(fmi2SetReal(c, &vr, 1, &value));
        else CHECK(fmi2GetReal(c, &vr, 1, &got));
        *sum += got;
    }
    return 0;
}

int main(void) {
    double sum = 0.0;
    fmi2Component c = initialising();
    if (c == NULL) return 1;
    if (each(c, "input", 1, 0.75, &sum) || each(c, "output", 0, 0.0, &sum)) return 1;
    if (each(c, "input", 1, 0.5, &sum) || each(c, "output", 0, 0.0, &sum)) return 1;
    if (declares("f[1]") && declares("Ts")) { /* a Shaper or a ScheduledShaper, not a plant */
        const fmi2ValueReference ts = vr_of("Ts");
        const double too_short = 1e-9, built = atof(variable_named("Ts")->start);
        CHECK(fmi2SetReal(c, &ts, 1, &too_short));
        if (each(c, "output", 0, 0.0, &sum)) return 1;
        CHECK(fmi2SetReal(c, &ts, 1, &built));
        if (each(c, "output", 0, 0.0, &sum)) return 1;
    }
    CHECK(fmi2ExitInitializationMode(c));
    if (each(c, "output", 0, 0.0, &sum)) return 1;
    CHECK(fmi2DoStep(c, 0.0, 1e-3, fmi2True));
    if (each(c, "output", 0, 0.0, &sum)) return 1;
    CHECK(fmi2Terminate(c));
    fmi2FreeInstance(c);
    printf("ok %g\n", sum);
    return 0;
}
