/* The 4-state resonance EKF of paper 001, eqs. (15)-(26): runtime/ekf.py's ResonanceEKF in C,
 * operation for operation (its module docstring derives the OCR corrections), for the native EKF
 * tuner (ekf_tuner_part.c, runtime/ekf.py's default_tuning) and the native tracked shaper
 * (tracked_shaper_part.c, its own tuning). The reference phase is 0 (H = [1, 0, 0, 0]). */
#include <math.h>
#include <string.h>

#include "resonance_ekf.h"

#define PI 3.14159265358979323846
/* runtime/ekf.py's default_tuning fractions and ResonanceEKF defaults */
#define Q_PHASOR 1e-3
#define Q_OMEGA_PER_PERIOD 1e-4
#define Q_SIGMA_PER_PERIOD 1e-5
#define R_AMPLITUDE 0.1
#define OMEGA_TOL 2e-3
#define SIGMA_TOL 5e-3
#define NIS_LIMIT 9.0

static void diagonal(double P[4][4], const double *variances) {
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) P[i][j] = i == j ? variances[i] : 0.0;
}

void ekf_start(Ekf *e, double fs, double omega0, double amplitude, long long window) {
    const double samples_per_period = 2.0 * PI * fs / omega0;
    const double q_omega = pow(Q_OMEGA_PER_PERIOD * omega0, 2) / samples_per_period;
    const double q_sigma = pow(Q_SIGMA_PER_PERIOD * omega0, 2) / samples_per_period;
    const double p0[4] = {pow(amplitude, 2), pow(amplitude, 2), pow(EKF_P0_OMEGA * omega0, 2), pow(EKF_P0_SIGMA * omega0, 2)};
    const double q[4] = {pow(Q_PHASOR * amplitude, 2), pow(Q_PHASOR * amplitude, 2), q_omega, q_sigma};
    ekf_start_tuned(e, fs, omega0, 0.0, p0, q, pow(R_AMPLITUDE * amplitude, 2), OMEGA_TOL, SIGMA_TOL, window);
}

void ekf_start_tuned(Ekf *e, double fs, double omega0, double sigma0, const double p0[4], const double q[4], double r,
                     double omega_tol, double sigma_tol, long long window) {
    memset(e, 0, sizeof *e);
    e->fs = fs;
    memcpy(e->p0, p0, sizeof e->p0);
    memcpy(e->q, q, sizeof e->q);
    e->r = r;
    e->omega_tol = omega_tol, e->sigma_tol = sigma_tol, e->nis_limit = NIS_LIMIT;
    e->window = window;
    e->nis = 1.0;
    e->dt = 1.0 / fs;
    e->x[0] = 0.0, e->x[1] = 0.0, e->x[2] = omega0, e->x[3] = sigma0;
    diagonal(e->P, e->p0);
    memcpy(e->good, e->x, sizeof e->x);
}

/* Eqs. (15)-(16): the state through eq. (24), P- = F P F^T + Q (phase 0: H = [1, 0, 0, 0]). */
static void ekf_predict(Ekf *e) {
    const double x1 = e->x[0], x2 = e->x[1], omega = e->x[2], sigma = e->x[3], dt = e->dt;
    const double decay = exp(-sigma * dt);
    const double c = decay * cos(omega * dt), s = decay * sin(omega * dt);
    const double f1 = c * x1 + s * x2, f2 = -s * x1 + c * x2;
    const double F1[4] = {c, s, dt * f2, -dt * f1}, F2[4] = {-s, c, -dt * f1, -dt * f2};
    double (*P)[4] = e->P, A1[4], A2[4];
    for (int j = 0; j < 4; j++) {
        A1[j] = F1[0] * P[0][j] + F1[1] * P[1][j] + F1[2] * P[2][j] + F1[3] * P[3][j];
        A2[j] = F2[0] * P[0][j] + F2[1] * P[1][j] + F2[2] * P[2][j] + F2[3] * P[3][j];
    }
    const double *q = e->q;
    const double p11 = A1[0] * F1[0] + A1[1] * F1[1] + A1[2] * F1[2] + A1[3] * F1[3] + q[0];
    const double p12 = A1[0] * F2[0] + A1[1] * F2[1] + A1[2] * F2[2] + A1[3] * F2[3];
    const double p22 = A2[0] * F2[0] + A2[1] * F2[1] + A2[2] * F2[2] + A2[3] * F2[3] + q[1];
    const double p13 = A1[2], p14 = A1[3], p23 = A2[2], p24 = A2[3];
    const double p33 = P[2][2] + q[2], p34 = P[2][3], p44 = P[3][3] + q[3];
    e->x[0] = f1, e->x[1] = f2;
    const double next[4][4] = {{p11, p12, p13, p14}, {p12, p22, p23, p24}, {p13, p23, p33, p34}, {p14, p24, p34, p44}};
    memcpy(e->P, next, sizeof next);
}

