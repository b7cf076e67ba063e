/* The native EKFTuner FMU under memcheck: a 10 Hz ring-down at Ts = 1 ms and a command that moves and
 * rests, so the EKF converges and a shaper is designed and switched in (every buffer used); steps of
 * every kind, the FMU state's round trip, refused calls (a step before initialisation, over too many
 * samples, a value that is not finite) with reset, and a run from t0 = 0.5. */
#include "driver_fmi2.h"

static void inputs(double t, double values[2]) {
    values[0] = t > 0.05 && t < 0.3 ? 1.0 : t > 1.5 ? 2.0 : 0.0;
    values[1] = exp(-1.2566 * t) * sin(62.83 * t);
}

static int converged(const double *out) {
    if (out[1] == 1.0) return 0;
    fprintf(stderr, "the EKF did not converge\n");
    return 1;
}

int main(void) {
    static const TwoByTwo plan = {{"u", "vibration"}, {"y", "converged"}, inputs, 0};
    fmi2Component c = initialising();
    if (c == NULL) return 1;
    const fmi2ValueReference kind = vr_of("kind");
    const fmi2String mzv = "mzv";
    CHECK(fmi2SetString(c, &kind, 1, &mzv));
    CHECK(fmi2ExitInitializationMode(c));
    return two_by_two_run(c, &plan, 900, 1500, converged, "omega0", 300);
}
