/* Matrix exponential by scaling and squaring with the [13/13] Pade approximant.
 *
 * N. J. Higham, "The scaling and squaring method for the matrix exponential revisited",
 * SIAM J. Matrix Anal. Appl. 26(4), 2005, Algorithm 2.3 (the branch for ||A||_1 > theta_9, used
 * here for every norm: degree 13 is at least as accurate as the lower degrees, and the cost does
 * not matter because the result is cached until the step size or the parameters change).
 *
 * Before scaling, M is balanced by a diagonal similarity D^-1 M D with powers of two (the
 * Parlett-Reinsch iteration of EISPACK's balanc, without permutations). The plants' state
 * matrices mix entries of 1 and omega^2 ~ 1e8; balancing makes the norm that sets the number of
 * squarings, and the rounding errors of the products, those of the well-scaled matrix. Powers of
 * two make the similarity exact, so expm(M) = D expm(D^-1 M D) D^-1 loses nothing.
 */
#include <math.h>
#include <string.h>

#include "plant_expm.h"

#define AT(X, i, j) (X)[(size_t)(j) * (size_t)n + (size_t)(i)]

/* Z = X Y (n x n, column-major); Z must not alias X or Y. */
static void matmul(int n, const double *X, const double *Y, double *Z) {
    for (int j = 0; j < n; j++) {
        for (int i = 0; i < n; i++) AT(Z, i, j) = 0.0;
        for (int k = 0; k < n; k++) {
            const double y = AT(Y, k, j);
            if (y == 0.0) continue;
            for (int i = 0; i < n; i++) AT(Z, i, j) += AT(X, i, k) * y;
        }
    }
}

/* Diagonal balancing by powers of two: A <- D^-1 A D, d holds D. */
static void balance(int n, double *A, double *d) {
    const double radix = 2.0, radix2 = 4.0;
    for (int i = 0; i < n; i++) d[i] = 1.0;
    for (int sweep = 0, converged = 0; !converged && sweep < 100; sweep++) {
        converged = 1;
        for (int i = 0; i < n; i++) {
            double c = 0.0, r = 0.0;
            for (int j = 0; j < n; j++) {
                if (j == i) continue;
                c += fabs(AT(A, j, i));
                r += fabs(AT(A, i, j));
            }
            if (c == 0.0 || r == 0.0) continue;
            double g = r / radix, f = 1.0;
            const double s = c + r;
            while (c < g) { f *= radix; c *= radix2; }
            g = r * radix;
            while (c >= g) { f /= radix; c /= radix2; }
            if ((c + r) / f < 0.95 * s) {
                converged = 0;
                d[i] *= f;
                for (int j = 0; j < n; j++) AT(A, i, j) /= f;
                for (int j = 0; j < n; j++) AT(A, j, i) *= f;
            }
        }
    }
}

/* Solve Q X = P in place (X overwrites P) by LU with partial pivoting; Q is destroyed. */
static int solve(int n, double *Q, double *P, int *pivot) {
    for (int k = 0; k < n; k++) {
        int p = k;
        for (int i = k + 1; i < n; i++)
            if (fabs(AT(Q, i, k)) > fabs(AT(Q, p, k))) p = i;
        if (AT(Q, p, k) == 0.0) return -1;
        pivot[k] = p;
        if (p != k)
            for (int j = 0; j < n; j++) {
                double t = AT(Q, k, j); AT(Q, k, j) = AT(Q, p, j); AT(Q, p, j) = t;
                t = AT(P, k, j); AT(P, k, j) = AT(P, p, j); AT(P, p, j) = t;
            }
        for (int i = k + 1; i < n; i++) {
            const double l = AT(Q, i, k) / AT(Q, k, k);
            AT(Q, i, k) = l;
            for (int j = k + 1; j < n; j++) AT(Q, i, j) -= l * AT(Q, k, j);
            for (int j = 0; j < n; j++) AT(P, i, j) -= l * AT(P, k, j);
        }
    }
    for (int j = 0; j < n; j++)
        for (int i = n - 1; i >= 0; i--) {
            double s = AT(P, i, j);
            for (int k = i + 1; k < n; k++) s -= AT(Q, i, k) * AT(P, k, j);
            AT(P, i, j) = s / AT(Q, i, i);
        }
    return 0;
}

int plant_expm(int n, const double *M, double *E, double *work, int *iwork) {
    /* Pade [13/13] coefficients b_0 .. b_13 and theta_13 (Higham 2005, Table 2.3 and eq. 2.9). */
    static const double b[14] = {
        64764752532480000.0, 32382376266240000.0, 7771770303897600.0, 1187353796428800.0,
        129060195264000.0, 10559470521600.0, 670442572800.0, 33522128640.0, 1323241920.0,
        40840800.0, 960960.0, 16380.0, 182.0, 1.0};
    const double theta13 = 5.371920351148152;
    const size_t nn = (size_t)n * (size_t)n;
    double *A = work, *A2 = A + nn, *A4 = A2 + nn, *A6 = A4 + nn, *U = A6 + nn, *V = U + nn,
           *T = V + nn, *Q = T + nn, *d = Q + nn;

    for (size_t k = 0; k < nn; k++) {
        if (!isfinite(M[k])) return -1;
        A[k] = M[k];
    }
    balance(n, A, d);

    double norm = 0.0;
    for (int j = 0; j < n; j++) {
        double column = 0.0;
        for (int i = 0; i < n; i++) column += fabs(AT(A, i, j));
        if (column > norm) norm = column;
    }
    int squarings = 0;
    if (norm > theta13) squarings = (int)ceil(log2(norm / theta13));
    const double scale = ldexp(1.0, -squarings);
    for (size_t k = 0; k < nn; k++) A[k] *= scale;

    matmul(n, A, A, A2);
    matmul(n, A2, A2, A4);
    matmul(n, A4, A2, A6);
    /* U = A [A6 (b13 A6 + b11 A4 + b9 A2) + b7 A6 + b5 A4 + b3 A2 + b1 I] */
    for (size_t k = 0; k < nn; k++) Q[k] = b[13] * A6[k] + b[11] * A4[k] + b[9] * A2[k];
    matmul(n, A6, Q, T);
    for (size_t k = 0; k < nn; k++) T[k] += b[7] * A6[k] + b[5] * A4[k] + b[3] * A2[k];
    for (int i = 0; i < n; i++) AT(T, i, i) += b[1];
    matmul(n, A, T, U);
    /* V = A6 (b12 A6 + b10 A4 + b8 A2) + b6 A6 + b4 A4 + b2 A2 + b0 I */
    for (size_t k = 0; k < nn; k++) Q[k] = b[12] * A6[k] + b[10] * A4[k] + b[8] * A2[k];
    matmul(n, A6, Q, V);
    for (size_t k = 0; k < nn; k++) V[k] += b[6] * A6[k] + b[4] * A4[k] + b[2] * A2[k];
    for (int i = 0; i < n; i++) AT(V, i, i) += b[0];
    /* r13 = (V - U)^-1 (V + U) */
    for (size_t k = 0; k < nn; k++) {
        Q[k] = V[k] - U[k];
        E[k] = V[k] + U[k];
    }
    if (solve(n, Q, E, iwork) != 0) return -1;
    for (int s = 0; s < squarings; s++) {
        matmul(n, E, E, T);
        memcpy(E, T, nn * sizeof(double));
    }
    /* Undo the balancing: expm(M) = D expm(D^-1 M D) D^-1. */
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) AT(E, i, j) *= d[i] / d[j];
    return 0;
}
