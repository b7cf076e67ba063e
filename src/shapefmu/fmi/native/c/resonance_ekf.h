/* The resonance EKF of paper 001 (resonance_ekf.c): runtime/ekf.py's ResonanceEKF in C. */
#ifndef RESONANCE_EKF_H
#define RESONANCE_EKF_H

/* The convergence window is one period of omega0 in samples; its history is allocated by the caller. */
#define EKF_MAX_WINDOW 1000000L

/* A queue of window slots in a circular buffer of `window` entries. */
typedef struct {
    long long size, front;
} EkfQueue;

enum { HIGH_OMEGA, LOW_OMEGA, HIGH_SIGMA, LOW_SIGMA, EKF_QUEUES };

/* Plain data (an FMU state copies it as it is). The window of estimates (omega, sigma) is a ring in
 * EkfHistory, and for each extreme a monotonic queue of the slots, oldest first, that may still be
 * it: runtime/ekf.py scans its deque for max - min every sample, these give the same values in
 * O(1) per sample. */
typedef struct {
    double x[4], P[4][4];
    double p0[4], q[4], r, omega_tol, sigma_tol, nis_limit, nis, fs, dt, good[4];
    long long window, count, slot;  /* the last `count` <= window estimates, the next one goes to slot */
    long long samples, missing, resets, reacquisitions, reset_last, converged;
    EkfQueue queue[EKF_QUEUES];
} Ekf;

typedef struct {
    double *recent;      /* 2 * window: (omega, sigma) per slot */
    long long *queued;   /* EKF_QUEUES * window */
} EkfHistory;

/* A filter at rest at the guess omega0 (rad/s) for samples at fs (Hz), tuned for a signal of
 * amplitude (default_tuning), with a convergence window of `window` samples. */
void ekf_start(Ekf *e, double fs, double omega0, double amplitude, long long window);
/* One sample: predict, update unless z is not finite, the health check, re-acquisition, the
 * window, the convergence flag (e->converged). */
void ekf_step(Ekf *e, EkfHistory *history, double z);
/* The undamped natural frequency hypot(omega_d, sigma), rad/s. */
double ekf_omega_n(const Ekf *e);
/* The queues again from the ring (after the ring and e were restored from an FMU state). */
void ekf_rebuild_history(Ekf *e, EkfHistory *history);

#endif
