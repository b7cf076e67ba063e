"""Time-frequency localised motion profile (Zhou & Misawa, paper 004), standard library only.

What a ProfileGenerator or ShapeFilter FMU computes at initialisation: the sampled derivative of a
Gaussian g_{phi,n}[k] = phi_n((k - M/2) Ts), k = 0..M (eq. 12, 15), with the scale n that minimises
the share of its energy above the first resonance, 1 - J (eq. 18-20), found by bounded Brent
minimisation (``scalar_search.minimize_bounded``, the algorithm of Matlab's ``fminbound`` that the
paper uses and of scipy's ``minimize_scalar(method="bounded")``). The design layer
``shapefmu.shapers.time_frequency`` calls these functions, so what is analysed is what the FMU
runs; ``tests/test_runtime_profiles.py`` checks them against scipy and closed forms.

The objective 1 - J is computed as the energy above omega_0 over the total energy (``_leakage``),
not as one minus the share below: near the optimum 1 - J is 1e-5 (2.5 ms moves) to 1e-10 (5 ms),
and one minus a ratio would keep only its first few digits, too few to place n to 1e-6.
"""

import functools
import math
import operator
from dataclasses import dataclass

from .checks import check_omega, check_positive, check_size
from .motion import PiecewiseAcceleration, held_acceleration
from .scalar_search import minimize_bounded

# Relative tolerance on move_time / ts being an integer number of samples M.
_RTOL = 1e-9


def phi(t, n):
    """phi_n(t) = -t exp(-2^{2n} t^2 / 2) (paper 004, eq. 12)."""
    return -t * math.exp(-0.5 * 4.0**n * t * t)


def samples(move_time, ts):
    """M = move_time / ts, which must be an integer >= 2 (eq. 15 samples k = 0..M)."""
    move_time = check_positive(move_time, "move_time")
    ts = check_positive(ts, "ts")
    m_real = move_time / ts
    check_size(m_real, "MAX_SAMPLED_LENGTH", f"move_time / ts = {move_time!r} / {ts!r} gives M =", "samples",
               "use a longer ts or a shorter move_time")
    m = round(m_real)
    if m < 2 or abs(m_real - m) > _RTOL * m_real:
        lo, hi = max(2, math.floor(m_real)), max(2, math.ceil(m_real))
        raise ValueError(
            f"move_time / ts must be an integer M >= 2, got {move_time!r} / {ts!r} = {m_real:.6g}; the nearest "
            f"valid move times are {lo * ts:.10g} s (M = {lo}) and {hi * ts:.10g} s (M = {hi})"
        )
    return m


def sampled_phi(n, ts, move_time):
    """g_{phi,n}[k] = phi_n((k - M/2) Ts), k = 0..M (eq. 15): antisymmetric, it sums to zero."""
    m = samples(move_time, ts)
    return [phi((k - m / 2.0) * ts, n) for k in range(m + 1)]


def scale_bounds(ts, move_time):
    """Default search interval of n: the peak time 2^{-n} between one sample and half the move."""
    return math.log2(2.0 / check_positive(move_time, "move_time")), math.log2(1.0 / check_positive(ts, "ts"))


def _bounds(bounds, ts, move_time):
    lo, hi = scale_bounds(ts, move_time) if bounds is None else (float(bounds[0]), float(bounds[1]))
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ValueError(f"bounds must be finite with low < high, got {bounds!r}")
    return lo, hi


def _omega_0(first_resonance, ts):
    omega_0 = check_omega(first_resonance, "first_resonance") * check_positive(ts, "ts")
    if omega_0 >= math.pi:
        raise ValueError(
            f"first_resonance * ts must be in (0, pi) (below the Nyquist frequency), got {omega_0:.6g}"
        )
    return omega_0


