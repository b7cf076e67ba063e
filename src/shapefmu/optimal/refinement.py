"""Exact switch times of a bang-bang move: Levenberg-Marquardt in double precision (``refine``) and,
for closely spaced modes, Newton on the extremal's equations in ``_EXACT_DIGITS`` digits (mpmath,
``refine_exact``)."""

from __future__ import annotations

import mpmath
import numpy as np
from scipy.optimize import least_squares
from scipy.sparse.csgraph import connected_components

from shapefmu.optimal.moves import _augmented_expm
from shapefmu.plants import Plant, as_plant


# ---------------------------------------------------------------------------------------------
# Switching-time refinement


def _final_state(A, B, switches, T, levels):
    """x(T) from rest and its Jacobian with respect to (switches..., T), exactly.

    x(T) = sum_k L_k (Phi(T - s_k) - Phi(T - s_{k+1})), Phi(tau) = int_0^tau e^{A s} ds B, so
    dx/ds_k = (L_{k-1} - L_k) e^{A (T - s_k)} B and dx/dT = A x(T) + B L_last.
    """
    edges = np.concatenate([[0.0], switches, [T]])
    x = np.zeros(A.shape[0])
    J = np.zeros((A.shape[0], len(switches) + 1))
    for k, level in enumerate(levels):
        E_a, G_a = _augmented_expm(A, B, T - edges[k])
        G_b = _augmented_expm(A, B, T - edges[k + 1])[1]
        x += level * (G_a[:, 0] - G_b[:, 0])
        if k > 0:
            J[:, k - 1] = (levels[k - 1] - level) * (E_a @ B[:, 0])
    J[:, -1] = A @ x + B[:, 0] * levels[-1]
    return x, J


def refine(plant, x_f, levels, switches, T, scale):
    """Switch times and T with x(T) = x_f exactly (to rounding), by Levenberg-Marquardt.

    Unknowns and residuals are dimensionless (times / T, states / ``scale``) so that the
    tolerances mean relative accuracy.

    Examples
    --------
    >>> import numpy as np
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(1.0, u_max=1.0)  # from a guess of the bang-bang's switch and end
    >>> switches, T = refine(plant, np.array([1.0, 0.0]), (1.0, -1.0), [0.9], 2.1, np.array([1.0, 1.0]))
    >>> [float(s) for s in switches], T
    ([1.0], 2.0)
    """
    A, B = plant.A, plant.B[:, :1]
    t0 = float(T)

    def residual(p):
        return (_final_state(A, B, p[:-1] * t0, p[-1] * t0, levels)[0] - x_f) / scale

    def jacobian(p):
        return _final_state(A, B, p[:-1] * t0, p[-1] * t0, levels)[1] * t0 / scale[:, None]

    p0 = np.append(np.asarray(switches, dtype=float), T) / t0
    # Levenberg-Marquardt needs at least as many residuals as unknowns; more switches than states
    # (fast oscillatory modes over a long move) leave a family of solutions: trust region then.
    method = "lm" if p0.size <= x_f.size else "trf"
    fit = least_squares(residual, p0, jac=jacobian, method=method, xtol=1e-15, ftol=1e-15, gtol=1e-15,
                        max_nfev=100 * p0.size)
    p = fit.x * t0
    return list(p[:-1]), float(p[-1])


# ---------------------------------------------------------------------------------------------
# Exact (extended-precision) propagation, for plants whose modes are closely spaced


_EXACT_DIGITS = 40


def _divided_difference(f, df, l1, l2):
    """f[l1, l2] = (f(l1) - f(l2)) / (l1 - l2), f'(l1) when l1 == l2 (Newton form of a 2x2 f(M))."""
    if l1 == l2:
        return df(l1)
    with mpmath.workdps(2 * mpmath.mp.dps):  # the difference of nearly equal values loses digits
        return (f(l1) - f(l2)) / (l1 - l2)


