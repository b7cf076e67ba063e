/* The native ProfileGenerator FMU under memcheck: a design parameter refused, a move that waits for
 * its start input and runs with steps of 1e-16 s and 1.3 ms, and the FMU state's round trip. */
#include "driver_fmi2.h"

int main(void) {
    const fmi2ValueReference start = vr_of("start"), distance = vr_of("distance"), t_start = vr_of("t_start");
    const fmi2ValueReference outputs[3] = {vr_of("position"), vr_of("velocity"), vr_of("acceleration")};
    double out[3], t = 0.0, value;
    fmi2Component c = fmi2Instantiate("c", fmi2CoSimulation, FMU_GUID, "", &callbacks, fmi2False, fmi2True);
    if (c == NULL) return 1;
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    value = 99.0;
    REFUSED(fmi2SetReal(c, &distance, 1, &value));
    CHECK(fmi2Reset(c));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    value = -1.0;
    CHECK(fmi2SetReal(c, &t_start, 1, &value));                        /* wait for the input */
    CHECK(fmi2ExitInitializationMode(c));
    fmi2FMUstate state = NULL;
    for (int k = 0; k < 3000; k++) {
        const double h = k % 5 == 0 ? 1e-16 : 1.3e-3, on = k >= 100 ? 1.0 : 0.0;
        CHECK(fmi2SetReal(c, &start, 1, &on));
        CHECK(fmi2DoStep(c, t, h, fmi2True));
        t += h;
        CHECK(fmi2GetReal(c, outputs, 3, out));
        if (k == 500) CHECK(fmi2GetFMUstate(c, &state));
    }
    if (restore_serialised(c, &state)) return 1;
    CHECK(fmi2Terminate(c));
    fmi2FreeInstance(c);
    printf("ok %g\n", out[0]);
    return 0;
}