def gauss_legendre(count):
    """Nodes and weights of the ``count``-point Gauss-Legendre rule on [-1, 1].

    Nodes are the roots of P_count, found by Newton's method from Tricomi's estimate
    cos(pi (i - 1/4) / (count + 1/2)), P and P' from the three-term recurrence; weights
    2 / ((1 - x^2) P'(x)^2) (Abramowitz & Stegun 25.4.29).
    """
    nodes, weights = [], []
    for i in range(1, count // 2 + 1):
        x = math.cos(math.pi * (i - 0.25) / (count + 0.5))
        for _ in range(100):
            p, p_previous = x, 1.0
            for degree in range(2, count + 1):
                p, p_previous = ((2 * degree - 1) * x * p - (degree - 1) * p_previous) / degree, p
            derivative = count * (x * p - p_previous) / (x * x - 1.0)
            dx = p / derivative
            x -= dx
            if abs(dx) <= 1e-16:
                break
        weight = 2.0 / ((1.0 - x * x) * derivative * derivative)
        nodes += [x, -x]
        weights += [weight, weight]
    if count % 2:  # the middle node x = 0, where P'_count(0) = count P_{count-1}(0)
        nodes.append(0.0)
        weights.append(2.0 / (count * _legendre_at_zero(count - 1)) ** 2)
    return nodes, weights


def _legendre_at_zero(degree):
    """P_degree(0) = (-1)^(degree/2) (degree - 1)!! / degree!! for even degree, 0 for odd."""
    value = 1.0
    for k in range(2, degree + 1, 2):
        value *= -(k - 1) / k
    return value if degree % 2 == 0 else 0.0


@functools.lru_cache(maxsize=4)
def _out_of_band_rule(size, omega_0):
    """Gauss-Legendre rule on [omega_0, pi] and the cosines and sines it needs for ``size`` samples.

    With c_k = M/2 - k, |G(omega)| = |sum_k g_k exp(j omega c_k)|; pairing k with M - k
    (c_{M-k} = -c_k) leaves cos(omega c_k) and sin(omega c_k) for k < M/2 only. |G|^2 is a
    trigonometric polynomial of degree M; on an interval of half-width h, exp(j M omega) has
    Legendre coefficients ~ j_l(M h), negligible once l > M h + 8 (M h)^(1/3), so a rule exact
    to degree 2 count - 1 above that integrates |G|^2 to rounding.
    """
    half_width = 0.5 * (math.pi - omega_0)
    reach = (size - 1) * half_width
    count = math.ceil(0.5 * (reach + 8.0 * reach ** (1.0 / 3.0))) + 16
    nodes, weights = gauss_legendre(count)
    offsets = [0.5 * (size - 1) - k for k in range(size // 2)]
    omegas = [omega_0 + half_width * (x + 1.0) for x in nodes]
    cosines = [[math.cos(w * c) for c in offsets] for w in omegas]
    sines = [[math.sin(w * c) for c in offsets] for w in omegas]
    return [half_width * w for w in weights], cosines, sines


def _leakage(g, omega_0):
    """1 - J of eq. (19), as the energy above omega_0 over the total, both computed directly.

    Eq. (19)'s numerator int_0^pi |G|^2 - int_0^{omega_0} |G|^2 is int_{omega_0}^pi |G|^2: a sum of
    positive terms w_i |G(omega_i)|^2 (``_out_of_band_rule``), with no cancellation. The
    denominator is pi sum g^2 (Parseval).
    """
    size = len(g)
    half = size // 2
    even = [g[k] + g[size - 1 - k] for k in range(half)]  # weights of cos(omega c_k)
    odd = [g[k] - g[size - 1 - k] for k in range(half)]  # weights of sin(omega c_k)
    middle = g[half] if size % 2 else 0.0  # c = 0 when M is even
    weights, cosines, sines = _out_of_band_rule(size, omega_0)
    outside = math.fsum(
        w * ((math.fsum(map(operator.mul, even, cos_row)) + middle) ** 2 + math.fsum(map(operator.mul, odd, sin_row)) ** 2)
        for w, cos_row, sin_row in zip(weights, cosines, sines)
    )
    return outside / (math.pi * math.fsum(v * v for v in g))


def energy_leakage(n, first_resonance, ts, move_time):
    """1 - J (eq. 18-19): the share of the energy of g_{phi,n} above omega_0 = Omega_0 Ts."""
    return _leakage(sampled_phi(n, ts, move_time), _omega_0(first_resonance, ts))


def optimal_scale(first_resonance, ts, move_time, bounds=None):
    """(n, 1 - J) at the n minimising 1 - J on ``bounds`` (eq. 20), n to within ~1e-6."""
    omega_0 = _omega_0(first_resonance, ts)
    lo, hi = _bounds(bounds, ts, move_time)
    m = samples(move_time, ts)
    t = [(k - m / 2.0) * ts for k in range(m + 1)]
    return minimize_bounded(lambda n: _leakage([phi(x, n) for x in t], omega_0), lo, hi, xatol=1e-6)


@dataclass(frozen=True)
class TimeFrequencyDesign:
    """The scale n, its leakage 1 - J, the unscaled kernel g_{phi,n} at ``ts`` and the exact move."""

    n: float
    leakage: float
    kernel: list
    ts: float
    motion: PiecewiseAcceleration

    def sample(self):
        """Lists (t, acceleration, velocity, position) of ``motion`` on the design layer's grid k ts, k = 0..M + 1."""
        return self.motion.sample(self.ts, len(self.kernel) + 1)


def time_frequency_profile(first_resonance, ts, move_time, distance, n=None, *, bounds=None):
    """Rest-to-rest move over ``distance`` with held acceleration K g_{phi,n}[k] (eq. 15).

    ``n`` defaults to the optimum of eq. (20) within ``bounds`` (default ``scale_bounds``); K makes
    the position end at ``distance`` ("a constant gain K", section II). The acceleration lasts
    (M + 1) Ts.
    """
    distance = check_positive(distance, "distance")
    lo, hi = _bounds(bounds, ts, move_time)
    if n is None:
        n, leakage = optimal_scale(first_resonance, ts, move_time, (lo, hi))
    else:
        n = float(n)
        if not lo <= n <= hi:
            raise ValueError(f"n must be in [{lo:.6g}, {hi:.6g}] (the searched bounds), got {n!r}")
        leakage = energy_leakage(n, first_resonance, ts, move_time)
    g = sampled_phi(n, ts, move_time)
    unit = held_acceleration(g, ts).distance
    if not unit > 0.0:
        raise ValueError(f"n = {n!r} makes g_phi,n vanish on the grid; choose n within the bounds")
    return TimeFrequencyDesign(n, leakage, g, ts, held_acceleration([v * (distance / unit) for v in g], ts))