class _ExactPlant:
    """e^{A tau} B and Phi(tau) = int_0^tau e^{A s} ds B to ``_EXACT_DIGITS`` digits (mpmath).

    Closely spaced modes (the ten pendula) make the final state's dependence on the switch times
    nearly singular (relative singular values ~1e-14): double precision then fixes the switch
    times only to ~1e-4 and lets an iteration slide along the weak directions. In 40 digits those
    directions are resolved to ~1e-26. A is split into the blocks that no entry couples (a modal or
    physical-coordinate model is block diagonal), and each block of size <= 2 is evaluated in
    closed form, f(M) = f(l1) I + f[l1, l2] (M - l1 I) (Newton's form of Sylvester's formula) with
    f(l) = e^{l tau} and f(l) = (e^{l tau} - 1) / l; larger blocks use mpmath's expm of the
    augmented matrix [[A, B], [0, 0]].
    """

    def __init__(self, A, B):
        n = A.shape[0]
        _, labels = connected_components(np.abs(A) + np.abs(A.T) > 0, directed=False)
        self.n = n
        self.blocks = []
        for label in np.unique(labels):
            index = np.flatnonzero(labels == label)
            M = mpmath.matrix(A[np.ix_(index, index)].tolist())
            b = mpmath.matrix(B[index, 0].tolist())
            if index.size == 1:
                eigenvalues = (M[0, 0], M[0, 0])
            elif index.size == 2:
                half = (M[0, 0] + M[1, 1]) / 2
                root = mpmath.sqrt(mpmath.mpc(half**2 - (M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0])))
                eigenvalues = (half + root, half - root)
            else:
                eigenvalues = None
            self.blocks.append((index, M, b, eigenvalues))
        self.A = mpmath.matrix(A.tolist())
        self.B = mpmath.matrix(B[:, 0].tolist())

    def _block(self, M, b, eigenvalues, f, df):
        l1, l2 = eigenvalues
        if M.rows == 1:
            return mpmath.matrix([mpmath.re(f(l1)) * b[0]])
        c0, c1 = f(l1), _divided_difference(f, df, l1, l2)
        Mb = M * b
        return mpmath.matrix([mpmath.re(c0 * b[i] + c1 * (Mb[i] - l1 * b[i])) for i in range(M.rows)])

    def propagate(self, tau):
        """(e^{A tau} B, Phi(tau)) as mpmath vectors."""
        tau = mpmath.mpf(tau)
        E, P = mpmath.matrix(self.n, 1), mpmath.matrix(self.n, 1)
        for index, M, b, eigenvalues in self.blocks:
            if eigenvalues is None:
                k = M.rows
                aug = mpmath.zeros(k + 1, k + 1)
                for i in range(k):
                    aug[i, k] = b[i] * tau
                    for j in range(k):
                        aug[i, j] = M[i, j] * tau
                Z = mpmath.expm(aug)
                e_block = mpmath.matrix([sum(Z[i, j] * b[j] for j in range(k)) for i in range(k)])
                p_block = mpmath.matrix([Z[i, k] for i in range(k)])
            else:
                exp = lambda l: mpmath.exp(l * tau)
                dexp = lambda l: tau * mpmath.exp(l * tau)
                phi = lambda l: mpmath.expm1(l * tau) / l if l != 0 else tau
                dphi = lambda l: (l * tau * mpmath.exp(l * tau) - mpmath.expm1(l * tau)) / l**2 if l != 0 else tau**2 / 2
                e_block = self._block(M, b, eigenvalues, exp, dexp)
                p_block = self._block(M, b, eigenvalues, phi, dphi)
            for i, row in enumerate(index):
                E[int(row)], P[int(row)] = e_block[i], p_block[i]
        return E, P

    def switching_function(self, eta):
        """sigma(tau) = eta^T e^{A tau} B as a function of the time to go tau, in closed form per block:
        eta_b^T f(M) b = f(l1) eta_b^T b + f[l1, l2] eta_b^T (M - l1 I) b with f(l) = e^{l tau}."""
        terms = []
        for index, M, b, eigenvalues in self.blocks:
            e = [eta[int(i)] for i in index]
            if eigenvalues is None:
                terms.append((None, M, b, e))
            else:
                Mb = M * b
                along_b = sum(e[i] * b[i] for i in range(M.rows))
                along_m = sum(e[i] * (Mb[i] - eigenvalues[0] * b[i]) for i in range(M.rows)) if M.rows == 2 else 0
                terms.append((eigenvalues, along_b, along_m, None))

        def sigma(tau):
            tau = mpmath.mpf(tau)
            exp = lambda l: mpmath.exp(l * tau)
            dexp = lambda l: tau * mpmath.exp(l * tau)
            total = mpmath.mpf(0)
            for eigenvalues, first, second, e in terms:
                if eigenvalues is None:  # first, second = M, b of a block larger than 2
                    total += sum(ei * value for ei, value in zip(e, mpmath.expm(first * tau) * second))
                else:
                    l1, l2 = eigenvalues
                    total += mpmath.re(first * exp(l1) + second * _divided_difference(exp, dexp, l1, l2))
            return total

        return sigma

    def final_state(self, switches, T, levels):
        """x(T) from rest, its Jacobian in (switches..., T) as in ``_final_state``, and the columns
        e^{A (T - s)} B at s = 0, the switches and T, exactly."""
        edges = [mpmath.mpf(0), *switches, T]
        phis, columns = [], []
        for edge in edges:
            E, P = self.propagate(T - edge)
            phis.append(P)
            columns.append(E)
        x = mpmath.matrix(self.n, 1)
        for k, level in enumerate(levels):
            x += level * (phis[k] - phis[k + 1])
        J = mpmath.matrix(self.n, len(switches) + 1)
        for k in range(1, len(levels)):
            for i in range(self.n):
                J[i, k - 1] = (levels[k - 1] - levels[k]) * columns[k][i]
        rate = self.A * x + self.B * levels[-1]
        for i in range(self.n):
            J[i, len(switches)] = rate[i]
        return x, J, columns


