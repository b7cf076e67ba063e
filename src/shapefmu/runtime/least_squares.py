"""Dense linear least squares by Householder QR, for the small systems of the runtime solvers.

The initialisation-time solvers (``multimode``, ``ei``) solve systems of at most ~15 unknowns.
Householder QR is used rather than the normal equations because it keeps the conditioning of the
matrix itself instead of squaring it: the Jacobian of eq. (20) of paper 002 is poorly conditioned
when two impulse times nearly coincide, which is exactly where a start of the solver's grid may lie.
"""

import math


def solve_least_squares(rows, rhs):
    """x minimising ||A x - b||_2 for A given as a list of rows (m x n, m >= n) and b of length m.

    Returns ``None`` when A is rank deficient to working precision (a zero pivot in R), so that a
    caller can treat that start or step as failed instead of dividing by zero.
    """
    m = len(rows)
    n = len(rows[0]) if rows else 0
    if m < n or len(rhs) != m or n == 0:
        raise ValueError(f"A must be m x n with m >= n >= 1 and b of length m, got {m} x {n} and {len(rhs)}")
    a = [list(map(float, row)) for row in rows]
    b = [float(v) for v in rhs]
    scale = max((abs(v) for row in a for v in row), default=0.0)
    if scale == 0.0:
        return None
    diagonal = []
    for k in range(n):
        norm = math.sqrt(math.fsum(a[i][k] * a[i][k] for i in range(k, m)))
        if norm <= 1e-14 * scale:
            return None
        # Reflect column k onto -sign(a_kk) ||.|| e_k: the sign avoids cancellation in v_k.
        alpha = -norm if a[k][k] >= 0.0 else norm
        v = [0.0] * m
        v[k] = a[k][k] - alpha
        for i in range(k + 1, m):
            v[i] = a[i][k]
        vv = math.fsum(v[i] * v[i] for i in range(k, m))
        for j in range(k + 1, n):
            factor = 2.0 * math.fsum(v[i] * a[i][j] for i in range(k, m)) / vv
            for i in range(k, m):
                a[i][j] -= factor * v[i]
        factor = 2.0 * math.fsum(v[i] * b[i] for i in range(k, m)) / vv
        for i in range(k, m):
            b[i] -= factor * v[i]
        diagonal.append(alpha)
    x = [0.0] * n
    for k in range(n - 1, -1, -1):
        x[k] = (b[k] - math.fsum(a[k][j] * x[j] for j in range(k + 1, n))) / diagonal[k]
    return x
