/* Matrix exponential for the exact zero-order-hold step of linear plants. */
#ifndef PLANT_EXPM_H
#define PLANT_EXPM_H

/* Doubles of scratch plant_expm needs for an n x n matrix. */
#define PLANT_EXPM_WORK(n) (8 * (n) * (n) + (n))
/* Integers of scratch (LU pivots). */
#define PLANT_EXPM_IWORK(n) (n)

/* E = expm(M) for the n x n column-major M; returns 0, or -1 if M is not finite or the Pade
 * denominator is singular (which cannot happen for a finite M, see plant_expm.c). */
int plant_expm(int n, const double *M, double *E, double *work, int *iwork);

#endif
