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

/* The doubles stos_design_curves stores for a shaper of n impulses. */
#define STOS_CURVE_DOUBLES(n) (13 * (size_t)(n))

/* runtime/stos.py's stos_curves for the rigid body x'' = -damping x' + b u, |u| <= U, and the
 * impulses (times strictly increasing, amplitudes > 0 summing to 1, as the closed-form designs
 * give them): fills curves, its arrays in storage (STOS_CURVE_DOUBLES(n) doubles, owned by the
 * caller). Returns NULL, or why the shaper does not suit this rigid body (as _min_distance). */
const char *stos_design_curves(StosCurves *curves, double *storage, double b, double U, double damping,
                               const double *times, const double *amplitudes, int n);

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
