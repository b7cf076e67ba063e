"""Vibration-suppression shape filters generated from window functions (Zhou & Misawa, paper 000).

A finite base sequence ``h[k]`` whose discrete-time Fourier transform vanishes at the damped
frequency, ``H(omega_d Ts) = 0``, becomes a shape filter for the mode (omega_n, zeta) by damping
compensation and normalisation (paper 000, Conclusion 2.1 and section 3):

    f[k] = h[k] e^{-zeta omega_n k Ts} / sum_m h[m] e^{-zeta omega_n m Ts},

and a filter of robustness order n is the n-fold self-convolution of ``f`` (eq. 1), whose spectrum
is ``F^n``. The residual vibration of the mode after ``f`` is proportional to
``|sum_k f[k] e^{(zeta omega_n + j omega_d) k Ts}| = |H(omega_d Ts)| / sum_m h[m] e^{-zeta omega_n m Ts}``,
which is why the null of the *base* window is all that matters, for any damping.

Every design function has the signature ``name(omega_n, zeta, ts, order=1, *, adjust_ts=False, ...)``
and returns a ``SampledShaper``. The window length M follows from ``omega_d * ts`` and must be an
integer: with ``adjust_ts=False`` a ``ts`` that does not make M an integer raises ValueError naming
the nearest valid sampling periods; with ``adjust_ts=True`` the nearest valid ``ts`` is used and
reported as the shaper's ``ts``. M is never rounded silently.
"""

from __future__ import annotations

import numpy as np

from shapefmu.runtime import window_filters
from shapefmu.runtime.checks import check_count
from shapefmu.runtime.units import RadPerSecond
from shapefmu.runtime.window_filters import cosine_base, damped_mode
from shapefmu.shapers.sampled import SampledShaper

# --- the shared step: the runtime's order-1 filter, raised to order n ----------------------------


def _sampled(design, order):
    """An order-1 filter ``(taps, ts)`` of ``shapefmu.runtime.window_filters``, to order n by eq. (1).

    The runtime (what a ShapeFilter FMU runs) validates the parameters, builds the base window,
    finds the integer M for ts, compensates the damping and normalises (section 3). The n-fold
    self-convolution of eq. (1) is O(n M^2): numpy's here, the same sums as the runtime's
    pure-Python convolution to rounding, at a hundredth of the time.
    """
    taps, ts = design
    order = check_count(order, "order", 1)
    window_filters.check_order_cost(len(taps), order)
    f = np.array(taps, dtype=float)
    out = f
    for _ in range(order - 1):
        out = np.convolve(out, f)
    return SampledShaper(out, ts)


# --- designs ---------------------------------------------------------------------------------


def rectangle_filter(omega_n: RadPerSecond, zeta, ts, order=1, *, adjust_ts=False) -> SampledShaper:
    """Rectangle-window shape filter: M equal samples, M = 2 pi / (omega_d Ts).

    Parameters
    ----------
    omega_n : float
        Natural frequency of the mode to suppress, rad/s.
    zeta : float
        Damping ratio in [0, 1).
    ts : float
        Sampling period, s. M must come out an integer (see ``adjust_ts``).
    order : int
        Robustness order n >= 1: the n-fold self-convolution of eq. (1).
    adjust_ts : bool
        Use the nearest ts that makes M an integer instead of raising ValueError.

    Returns
    -------
    SampledShaper
        Taps f_n[k] summing to 1, with the ts actually used.

    Notes
    -----
    h[k] = 1 for 0 <= k <= M - 1 (Zhou & Misawa 2005a, recalled in paper 000 section 1); its
    transform vanishes at omega = 2 pi / M. With ts = pi / omega_d (M = 2) the filter is the ZV
    shaper: Input Shaping is a special case of the rectangle filter.

    References
    ----------
    L. Zhou, E. A. Misawa, "Vibration suppression shape filter generation from window functions",
    IFAC 2005 (paper 000), sections 1-3.

    Examples
    --------
    >>> rectangle_filter(1.0, 0.0, np.pi / 100).taps.size
    200
    """
    return _sampled(window_filters.rectangle_filter(omega_n, zeta, ts, adjust_ts=adjust_ts), order)


def hanning_filter(omega_n: RadPerSecond, zeta, ts, order=1, *, adjust_ts=False) -> SampledShaper:
    """Hanning-window shape filter, M = 4 pi / (omega_d Ts) (paper 000, eq. 2, section 3).

    Parameters are those of :func:`rectangle_filter`.

    Notes
    -----
    h[k] = 0.5 - 0.5 cos(2 pi k / M), 0 <= k <= M (eq. 2). Its first and last samples are zero, so
    the filter is also a velocity profile (Fig. 4; :func:`shapefmu.shapers.profile.velocity_profile`).

    References
    ----------
    Paper 000, section 3, eq. (1)-(2).

    Examples
    --------
    >>> hanning_filter(1.0, 0.0, np.pi / 100).taps.size  # M + 1 with M = 400
    401
    """
    return _sampled(window_filters.hanning_filter(omega_n, zeta, ts, adjust_ts=adjust_ts), order)