def _rest_state_exact(plant: Plant, distance: float, output: int):
    """``rest_state`` in extended precision (a double solve leaves ~1e-17 in the modal targets,
    which the weak directions would amplify)."""
    j = output
    M = np.block([[plant.A, plant.B[:, :1]], [plant.C[j : j + 1], plant.D[j : j + 1, :1]]])
    rhs = mpmath.matrix(M.shape[0], 1)
    rhs[M.shape[0] - 1] = mpmath.mpf(distance)
    return mpmath.lu_solve(mpmath.matrix(M.tolist()), rhs)[: plant.n_states, 0]


def refine_exact(plant, distance: float, output: int, levels, switches, T, max_iterations: int = 40):
    """Switch times, T and the costate eta of a bang-bang extremal, by Newton's method in
    ``_EXACT_DIGITS`` digits: x(T) = x_f, sigma(s_k) = eta^T e^{A (T - s_k)} B = 0 at every switch
    and eta^T x_f = 1 (n + m + 1 equations in the m switches, T and the n costate components).

    With the costate among the unknowns the system is square for any number of switches m (the
    ten pendula's longer moves need n + 1). Returns (switches, T) rounded to double, or None if
    Newton does not converge, reorders the switches or meets a singular Jacobian.

    Examples
    --------
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(1.0, u_max=1.0)  # x'' = u, |u| <= 1: T = 2 sqrt(X / (b U)) = 2 for X = 1
    >>> refine_exact(plant, 1.0, 0, (1.0, -1.0), [0.9], 2.1)
    ([1.0], 2.0)
    """
    plant = as_plant(plant)
    n, m = plant.n_states, len(switches)
    with mpmath.workdps(_EXACT_DIGITS):
        exact = _ExactPlant(plant.A, plant.B[:, :1])
        x_f = _rest_state_exact(plant, distance, output)
        levels = [mpmath.mpf(level) for level in levels]
        # Initial costate: the direction nearest to orthogonal to e^{A (T - s_k)} B at every switch.
        rows = mpmath.zeros(m + 1, n)
        for k, s in enumerate(switches):
            column = exact.propagate(mpmath.mpf(T) - s)[0]
            for i in range(n):
                rows[k, i] = column[i]
        eta = mpmath.svd_r(rows, full_matrices=True)[2][n - 1, :].T
        along = sum(eta[i] * x_f[i] for i in range(n))
        if along == 0:
            return None
        p = mpmath.matrix([*map(mpmath.mpf, switches), mpmath.mpf(T), *(eta / along)])
        for _ in range(max_iterations):
            s, t_end, eta = list(p[:m]), p[m], p[m + 1 :]
            x, J_x, columns = exact.final_state(s, t_end, levels)
            F = mpmath.zeros(n + m + 1, 1)
            J = mpmath.zeros(n + m + 1, n + m + 1)
            for i in range(n):
                F[i] = x[i] - x_f[i]
                for j in range(m + 1):
                    J[i, j] = J_x[i, j]
            for k in range(m):
                column = columns[k + 1]
                rate = exact.A * column
                F[n + k] = sum(eta[i] * column[i] for i in range(n))
                slope = sum(eta[i] * rate[i] for i in range(n))
                J[n + k, k], J[n + k, m] = -slope, slope
                for i in range(n):
                    J[n + k, m + 1 + i] = column[i]
            F[n + m] = sum(eta[i] * x_f[i] for i in range(n)) - 1
            for i in range(n):
                J[n + m, m + 1 + i] = x_f[i]
            try:
                step = mpmath.lu_solve(J, -F)
            except ZeroDivisionError:
                return None
            p += step
            edges = [0.0, *(float(v) for v in p[: m + 1])]
            if any(b <= a for a, b in zip(edges[:-1], edges[1:])):
                return None
            if mpmath.norm(step[: m + 1]) <= mpmath.mpf(10) ** (16 - _EXACT_DIGITS) * p[m]:
                x = exact.final_state(list(p[:m]), p[m], levels)[0]
                if mpmath.norm(x - x_f) > mpmath.mpf(10) ** (20 - _EXACT_DIGITS) * mpmath.norm(x_f):
                    return None
                return [float(v) for v in p[:m]], float(p[m])
        return None
