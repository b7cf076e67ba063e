"""Window-function shape filters (Zhou & Misawa, paper 000), standard library only.

The taps a ShapeFilter FMU computes at initialisation from its parameters, and the taps the design
layer (``shapefmu.shapers.window``, whose docstrings carry the paper's derivations) returns: it
calls these functions, so what is analysed is what the FMU runs. ``tests/test_runtime_profiles.py``
checks the taps against windows built with ``scipy.signal.windows``.

A base sequence h[k] with H(omega_d Ts) = 0 becomes the filter for the mode (omega_n, zeta) by
damping compensation and normalisation (paper 000, Conclusion 2.1 and section 3),

    f[k] = h[k] e^{-zeta omega_n k Ts} / sum_m h[m] e^{-zeta omega_n m Ts},

and robustness order n is its n-fold self-convolution (eq. 1).

Every function has the signature ``name(omega_n, zeta, ts, order=1, *, adjust_ts=False, ...)`` and
returns ``(taps, ts)``: a list of floats summing to 1 and the sampling period actually used. The
window length M follows from omega_d ts and must be an integer: a ts that does not make it one
raises ValueError naming the nearest valid periods, unless ``adjust_ts`` picks the nearest. Adjusting
rounds M, never more: a ts too long for the shortest window (M below its minimum by more than a
half) is refused naming the longest ts that makes one, where it silently became that ts (a ts of
1 s for a 40 Hz mode became 0.007 s).
"""

import math

from .checks import check_count, check_finite, check_omega, check_positive, check_size, check_zeta

# Relative tolerance on ts for "M is an integer": ts given to ~10 significant digits is accepted.
_TS_RTOL = 1e-9


def damped_mode(omega_n, zeta):
    """Validated (omega_n, zeta, omega_d) of the design point."""
    omega_n = check_omega(omega_n, "omega_n")
    zeta = check_zeta(zeta)
    return omega_n, zeta, omega_n * math.sqrt(1.0 - zeta * zeta)


def window_length(omega_d, ts, adjust_ts, m_of_ts, ts_of_m, minimum, formula):
    """The integer window length M for ``ts``, and the ts actually used.

    ``m_of_ts`` gives the real M for a sampling period, ``ts_of_m`` its inverse; ``minimum`` is the
    shortest window whose null is the design null (below it the null aliases onto a pole of the
    window's transform). ``formula`` names the relation in error messages.
    """
    ts = check_positive(ts, "ts")
    try:
        m_real = m_of_ts(omega_d * ts)
    except ZeroDivisionError:  # omega_d * ts underflowed to 0
        m_real = math.inf
    check_size(m_real, "MAX_SAMPLED_LENGTH", f"ts = {ts!r} s gives a window of M = {formula} =", "samples",
               "use a longer ts")
    if m_real < minimum - 0.5:
        raise ValueError(f"ts = {ts!r} s gives a window of M = {formula} = {m_real:.3g} samples, fewer than the "
                         f"{minimum} a window needs: ts must be at most {ts_of_m(minimum) / omega_d:.6g} s for "
                         f"omega_d = {omega_d:.6g} rad/s")
    candidates = sorted({max(minimum, math.floor(m_real)), max(minimum, math.ceil(m_real))})
    nearest = min(candidates, key=lambda m: abs(ts_of_m(m) / omega_d - ts))
    ts_nearest = ts_of_m(nearest) / omega_d
    if abs(ts_nearest - ts) <= _TS_RTOL * ts:
        return nearest, ts
    if adjust_ts:
        return nearest, ts_nearest
    options = ", ".join(f"{ts_of_m(m) / omega_d:.10g} s (M = {m})" for m in candidates)
    raise ValueError(
        f"ts = {ts!r} s gives M = {formula} = {m_real:.6g}, which is not an integer; valid ts make M an "
        f"integer >= {minimum}, the nearest are {options}; or pass adjust_ts=True"
    )


def convolve(a, b):
    """Full discrete convolution of two sequences (length len(a) + len(b) - 1)."""
    check_size(len(a) * len(b), "MAX_CONVOLUTION_PRODUCTS",
               f"convolving windows of {len(a)} and {len(b)} samples takes", "multiply-adds", "use a longer ts")
    out = [0.0] * (len(a) + len(b) - 1)
    for i, x in enumerate(a):
        if x:
            for j, y in enumerate(b):
                out[i + j] += x * y
    return out


def check_order_cost(length, order):
    """Refuse order n of a ``length``-tap filter past the limits, before convolving: eq. (1) repeats
    the convolution n - 1 times on a growing sequence, about length^2 n^2 / 2 multiply-adds."""
    check_size(order * (length - 1) + 1, "MAX_SAMPLED_LENGTH", f"order {order} of a {length}-tap window has",
               "taps", "use a lower order or a longer ts")
    check_size(length * length * order * (order - 1) // 2, "MAX_CONVOLUTION_PRODUCTS",
               f"order {order} of a {length}-tap window takes", "multiply-adds", "use a lower order or a longer ts")


