/* The resonance EKF of paper 001 (resonance_ekf.c): runtime/ekf.py's ResonanceEKF in C. */
#ifndef RESONANCE_EKF_H
#define RESONANCE_EKF_H

/* runtime/ekf.py's initial standard deviations of omega and sigma, as fractions of omega0. */
#define EKF_P0_OMEGA 0.25
#define EKF_P0_SIGMA 0.1

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
    long long omega_converged, sigma_converged;  /* runtime/ekf.py's two halves of converged */
    EkfQueue queue[EKF_QUEUES];
} Ekf;

/* What one ekf_step overwrote in the history, so that ekf_take_back can undo it. */
typedef struct {
    int pushed;                                     /* the step pushed an estimate */
    long long slot, at[EKF_QUEUES], was[EKF_QUEUES];  /* queued[at[k]] held was[k] */
    double recent[2];                               /* what recent[2 slot], recent[2 slot + 1] held */
} EkfJournal;

typedef struct {
    double *recent;      /* 2 * window: (omega, sigma) per slot */
    long long *queued;   /* EKF_QUEUES * window */
    EkfJournal *journal; /* NULL, or where ekf_step notes what it overwrites */
} EkfHistory;

/* A filter at rest at the guess omega0 (rad/s) for samples at fs (Hz), tuned for a signal of
 * amplitude (default_tuning), with a convergence window of `window` samples. */
void ekf_start(Ekf *e, double fs, double omega0, double amplitude, long long window);
/* The same with the decay rate guess sigma0 (1/s) and a tuning of one's own: the initial and
 * per-sample process variances p0, q of (x1, x2, omega, sigma), the measurement variance r and the
 * convergence tolerances (ResonanceEKF's keyword arguments). */
void ekf_start_tuned(Ekf *e, double fs, double omega0, double sigma0, const double p0[4], const double q[4], double r,
                     double omega_tol, double sigma_tol, long long window);
/* One sample: predict, update unless z is not finite, the health check, re-acquisition, the
 * window, the convergence flags (e->omega_converged, e->sigma_converged, e->converged). Returns
 * whether z updated the filter (it was finite and the step needed no reset), as ResonanceEKF.step. */
int ekf_step(Ekf *e, EkfHistory *history, double z);
/* Whether e (its window's history is rebuilt by ekf_rebuild_history) is a filter a run reaches, as
 * far as its sizes, flags and the finiteness of its estimates go: what an FMU state restoring it must hold. */
int ekf_valid(const Ekf *e);
/* Undo the one ekf_step journalled in history->journal: the history's entries back, and *e = *before
 * (the filter as it was before that step). */
void ekf_take_back(Ekf *e, EkfHistory *history, const Ekf *before);
/* ResonanceEKF.restart_phasor: a new ring begins; omega and sigma keep what they learnt. */
void ekf_restart_phasor(Ekf *e);
/* The undamped natural frequency hypot(omega_d, sigma), rad/s. */
double ekf_omega_n(const Ekf *e);
/* The queues again from the ring (after the ring and e were restored from an FMU state). */
void ekf_rebuild_history(Ekf *e, EkfHistory *history);

#endif
