/* The STOS law of paper 002 (stos_law.c): runtime/stos.py's locate, STOSKernel.control and its
 * sub-sample switching and settle hand-over, in C, over switching curves made at build time by
 * runtime/stos.py's stos_curves. */
#ifndef STOS_LAW_H
#define STOS_LAW_H

/* stos_curves' result for a shaper of n impulses: levels and velocities of the accelerating,
 * middle and decelerating switches, the middle curves x_e = F(a v + c) + p v + q (a quadratic
 * alpha v^2 + beta v + gamma without damping), the base point x_base. */
typedef struct {
    int n;
    double b, U, damping, x_base;
    const double *levels_accel, *v_accel, *levels_mid, *levels_decel; /* n - 1 each */
    const double *v_decel;                                            /* n */
    const double *a, *c, *p, *q;                                      /* n each */
    int quadratic;                                                    /* damping 0: alpha, beta, gamma */
    const double *alpha, *beta, *gamma;                               /* n each */
} StosCurves;

typedef struct {
    double kp, kd, ki, ts, x_enter, v_enter, x_exit, v_exit;
} StosSettle;

/* The kernel's state (STOSKernel.get_state): the settle law in charge, its integrator. */
typedef struct {
    double settling, integral;
} StosState;

/* One sample of STOSKernel.control: u in [-U, U]. settle is NULL without the hand-over; then the
 * law is the plain sampled one (no sub-sample switching), as STOSKernel with Ts = None. */
double stos_control(const StosCurves *curves, const StosSettle *settle, StosState *state, double target, double x_r,
                    double x_r_dot);

#endif