def _shape(h, omega_n, zeta, ts, order):
    """Damping compensation and normalisation (section 3), then order n by eq. (1)."""
    order = check_count(order, "order", 1)
    check_order_cost(len(h), order)
    f = [v * math.exp(-zeta * omega_n * k * ts) for k, v in enumerate(h)]
    total = math.fsum(f)
    f = [v / total for v in f]
    out = f
    for _ in range(order - 1):
        out = convolve(out, f)
    return out, ts


def _cosine_window(m, coefficients):
    """sum_i c_i cos(2 pi i k / M), k = 0..M (eq. 2 and the Blackman / Hamming forms)."""
    return [
        math.fsum(c * math.cos(2.0 * math.pi * i * k / m) for i, c in enumerate(coefficients)) for k in range(m + 1)
    ]


# Base windows of paper 000: (coefficients of cos(2 pi i k/M), null at omega_d Ts = 2 pi m0 / M,
# smallest M). The null of a generalised cosine window of M + 1 samples whose end samples are zero
# sits on every DFT bin 2 pi m / M with m beyond its last cosine term; m0 is the first of them.
_COSINE_WINDOWS = {
    "hanning": ((0.5, -0.5), 2, 4),  # eq. (2): M = 4 pi / (omega_d Ts)
    "blackman": ((0.42, -0.5, 0.08), 3, 6),  # section 4: M = 6 pi / (omega_d Ts)
    "hamming": ((25.0 / 46.0, -21.0 / 46.0), 2, 4),  # section 5: approximate null only
}


def cosine_base(name, omega_d, ts, adjust_ts):
    """The base window ``name`` of ``_COSINE_WINDOWS`` for omega_d and ts, and the ts used."""
    coefficients, m0, minimum = _COSINE_WINDOWS[name]
    m, ts = window_length(
        omega_d,
        ts,
        adjust_ts,
        lambda u: 2.0 * math.pi * m0 / u,
        lambda m: 2.0 * math.pi * m0 / m,
        minimum,
        f"{2 * m0}*pi/(omega_d*ts)",
    )
    return _cosine_window(m, coefficients), ts


def _rectangle_length(omega_d, ts, adjust_ts):
    # M equal samples k = 0..M-1 null every bin 2 pi m / M, m >= 1 (Zhou & Misawa 2005a).
    return window_length(
        omega_d, ts, adjust_ts, lambda u: 2.0 * math.pi / u, lambda m: 2.0 * math.pi / m, 2, "2*pi/(omega_d*ts)"
    )


def _base(base, omega_d, ts, adjust_ts):
    """A symmetric base g with G(omega_d Ts) = 0, for the non-symmetric constructions (section 8)."""
    if base == "rectangle":
        m, ts = _rectangle_length(omega_d, ts, adjust_ts)
        return [1.0] * m, ts
    if base in ("hanning", "blackman"):
        return cosine_base(base, omega_d, ts, adjust_ts)
    raise ValueError(f"base must be one of 'rectangle', 'hanning', 'blackman', got {base!r}")


def _check_gain(h, name):
    # The filter is normalised by the sum of its samples, which the weights can cancel.
    if abs(math.fsum(h)) <= 1e-9 * math.fsum(abs(v) for v in h):
        raise ValueError(f"{name} and k2 make the base sum to 0; the filter cannot be normalised")


def rectangle_filter(omega_n, zeta, ts, order=1, *, adjust_ts=False):
    """Rectangle window: M equal samples, M = 2 pi / (omega_d Ts) (paper 000, section 1)."""
    omega_n, zeta, omega_d = damped_mode(omega_n, zeta)
    m, ts = _rectangle_length(omega_d, ts, adjust_ts)
    return _shape([1.0] * m, omega_n, zeta, ts, order)


def hanning_filter(omega_n, zeta, ts, order=1, *, adjust_ts=False):
    """Hanning window h[k] = 0.5 - 0.5 cos(2 pi k / M), M = 4 pi / (omega_d Ts) (eq. 2)."""
    omega_n, zeta, omega_d = damped_mode(omega_n, zeta)
    h, ts = cosine_base("hanning", omega_d, ts, adjust_ts)
    return _shape(h, omega_n, zeta, ts, order)


def blackman_filter(omega_n, zeta, ts, order=1, *, adjust_ts=False):
    """Blackman window 0.42 - 0.5 cos(2 pi k/M) + 0.08 cos(4 pi k/M), M = 6 pi / (omega_d Ts) (section 4)."""
    omega_n, zeta, omega_d = damped_mode(omega_n, zeta)
    h, ts = cosine_base("blackman", omega_d, ts, adjust_ts)
    return _shape(h, omega_n, zeta, ts, order)