/* Eqs. (17)-(19) for z = x1 + n, P = P- - K S K^T. */
static void ekf_update(Ekf *e, double z) {
    double (*P)[4] = e->P, pht[4], K[4];
    const double h1 = 1.0, h2 = 0.0;  /* cos(0), sin(0): the reference phase 0 */
    for (int i = 0; i < 4; i++) pht[i] = h1 * P[i][0] + h2 * P[i][1];
    const double innovation_var = h1 * pht[0] + h2 * pht[1] + e->r;
    for (int i = 0; i < 4; i++) K[i] = pht[i] / innovation_var;
    const double innovation = z - (h1 * e->x[0] + h2 * e->x[1]);
    for (int i = 0; i < 4; i++) e->x[i] = e->x[i] + K[i] * innovation;
    e->nis += (innovation * innovation / innovation_var - e->nis) / (double)e->window;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) P[i][j] = P[i][j] - pht[i] * K[j];
}

static int ekf_healthy(const Ekf *e) {
    for (int i = 0; i < 4; i++) {
        if (!isfinite(e->x[i])) return 0;
        for (int j = 0; j < 4; j++)
            if (!isfinite(e->P[i][j])) return 0;
    }
    for (int i = 0; i < 4; i++)
        if (e->P[i][i] < 0.0) return 0;
    return 0.0 < e->x[2] && e->x[2] < PI * e->fs;
}

double ekf_omega_n(const Ekf *e) { return hypot(e->x[2], e->x[3]); }

static double estimate(const EkfHistory *history, long long slot, int which) {
    return history->recent[2 * slot + (which >= HIGH_SIGMA)];
}

static void window_clear(Ekf *e) {
    e->count = 0;
    memset(e->queue, 0, sizeof e->queue);
}

static long long wrapped(long long i, long long w) { return i >= w ? i - w : i; }

/* Append the estimate (omega, sigma) at the next slot; in a full window it replaces the oldest,
 * which leaves every queue it is still at the front of. */
static void window_push(Ekf *e, EkfHistory *history, double omega, double sigma) {
    const long long w = e->window, slot = e->slot;
    const int full = e->count == w;
    EkfJournal *journal = history->journal;
    if (journal != NULL) {
        journal->pushed = 1, journal->slot = slot;
        journal->recent[0] = history->recent[2 * slot], journal->recent[1] = history->recent[2 * slot + 1];
    }
    history->recent[2 * slot] = omega;
    history->recent[2 * slot + 1] = sigma;
    for (int k = 0; k < EKF_QUEUES; k++) {
        EkfQueue *queue = &e->queue[k];
        long long *at = history->queued + k * w;
        if (full && queue->size > 0 && at[queue->front] == slot) queue->front = wrapped(queue->front + 1, w), queue->size--;
        const double value = k < HIGH_SIGMA ? omega : sigma;
        const int high = k == HIGH_OMEGA || k == HIGH_SIGMA;
        while (queue->size > 0) {
            const double back = estimate(history, at[wrapped(queue->front + queue->size - 1, w)], k);
            if (high ? back <= value : back >= value) queue->size--;
            else break;
        }
        const long long tail = wrapped(queue->front + queue->size, w);
        if (journal != NULL) journal->at[k] = k * w + tail, journal->was[k] = at[tail];
        at[tail] = slot;
        queue->size++;
    }
    e->slot = wrapped(slot + 1, w);
    if (!full) e->count++;
}

