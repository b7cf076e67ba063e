/* The C twin of the motion planner (src/shapefmu/fmi/native/c/jerk_*.c) under memcheck: two
 * workspaces used in turn; the 40 Hz example of issue 36 with its ZV ceiling, a band of +-5 %, a
 * re-plan from the middle of the first move with its jerk history, a 2-axis move from a moving
 * start, an unreachable target refused with a message, and the rigid duration alone. Prints "ok"
 * and the durations, which the test compares with the planner called through ctypes. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "jerk_planner.h"

#define PI 3.14159265358979323846

static JpRequest request;  /* large (the ceiling's shapers): not on the stack */
static JpResult result;
static JpAxisPhases history[1];

static void example(double delta) {
    memset(&request, 0, sizeof(request));
    request.axes = 1;
    request.targets[0][0] = 0.01;
    request.limits[0] = (JpLimits){0.3, -0.3, 5.0, -5.0, 2000.0};
    request.mode_count[0] = 1;
    const double omega = 2.0 * PI * 40.0, zeta = 0.05;
    request.modes[0][0] = (JpMode){omega, zeta, delta, 0.01};
    /* ZV: A1 = 1 / (1 + K), A2 = K / (1 + K) at half the damped period, K = exp(-zeta pi / sqrt(1 - zeta^2)) */
    const double K = exp(-zeta * PI / sqrt(1.0 - zeta * zeta));
    request.ceiling_count[0] = 1;
    JpShaper *zv = &request.ceiling[0][0];
    zv->count = 2;
    zv->times[1] = PI / (omega * sqrt(1.0 - zeta * zeta));
    zv->amplitudes[0] = 1.0 / (1.0 + K);
    zv->amplitudes[1] = K / (1.0 + K);
}

/* the state of result's axis 0 at time t and its phases cut there, as a re-plan's history */
static void cut_at(double t, double *state) {
    const JpAxisPhases *ph = &result.phases[0];
    double p = ph->start[0], v = ph->start[1], a = ph->start[2], elapsed = 0.0;
    history[0].count = 0;
    for (int k = 0; k < ph->count && elapsed < t; k++) {
        const double d = fmin(ph->durations[k], t - elapsed), j = ph->jerks[k];
        p += v * d + a * d * d / 2.0 + j * d * d * d / 6.0;
        v += a * d + j * d * d / 2.0;
        a += j * d;
        history[0].durations[history[0].count] = d;
        history[0].jerks[history[0].count++] = j;
        elapsed += d;
    }
    state[0] = p; state[1] = v; state[2] = a;
}

int main(void) {
    JpWorkspace *one = jp_workspace_new(), *two = jp_workspace_new();
    if (one == NULL || two == NULL) return 1;
    double durations[6];
    example(0.0);
    if (jp_plan(&request, &result, one) != 0) return 2;
    durations[0] = result.duration;
    example(0.05);
    if (jp_plan(&request, &result, two) != 0) return 3;
    durations[1] = result.duration;
    example(0.0);
    if (jp_plan(&request, &result, one) != 0) return 4;
    cut_at(0.03, request.states[0]);
    request.targets[0][0] = 0.025;
    request.history = history;
    if (jp_plan(&request, &result, two) != 0) return 5;
    durations[2] = result.duration;
    memset(&request, 0, sizeof(request));
    request.axes = 2;
    const double states[2][3] = {{0.1, 0.4, -0.5}, {-0.2, -0.3, 0.2}}, targets[2][3] = {{0.6, 0.0, 0.0}, {0.3, 0.0, 0.0}};
    memcpy(request.states, states, sizeof(states));
    memcpy(request.targets, targets, sizeof(targets));
    request.limits[0] = (JpLimits){1.0, -0.8, 2.0, -1.5, 8.0};
    request.limits[1] = (JpLimits){0.7, -1.2, 1.0, -2.5, 3.0};
    request.mode_count[0] = 1;
    request.modes[0][0] = (JpMode){2.0 * PI * 5.0, 0.05, 0.0, 0.01};
    if (jp_plan(&request, &result, one) != 0) return 6;
    durations[3] = result.duration;
    if (jp_rigid_duration(&request, &durations[4], result.message, (int)sizeof(result.message), two) != 0) return 7;
    request.targets[0][1] = 0.9;  /* arriving at 0.9 m/s while braking at 2 m/s^2: above v_max before */
    request.targets[0][2] = -2.0;
    if (jp_plan(&request, &result, two) == 0 || strstr(result.message, "unreachable") == NULL) return 8;
    jp_workspace_free(one);
    jp_workspace_free(two);
    printf("ok %.17g %.17g %.17g %.17g %.17g\n", durations[0], durations[1], durations[2], durations[3], durations[4]);
    return 0;
}
