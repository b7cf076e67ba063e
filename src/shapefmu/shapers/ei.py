"""Extra-insensitive (EI) shapers with one, two and three humps, exact for damping in [0, 0.3].

Definition (Singhose, Seering & Singer; the vector-diagram formulation). An N-hump EI shaper has
N + 2 impulses. Its percent residual vibration V(nu) against the frequency ratio
nu = omega_actual / omega (same damping ratio) has, around nu = 1, an alternating sequence of
N + 1 zeros and N humps:

    zero, hump, zero, ..., hump, zero,     every hump a local maximum of height exactly vtol.

The design frequency sits on the middle element: the middle hump for odd N (EI, three-hump EI:
V(1) = vtol, the shaper tolerates vtol at the model frequency to widen the band) and the middle
zero for even N (two-hump EI: V(1) = 0).

Equations, with dimensionless times tau = omega t and
R(nu) = sum_k A_k exp(nu [(zeta + j sqrt(1 - zeta^2)) tau_k - zeta tau_last]), V = |R| / sum A:

    sum_k A_k = 1                                                   1
    |R(nu_h)|^2 = vtol^2,  d|R|^2/dnu (nu_h) = 0    for each hump   2N
    Re R(nu_z) = Im R(nu_z) = 0                      for each zero   2(N + 1)

Unknowns: N + 2 amplitudes, N + 1 times (tau_1 = 0), and the N + (N + 1) hump and zero
frequencies less the one pinned at nu = 1: 4N + 3 equations, 4N + 3 unknowns.

At zeta = 0 the solutions are known in closed form (times 0, T/2, ..., amplitudes below) and are
exact; they start a continuation in zeta (steps of at most 0.02, halved where needed) that Newton's method (MINPACK
hybrid) follows to the requested damping. The result depends only on (N, zeta, vtol), so it is
cached in dimensionless form and scaled by 1/omega.

Where the continuation reaches (measured with steps of 0.01 in zeta): EI and two-hump EI for every
zeta in [0, 0.3] with vtol <= 0.05; three-hump EI for every zeta in [0, 0.3] with vtol <= 0.03 and
with vtol = 0.05, but for vtol in (0.03, 0.05) it stops between zeta = 0.27 and 0.29, where the
constraint Jacobian turns singular. For larger vtol the multi-hump branches end earlier, because
the outermost zero leaves for infinite frequency (three-hump vtol 0.08 up to zeta 0.22, vtol 0.1
up to 0.20; two-hump vtol 0.1 up to 0.28, vtol 0.2 up to 0.20). Beyond its reach ValueError says
how far the continuation got.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy.optimize import root

from shapefmu.runtime.checks import check_omega, check_vtol, check_zeta
from shapefmu.shapers.impulse import ImpulseShaper

ZETA_MAX = 0.3
_ZETA_STEP = 0.02


def ei(omega: float, zeta: float = 0.0, vtol: float = 0.05) -> ImpulseShaper:
    """Extra-insensitive shaper: 3 impulses over one damped period, V(omega) = vtol.

    Undamped it is (1+V)/4, (1-V)/2, (1+V)/4 at 0, T/2, T; with damping the constraints in the
    module docstring are solved exactly. I(5 %) = 0.399 at zeta = 0 (ZVD: 0.287).
    """
    return _design(1, omega, zeta, vtol)


def ei2(omega: float, zeta: float = 0.0, vtol: float = 0.05) -> ImpulseShaper:
    """Two-hump EI: 4 impulses over 1.5 periods, zero at omega, humps of vtol either side."""
    return _design(2, omega, zeta, vtol)


def ei3(omega: float, zeta: float = 0.0, vtol: float = 0.05) -> ImpulseShaper:
    """Three-hump EI: 5 impulses over 2 periods, humps of vtol at omega and either side."""
    return _design(3, omega, zeta, vtol)


def _design(humps: int, omega, zeta, vtol) -> ImpulseShaper:
    omega = check_omega(omega)
    zeta = check_zeta(zeta)
    if zeta > ZETA_MAX:
        raise ValueError(f"zeta must be in [0, {ZETA_MAX}] for EI shapers, got {zeta!r}")
    vtol = check_vtol(vtol)
    if vtol > 0.25:
        raise ValueError(f"vtol must be in (0, 0.25] for EI shapers, got {vtol!r}")
    tau, amplitudes = _dimensionless(humps, zeta, vtol)
    return ImpulseShaper(tuple(t / omega for t in tau), amplitudes)


def _undamped(humps: int, vtol: float):
    """Exact zeta = 0 solutions: times k*pi (half periods) and symmetric amplitudes."""
    v = vtol
    if humps == 1:
        a = [(1 + v) / 4, (1 - v) / 2, (1 + v) / 4]
    elif humps == 2:
        x = (v * v * (math.sqrt(1 - v * v) + 1)) ** (1 / 3)
        a1 = (3 * x * x + 2 * x + 3 * v * v) / (16 * x)
        a = [a1, 0.5 - a1, 0.5 - a1, a1]
    else:
        a1 = (1 + 3 * v + 2 * math.sqrt(2 * v * (v + 1))) / 16
        a2 = (1 - v) / 4
        a = [a1, a2, 1 - 2 * (a1 + a2), a2, a1]
    return np.arange(humps + 2) * math.pi, np.array(a)


def _response(nu, tau, amplitudes, zeta):
    """R(nu) and dR/dnu for the dimensionless impulse sequence (see module docstring)."""
    exponent = (zeta + 1j * math.sqrt(1 - zeta * zeta)) * tau - zeta * tau[-1]
    # Newton may probe huge nu near the end of a branch: let it see inf and shorten its step.
    with np.errstate(over="ignore", invalid="ignore"):
        terms = amplitudes * np.exp(np.multiply.outer(nu, exponent))
    return terms.sum(axis=-1), (terms * exponent).sum(axis=-1)


def _extrema(tau, amplitudes, zeta):
    """Zeros (local minima) and humps (local maxima) of V on (0.05, 2.5), from a fine grid."""
    nu = np.linspace(0.05, 2.5, 24501)
    v = np.abs(_response(nu, tau, amplitudes, zeta)[0])
    interior = slice(1, -1)
    minima = nu[interior][(v[1:-1] < v[:-2]) & (v[1:-1] <= v[2:])]
    maxima = nu[interior][(v[1:-1] > v[:-2]) & (v[1:-1] >= v[2:])]
    return minima, maxima


def _nearest(values, count, pinned=None):
    """The ``count`` values nearest to nu = 1, sorted, dropping the one pinned at 1."""
    chosen = np.sort(values[np.argsort(np.abs(values - 1.0))[:count]])
    if pinned:
        chosen = np.delete(chosen, np.argmin(np.abs(chosen - 1.0)))
    return chosen


def _residuals(x, humps, zeta, vtol):
    n = humps + 2
    amplitudes = x[:n]
    tau = np.concatenate([[0.0], x[n : 2 * n - 1]])
    rest = x[2 * n - 1 :]
    hump_nu, zero_nu = _split_frequencies(rest, humps)
    r_h, dr_h = _response(hump_nu, tau, amplitudes, zeta)
    r_z, _ = _response(zero_nu, tau, amplitudes, zeta)
    return np.concatenate(
        [
            [amplitudes.sum() - 1.0],
            np.abs(r_h) ** 2 - vtol * vtol,
            2.0 * np.real(np.conj(r_h) * dr_h),
            r_z.real,
            r_z.imag,
        ]
    )


def _split_frequencies(free, humps):
    """Hump and zero frequencies from the free unknowns, with nu = 1 re-inserted where pinned."""
    if humps % 2:  # odd: the middle hump is pinned at 1
        free_humps, zeros = free[: humps - 1], free[humps - 1 :]
        return np.sort(np.concatenate([free_humps, [1.0]])), zeros
    free_humps, free_zeros = free[:humps], free[humps:]
    return free_humps, np.sort(np.concatenate([free_zeros, [1.0]]))


@functools.lru_cache(maxsize=256)
def _dimensionless(humps: int, zeta: float, vtol: float):
    tau, amplitudes = _undamped(humps, vtol)
    minima, maxima = _extrema(tau, amplitudes, 0.0)
    odd = humps % 2 == 1
    x = np.concatenate(
        [
            amplitudes,
            tau[1:],
            _nearest(maxima, humps, pinned=odd),
            _nearest(minima, humps + 1, pinned=not odd),
        ]
    )
    # Continuation in zeta; a step that Newton cannot close is halved (near zeta = 0.28 the
    # three-hump Jacobian is poorly conditioned and a 0.02 step overshoots).
    done, step = 0.0, _ZETA_STEP
    while done < zeta:
        z = min(zeta, done + step)
        solution = root(_residuals, x, args=(humps, z, vtol), method="hybr", options={"xtol": 1e-14})
        worst = float(np.max(np.abs(_residuals(solution.x, humps, z, vtol))))
        if worst <= 1e-12:
            x, done = solution.x, z
        elif step > _ZETA_STEP / 64:
            step /= 2
        else:
            raise ValueError(
                f"the {humps}-hump EI shaper with vtol = {vtol:g} could be followed only up to "
                f"zeta = {done:.3g} (asked for {zeta:g}): its constraints turn singular there; the "
                "default vtol = 0.05 reaches every zeta in [0, 0.3]"
            )
    n = humps + 2
    tau = np.concatenate([[0.0], x[n : 2 * n - 1]])
    amplitudes = x[:n]
    if np.any(np.diff(tau) <= 0) or np.any(amplitudes <= 0):
        raise ValueError(f"EI ({humps} hump) solution lost its shape at zeta = {zeta:g}, vtol = {vtol:g}")
    return tuple(tau), tuple(amplitudes)