static double extreme(const Ekf *e, const EkfHistory *history, int which) {
    return estimate(history, history->queued[which * e->window + e->queue[which].front], which);
}

/* runtime/ekf.py's _steady: the standard deviation of the state below tol times omega, and its
 * estimates steady within that over the last window. */
static int steady(const Ekf *e, const EkfHistory *history, int state, int high, int low, double tol) {
    const double bound = tol * e->x[2], variance = e->P[state][state];
    if (sqrt(variance > 0.0 ? variance : 0.0) > bound || e->count < e->window) return 0;
    return extreme(e, history, high) - extreme(e, history, low) <= bound;
}

int ekf_step(Ekf *e, EkfHistory *history, double z) {
    if (history->journal != NULL) history->journal->pushed = 0;
    e->samples++;
    ekf_predict(e);
    const int measured = isfinite(z);
    if (measured) ekf_update(e, z);
    else e->missing++;
    e->reset_last = !ekf_healthy(e);
    if (e->reset_last) {
        e->resets++;
        memcpy(e->x, e->good, sizeof e->x);
        diagonal(e->P, e->p0);
        window_clear(e);
    } else {
        if (e->nis > e->nis_limit) {
            e->reacquisitions++;
            diagonal(e->P, e->p0);
            e->nis = 1.0;
            window_clear(e);
        }
        memcpy(e->good, e->x, sizeof e->x);
        window_push(e, history, e->x[2], e->x[3]);
    }
    e->omega_converged = steady(e, history, 2, HIGH_OMEGA, LOW_OMEGA, e->omega_tol);
    e->sigma_converged = steady(e, history, 3, HIGH_SIGMA, LOW_SIGMA, e->sigma_tol);
    e->converged = e->omega_converged && e->sigma_converged;
    return measured && !e->reset_last;
}

void ekf_take_back(Ekf *e, EkfHistory *history, const Ekf *before) {
    const EkfJournal *journal = history->journal;
    if (journal->pushed) {
        for (int k = 0; k < EKF_QUEUES; k++) history->queued[journal->at[k]] = journal->was[k];
        history->recent[2 * journal->slot] = journal->recent[0];
        history->recent[2 * journal->slot + 1] = journal->recent[1];
    }
    *e = *before;
}

static int flag(long long value) { return value == 0 || value == 1; }

int ekf_valid(const Ekf *e) {
    for (int i = 0; i < 4; i++) {
        if (!isfinite(e->x[i]) || !isfinite(e->good[i])) return 0;
        for (int j = 0; j < 4; j++)
            if (!isfinite(e->P[i][j])) return 0;
    }
    return e->window >= 2 && e->window <= EKF_MAX_WINDOW && e->count >= 0 && e->count <= e->window && e->slot >= 0
           && e->slot < e->window && flag(e->converged) && flag(e->omega_converged) && flag(e->sigma_converged)
           && flag(e->reset_last) && e->fs > 0.0 && isfinite(e->fs);
}

void ekf_restart_phasor(Ekf *e) {
    e->x[0] = e->x[1] = 0.0;
    for (int i = 0; i < 2; i++) {
        for (int j = 0; j < 4; j++) e->P[i][j] = e->P[j][i] = 0.0;
        e->P[i][i] = e->p0[i];
    }
}

void ekf_rebuild_history(Ekf *e, EkfHistory *history) {
    const long long count = e->count, window = e->window;
    window_clear(e);
    e->slot = wrapped(e->slot + window - count, window);
    for (long long j = 0; j < count; j++) {
        const long long slot = e->slot;
        window_push(e, history, history->recent[2 * slot], history->recent[2 * slot + 1]);
    }
}
