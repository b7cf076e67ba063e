/* The native TrackedShaper FMU under memcheck: moves of a 30 Hz bed (its accelerometer in closed
 * form) watched from a 27 Hz guess at Ts = 1 ms, so the EKF converges, the shaper is re-designed
 * during moves (designs in flight, the ring grown) and every buffer is used; steps of every kind,
 * the FMU state's round trip, refused calls (a step over too many samples, a value that is not
 * finite) with reset, and a run from t0 = 0.5. */
#include "driver_fmi2.h"

/* The drive's acceleration: a move (+1 for 40 ms, then -1 for 40 ms) every 0.4 s from 0.05 s. */
static double command(double t) {
    const double into = fmod(t, 0.4);
    return into >= 0.05 && into < 0.09 ? 1.0 : into >= 0.09 && into < 0.13 ? -1.0 : 0.0;
}

/* The bed's acceleration: each change da of the drive's acceleration at t_j adds
 * da (1 - exp(-sigma tau) (cos(w_d tau) - sigma / w_d sin(w_d tau))), tau = t - t_j: the
 * derivative of a damped spring-mass's step response, with omega = 2 pi 30 rad/s, zeta = 0.03. */
static double measurement(double t) {
    const double omega = 2.0 * 3.14159265358979323846 * 30.0, sigma = 0.03 * omega;
    const double omega_d = omega * sqrt(1.0 - 0.03 * 0.03);
    const double changes[3][2] = {{0.05, 1.0}, {0.09, -2.0}, {0.13, 1.0}};
    double sum = 0.0;
    for (double start = 0.0; start <= t; start += 0.4)
        for (int i = 0; i < 3; i++) {
            const double tau = t - start - changes[i][0];
            if (tau >= 0.0)
                sum += changes[i][1] * (1.0 - exp(-sigma * tau) * (cos(omega_d * tau) - sigma / omega_d * sin(omega_d * tau)));
        }
    return sum;
}

static void inputs(double t, double values[2]) {
    values[0] = command(t);
    values[1] = measurement(t);
}

static int followed(const double *out) {
    if (fabs(out[1] - 30.0) < 0.3) return 0;
    fprintf(stderr, "the shaper did not follow the 30 Hz mode: f = %g\n", out[1]);
    return 1;
}

int main(void) {
    static const TwoByTwo plan = {{"u", "measurement"}, {"y", "f"}, inputs, 1};
    fmi2Component c = initialising();
    if (c == NULL) return 1;
    const fmi2ValueReference resolution = vr_of("resolution");
    const double every_change = 0.0;
    CHECK(fmi2SetReal(c, &resolution, 1, &every_change));
    CHECK(fmi2ExitInitializationMode(c));
    return two_by_two_run(c, &plan, 900, 1500, followed, "f0", 300);
}
