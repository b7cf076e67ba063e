"""Closed-form impulse shapers, re-evaluated by tunable FMUs when a mode parameter changes.

Every function returns ``(times, amplitudes)`` as two lists of floats, times in seconds starting
at 0, amplitudes summing to 1. ``omega`` is the undamped natural frequency in rad/s, ``zeta`` the
damping ratio; ``sigma = zeta*omega`` and ``omega_d = omega*sqrt(1 - zeta^2)``.

All of them are solutions of the zero-vibration constraint of Singer & Seering (1990), eq. (20) of
La-orpacharapan & Pao (paper 002) for one mode:

    sum_i A_i exp(sigma t_i) exp(j omega_d t_i) = 0,      sum_i A_i = 1.
"""

import cmath
import math

from . import limits
from .checks import check_count, check_omega, check_zeta


UM_ZV_ZETA_MAX = 0.9


def _damped(omega, zeta):
    omega = check_omega(omega)
    zeta = check_zeta(zeta)
    return zeta * omega, omega * math.sqrt(1.0 - zeta * zeta)


def zv_dn(omega, zeta, n):
    """ZV shaper convolved with itself ``n`` more times: n = 0 is ZV, 1 is ZVD, 2 is ZVDD.

    ZV (paper 002, eq. 3): impulses 1/(1+K), K/(1+K) at 0 and pi/omega_d, with
    K = exp(-zeta*pi/sqrt(1 - zeta^2)). Convolving it n+1 times gives n+2 impulses spaced by
    pi/omega_d with amplitudes C(n+1, i) K^i / (1+K)^(n+1): the binomial expansion of
    (1 + K z)^(n+1) / (1+K)^(n+1), whose zero at z = -1/K has multiplicity n+1, so the residual
    vibration and its first n derivatives with respect to frequency vanish at the design point.
    """
    n = check_count(n, "n", minimum=0)
    if n > limits.MAX_ZV_DN_ORDER:
        raise ValueError(f"n must be in [0, {limits.MAX_ZV_DN_ORDER}] (shapefmu.runtime.limits.MAX_ZV_DN_ORDER: "
                         f"ZV convolved n + 1 times is (n + 1)/2 periods long), got {n}")
    sigma, omega_d = _damped(omega, zeta)
    half_period = math.pi / omega_d
    k = math.exp(-sigma * half_period)
    norm = (1.0 + k) ** (n + 1)
    times = [i * half_period for i in range(n + 2)]
    amplitudes = [math.comb(n + 1, i) * k**i / norm for i in range(n + 2)]
    return times, amplitudes


def mzv(omega, zeta):
    """Three impulses spaced 3/8 of the damped period apart (0.75 of the period in all).

    Fixing the spacing at Delta = 3*pi/(4*omega_d) and writing B_i = A_i exp(sigma t_i), the
    zero-vibration constraint reads B_1 + B_2 e^{j3pi/4} + B_3 e^{j3pi/2} = 0, whose real and
    imaginary parts give B_1 = B_3 = B_2/sqrt(2). Hence A = (1, sqrt(2) K, K^2) / (1 + sqrt(2) K + K^2)
    with K = exp(-sigma*Delta). Shorter than ZVD (0.75 vs 1 period), less robust than it.
    """
    sigma, omega_d = _damped(omega, zeta)
    spacing = 0.75 * math.pi / omega_d
    k = math.exp(-sigma * spacing)
    weights = [1.0, math.sqrt(2.0) * k, k * k]
    total = sum(weights)
    return [0.0, spacing, 2.0 * spacing], [w / total for w in weights]


def um_zv(omega, zeta, tol=1e-13, max_iter=50):
    """Unity-magnitude ZV: impulses +1, -1, +1 (for on-off actuators), times solved exactly.

    Undamped, the times are 0, T/6, T/3 (T the period). With damping the amplitudes stay +-1 and
    the constraint 1 - exp(s t_2) + exp(s t_3) = 0, s = sigma + j omega_d, is solved for t_2, t_3 by
    Newton's method, continued in zeta (steps of 0.01) from the undamped solution so that the root
    followed is the short one. As zeta grows the two later impulses close in on each other
    (zeta = 0.9: omega*t = 0, 6.1706, 6.1745) until they form a doublet and the Jacobian becomes
    singular, so the design is offered for zeta in [0, 0.9] only.
    """
    omega = check_omega(omega)
    zeta = check_zeta(zeta)
    if zeta > UM_ZV_ZETA_MAX:
        raise ValueError(f"zeta must be in [0, {UM_ZV_ZETA_MAX}] for the unity-magnitude ZV shaper, got {zeta!r}")
    # Dimensionless times tau = omega * t and s/omega = zeta + j sqrt(1 - zeta^2).
    tau2, tau3 = math.pi / 3.0, 2.0 * math.pi / 3.0
    steps = max(1, math.ceil(zeta / 0.01))
    for step in range(1, steps + 1):
        z = zeta * step / steps
        s = complex(z, math.sqrt(1.0 - z * z))
        for _ in range(max_iter):
            e2, e3 = cmath.exp(s * tau2), cmath.exp(s * tau3)
            f = 1.0 - e2 + e3
            # Jacobian of (Re f, Im f) with respect to (tau2, tau3): columns -s e2 and s e3.
            j2, j3 = -s * e2, s * e3
            det = j2.real * j3.imag - j3.real * j2.imag
            d2 = (f.real * j3.imag - j3.real * f.imag) / det
            d3 = (j2.real * f.imag - f.real * j2.imag) / det
            tau2, tau3 = tau2 - d2, tau3 - d3
            # Relative test: an absolute one stalls on rounding noise once tau3 grows with zeta.
            if abs(d2) + abs(d3) < tol * tau3:
                break
        else:
            raise ValueError(f"unity-magnitude ZV did not converge for zeta = {zeta!r}")
    if not 0.0 < tau2 < tau3:
        raise ValueError(f"unity-magnitude ZV has no ordered solution for zeta = {zeta!r}")
    return [0.0, tau2 / omega, tau3 / omega], [1.0, -1.0, 1.0]