def blackman_filter(omega_n: RadPerSecond, zeta, ts, order=1, *, adjust_ts=False) -> SampledShaper:
    """Blackman-window shape filter, M = 6 pi / (omega_d Ts) (paper 000, section 4).

    Parameters are those of :func:`rectangle_filter`.

    Notes
    -----
    h[k] = 0.42 - 0.5 cos(2 pi k / M) + 0.08 cos(4 pi k / M), 0 <= k <= M. (The OCR of section 4
    reads ``cos(2 pi n / M)`` in the second term; the index is k.) Zero at both ends, so it is also
    a velocity profile.

    References
    ----------
    Paper 000, section 4.

    Examples
    --------
    >>> blackman_filter(1.0, 0.0, np.pi / 100).taps.size  # M + 1 with M = 600
    601
    """
    return _sampled(window_filters.blackman_filter(omega_n, zeta, ts, adjust_ts=adjust_ts), order)


def hamming_filter(omega_n: RadPerSecond, zeta, ts, order=1, *, adjust_ts=False) -> SampledShaper:
    """Hamming-window shape filter with an approximate null, M = 4 pi / (omega_d Ts) (section 5).

    Parameters are those of :func:`rectangle_filter`. The residual vibration at the design point is
    not zero; :func:`hamming_null_depth` tells how small it is.

    Notes
    -----
    h[k] = 25/46 - 21/46 cos(2 pi k / M), 0 <= k <= M. The paper states H(omega) = 0 has no
    solution. The M samples k = 0..M-1 span whole periods and vanish at 4 pi / M; what remains is
    the end sample h[M] = 2/23, so |H(4 pi / M)| = 2/23 exactly against H(0) = (25 M + 4) / 46.

    References
    ----------
    Paper 000, section 5.

    Examples
    --------
    >>> hamming_filter(1.0, 0.0, np.pi / 100).taps.size  # M + 1 with M = 400
    401
    """
    return _sampled(window_filters.hamming_filter(omega_n, zeta, ts, adjust_ts=adjust_ts), order)


def hamming_null_depth(omega_n: RadPerSecond, zeta, ts, *, adjust_ts=False) -> float:
    """|H(omega_d Ts)| / H(0) of the Hamming base window: how far its approximate null is from 0.

    Equals 4 / (25 M + 4) (see :func:`hamming_filter`); for zeta = 0 this is also the percent
    residual vibration of the order-1 Hamming filter at the design point.

    Examples
    --------
    >>> round(hamming_null_depth(1.0, 0.0, np.pi / 100) * (25 * 400 + 4), 9)  # 4 / (25 M + 4), M = 400
    4.0
    """
    _, _, omega_d = damped_mode(omega_n, zeta)
    h, ts = cosine_base("hamming", omega_d, ts, adjust_ts)
    h = np.array(h)
    k = np.arange(h.size)
    return float(abs(np.sum(h * np.exp(-1j * omega_d * ts * k))) / h.sum())


def three_hanning_filter(omega_n: RadPerSecond, zeta, ts, order=1, *, c=0.25, adjust_ts=False) -> SampledShaper:
    """Shape filter from the sum of three Hanning windows with weight C (paper 000, section 7, eq. 6).

    Parameters are those of :func:`rectangle_filter`, plus

    c : float
        The weight C >= 0 of the two short Hanning windows (paper's Fig. 6 uses 0.25).

    Notes
    -----
    h = h_s1 + h_s2 + h_s3 on 0 <= k <= 2M: one Hanning of length 2M and C times two Hanning windows
    of length M placed end to end, i.e. h[k] = 1/2 - 1/2 cos(pi k / M) + C [1/2 - 1/2 cos(2 pi k / M)].
    Its null lies between DFT bins and M follows from eq. (6); see
    ``shapefmu.runtime.window_filters._three_hanning_u`` for the corrected forward relation.

    References
    ----------
    Paper 000, section 7, eq. (6).

    Examples
    --------
    >>> f = three_hanning_filter(2 * np.pi * 10.0, 0.0, 1e-3, adjust_ts=True)  # M whole: Ts moves
    >>> f.taps.size, round(f.ts, 9), round(f.gain, 12)
    (159, 0.001000721, 1.0)
    """
    design = window_filters.three_hanning_filter(omega_n, zeta, ts, c=c, adjust_ts=adjust_ts)
    return _sampled(design, order)