def hamming_filter(omega_n, zeta, ts, order=1, *, adjust_ts=False):
    """Hamming window 25/46 - 21/46 cos(2 pi k / M), approximate null, M = 4 pi / (omega_d Ts) (section 5)."""
    omega_n, zeta, omega_d = damped_mode(omega_n, zeta)
    h, ts = cosine_base("hamming", omega_d, ts, adjust_ts)
    return _shape(h, omega_n, zeta, ts, order)


def _three_hanning_u(m, c):
    """omega_d Ts for an integer M (section 7).

    The OCR prints ``omega_d Ts = [2 cos^2(pi/M)(C+1) + 2C cos(pi/M) - 1] / [2C cos(pi/M) + 2C + 1]``;
    the right side is cos(omega_d Ts) (it is what eq. (6) inverts, and it is the null of the base
    computed numerically). Written as 2 arcsin(...) because 1 - cos loses digits for large M:
    1 - cos(omega_d Ts) = 2 (C+1) sin^2(pi/M) / (2C cos(pi/M) + 2C + 1).
    """
    x = math.cos(math.pi / m)
    return 2.0 * math.asin(math.sin(math.pi / m) * math.sqrt((c + 1.0) / (2.0 * c * x + 2.0 * c + 1.0)))


def _three_hanning_m(u, c):
    """Eq. (6): M = pi / arccos[(C cos u - C + sqrt(B)) / (2C + 2)], u = omega_d Ts."""
    y = math.cos(u)
    b = c * c * y * y + 2 * c * c * y + c * c + 2 * c + 6 * c * y + 2 + 2 * y
    return math.pi / math.acos(min(1.0, (c * y - c + math.sqrt(b)) / (2 * c + 2)))


def three_hanning_filter(omega_n, zeta, ts, order=1, *, c=0.25, adjust_ts=False):
    """Sum of three Hanning windows with weight C (section 7, eq. 6) on 0 <= k <= 2M."""
    omega_n, zeta, omega_d = damped_mode(omega_n, zeta)
    c = check_finite(c, "c")
    if c < 0.0:
        raise ValueError(f"c must be >= 0, got {c!r}")
    m, ts = window_length(
        omega_d,
        ts,
        adjust_ts,
        lambda u: _three_hanning_m(u, c),
        lambda m: _three_hanning_u(m, c),
        2,
        "eq. (6) of paper 000",
    )
    h = [
        0.5 - 0.5 * math.cos(math.pi * k / m) + c * (0.5 - 0.5 * math.cos(2.0 * math.pi * k / m))
        for k in range(2 * m + 1)
    ]
    return _shape(h, omega_n, zeta, ts, order)


def differenced_filter(omega_n, zeta, ts, order=1, *, k1=1.0, k2=-25.0, base="hanning", adjust_ts=False):
    """h = k1 g + k2 dg, dg[k] = g[k] - g[k-1] on 0 <= k <= M + 1 (section 8.1)."""
    omega_n, zeta, omega_d = damped_mode(omega_n, zeta)
    k1, k2 = check_finite(k1, "k1"), check_finite(k2, "k2")
    g, ts = _base(base, omega_d, ts, adjust_ts)
    padded = g + [0.0]
    h = [k1 * v + k2 * (v - (padded[k - 1] if k else 0.0)) for k, v in enumerate(padded)]
    _check_gain(h, "k1")
    return _shape(h, omega_n, zeta, ts, order)


def convolved_filter(omega_n, zeta, ts, order=1, *, k1=1.0, k2=1.0 / 125.0, k0=None, base="hanning", adjust_ts=False):
    """h = k1 g[k - k0] + k2 (g * g)[k] (section 8.2); k0 defaults to M."""
    omega_n, zeta, omega_d = damped_mode(omega_n, zeta)
    k1, k2 = check_finite(k1, "k1"), check_finite(k2, "k2")
    g, ts = _base(base, omega_d, ts, adjust_ts)
    gg = convolve(g, g)
    m = len(g) - 1
    k0 = m if k0 is None else check_count(k0, "k0", 0)
    if k0 > len(gg) - len(g):
        raise ValueError(f"k0 must be an integer in [0, {len(gg) - len(g)}], got {k0!r}")
    h = [k2 * v for v in gg]
    for k, v in enumerate(g):
        h[k0 + k] += k1 * v
    _check_gain(h, "k1")
    return _shape(h, omega_n, zeta, ts, order)


#: Design functions by kind, the names the design layer and the ShapeFilter FMU's ``kind`` use.
WINDOW_FILTERS = {
    "rectangle": rectangle_filter,
    "hanning": hanning_filter,
    "blackman": blackman_filter,
    "hamming": hamming_filter,
    "three-hanning": three_hanning_filter,
    "differenced": differenced_filter,
    "convolved": convolved_filter,
}
