/* The native ReferencePlayer FMU under memcheck: its own table accepted and another refused, steps of
 * 1e-16 s and 3 ms across the switches, the table read back, and the FMU state's round trip. */
#include "driver_fmi2.h"

int main(void) {
    const fmi2ValueReference outputs[2] = {vr_of("y"), vr_of("y_mean")}, table = vr_of("table");
    double out[2], t = 0.0;
    fmi2Component c = fmi2Instantiate("c", fmi2CoSimulation, FMU_GUID, "", &callbacks, fmi2False, fmi2True);
    if (c == NULL) return 1;
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    const fmi2String same = variable_named("table")->start, other = "{}";
    CHECK(fmi2SetString(c, &table, 1, &same));
    REFUSED(fmi2SetString(c, &table, 1, &other));
    CHECK(fmi2Reset(c));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    CHECK(fmi2ExitInitializationMode(c));
    fmi2FMUstate state = NULL;
    for (int k = 0; k < 500; k++) {
        const double h = k % 5 == 0 ? 1e-16 : 3e-3;
        CHECK(fmi2DoStep(c, t, h, fmi2True));
        t += h;
        CHECK(fmi2GetReal(c, outputs, 2, out));
        if (k == 100) CHECK(fmi2GetFMUstate(c, &state));
    }
    fmi2String text = NULL;
    CHECK(fmi2GetString(c, &table, 1, &text));
    if (strcmp(text, same) != 0) return 1;
    if (restore_serialised(c, &state)) return 1;
    CHECK(fmi2Terminate(c));
    fmi2FreeInstance(c);
    printf("ok %g\n", out[1]);
    return 0;
}