def differenced_filter(
    omega_n: RadPerSecond, zeta, ts, order=1, *, k1=1.0, k2=-25.0, base="hanning", adjust_ts=False
) -> SampledShaper:
    """Non-symmetric shape filter h = k1 g + k2 dg from a base and its difference (section 8.1).

    Parameters are those of :func:`rectangle_filter`, plus

    k1, k2 : float
        Weights of the base and of its first difference (paper: k1 = 1, k2 = -25).
    base : {'hanning', 'blackman', 'rectangle'}
        The symmetric base g with G(omega_d Ts) = 0.

    Notes
    -----
    dg[k] = g[k] - g[k-1] on 0 <= k <= M + 1, so H(omega) = [k1 + k2 (1 - e^{-j omega})] G(omega)
    keeps the null of G. The normalising sum runs over all M + 2 samples (the OCR's upper limit M
    would drop the last one).

    References
    ----------
    Paper 000, section 8.1, Figs. 8-9.

    Examples
    --------
    >>> f = differenced_filter(1.0, 0.0, np.pi / 100)  # M + 2 samples, M = 400
    >>> f.taps.size, round(f.gain, 12)
    (402, 1.0)
    """
    design = window_filters.differenced_filter(omega_n, zeta, ts, k1=k1, k2=k2, base=base, adjust_ts=adjust_ts)
    return _sampled(design, order)


def convolved_filter(
    omega_n: RadPerSecond, zeta, ts, order=1, *, k1=1.0, k2=1.0 / 125.0, k0=None, base="hanning", adjust_ts=False
) -> SampledShaper:
    """Non-symmetric shape filter h = k1 g[k - k0] + k2 (g * g)[k] (paper 000, section 8.2).

    Parameters are those of :func:`rectangle_filter`, plus

    k1, k2 : float
        Weights of the delayed base and of its self-convolution (paper: k1 = 1, k2 = 1/125).
    k0 : int, optional
        Delay of the base in samples, 0 <= k0 <= M (the default M is the paper's example).
    base : {'hanning', 'blackman', 'rectangle'}
        The symmetric base g with G(omega_d Ts) = 0.

    Notes
    -----
    H(omega) = k1 e^{-j omega k0} G(omega) + k2 G(omega)^2 vanishes with G. h spans 0..2M; the
    normalising sum runs over all of it (the OCR's upper limit M is a slip).

    References
    ----------
    Paper 000, section 8.2, Figs. 10-11.

    Examples
    --------
    >>> f = convolved_filter(1.0, 0.0, np.pi / 100)  # spans 0..2M, M = 400
    >>> f.taps.size, round(f.gain, 12)
    (801, 1.0)
    """
    design = window_filters.convolved_filter(
        omega_n, zeta, ts, k1=k1, k2=k2, k0=k0, base=base, adjust_ts=adjust_ts
    )
    return _sampled(design, order)


#: Design functions by kind: the kinds of the runtime's table (what the ShapeFilter FMU's ``kind``
#: selects), each with its namesake here. ``get_window`` is the way to them by name.
WINDOW_FILTERS = {kind: globals()[runtime.__name__] for kind, runtime in window_filters.WINDOW_FILTERS.items()}


def get_window(kind, omega_n: RadPerSecond, zeta, ts, order=1, **options) -> SampledShaper:
    """The window shape filter ``kind`` for the mode (``omega_n`` rad/s, ``zeta``) sampled at ``ts`` s,
    as scipy.signal.get_window returns a window by name.

    Parameters
    ----------
    kind : str
        One of ``WINDOW_FILTERS``: rectangle, hanning, blackman, hamming, three-hanning,
        differenced, convolved.
    omega_n, zeta, ts, order
        As :func:`rectangle_filter`: natural frequency (rad/s), damping ratio, sampling period (s),
        robustness order.
    **options
        The kind's own keywords: ``adjust_ts`` for every kind, ``c`` for three-hanning, ``k1``,
        ``k2``, ``base`` (and ``k0``) for differenced and convolved.

    Returns
    -------
    SampledShaper
        The filter's taps summing to 1 and the ts used.

    Examples
    --------
    >>> window = get_window("hanning", 2 * np.pi * 10.0, 0.0, 1e-3)  # a 10 Hz mode, 1 kHz
    >>> window.taps.size, round(float(window.taps.sum()), 12)
    (201, 1.0)
    >>> get_window("kaiser", 1.0, 0.0, 0.01)
    Traceback (most recent call last):
    ...
    ValueError: kind must be one of rectangle, hanning, blackman, hamming, three-hanning, differenced, convolved, got 'kaiser'
    """
    if kind not in WINDOW_FILTERS:
        raise ValueError(f"kind must be one of {', '.join(WINDOW_FILTERS)}, got {kind!r}")
    return WINDOW_FILTERS[kind](omega_n, zeta, ts, order, **options)
