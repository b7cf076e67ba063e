"""Multi-mode impulse shapers: the convolution method and the simultaneous method (paper 002).

A mode is an ``(omega, zeta)`` pair: undamped natural frequency in rad/s and damping ratio.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence

from shapefmu.runtime import multimode
from shapefmu.runtime.multimode import check_modes
from shapefmu.runtime.shaper_designs import check_impulse_count
from shapefmu.runtime.units import RadPerSecond
from shapefmu.shapers.impulse import ImpulseShaper, zv

Mode = tuple[RadPerSecond, float]  # (omega, zeta)


def convolve_modes(
    modes: Sequence[Mode], base: Callable[[float, float], ImpulseShaper] = zv, name: str | None = None
) -> ImpulseShaper:
    """Convolution method (paper 002, section II-A): one ``base`` shaper per mode, convolved.

    With ``base=zv`` and M modes this gives 2^M impulses at sums of the half periods
    pi/omega_di, with products of the ZV amplitudes (eq. 3) as amplitudes; it is exactly zero at
    every mode because the product of spectra vanishes wherever one factor does.

    ``name`` names the base shaper in the error raised when the product of the per-mode impulse
    counts is past ``runtime.limits.MAX_IMPULSES`` (default: the function's name).

    Examples
    --------
    >>> import math
    >>> s = convolve_modes([(2 * math.pi, 0.0), (6 * math.pi, 0.0)])  # ZV at 1 Hz * ZV at 3 Hz
    >>> s.times, s.amplitudes
    ((0.0, 0.16666666666666666, 0.5, 0.6666666666666666), (0.25, 0.25, 0.25, 0.25))
    """
    checked = check_modes(modes)
    shapers = [base(w, z) for w, z in checked]
    check_impulse_count(name or getattr(base, "__name__", "the base shaper"), [len(s) for s in shapers])
    return functools.reduce(ImpulseShaper.convolve, shapers)


def simultaneous(modes: Sequence[Mode], starts_per_axis: int = 10) -> ImpulseShaper:
    """Simultaneous method (paper 002, eq. 20): M + 1 impulses for M modes, solved together.

    Unknowns: the M + 1 amplitudes and the times t_2..t_{M+1} (t_1 = 0); equations: for every
    mode j, sum_i a_i e^{-sigma_j (t_N - t_i)} cos(omega_dj t_i) = 0 and the same with sin, and
    sum_i a_i = 1: 2M + 1 of each. The system has many roots. This solves it from a grid of
    ``starts_per_axis`` times per impulse spread over (0, 1.5 T_conv], T_conv = sum pi/omega_dj the
    convolution shaper's length (a feasible length, so the shortest root lies below it), with the
    amplitudes of each start taken from the linear least-squares fit for those times, and returns
    the shortest root whose amplitudes are all positive and whose times are distinct. The solver is
    the runtime's (``shapefmu.runtime.multimode``, Levenberg-Marquardt with the analytic Jacobian),
    the one a Shaper FMU runs.

    For the disk drive of paper 002 (2.0 and 3.0 kHz, zeta = 0.01) this gives the paper's
    amplitudes 0.2848, 0.4471, 0.2681 at 0, 2.0030e-4, 4.0002e-4 s. The paper prints the times as
    2.0135e-4 and 4.0461e-4 s, which leave 1.1 % and 1.7 % residual vibration at its own modes: they
    are not a root of eq. (20); the root here is exact (residual ~1e-16) and 4.6 us shorter.

    Raises ValueError when no positive root exists (for instance two modes so close that M + 1
    impulses cannot separate them): use ``convolve_modes`` then.

    Examples
    --------
    >>> import math
    >>> s = simultaneous([(2 * math.pi * 2000, 0.01), (2 * math.pi * 3000, 0.01)])  # paper 002
    >>> [round(a, 4) for a in s.amplitudes], [f"{t:.4e}" for t in s.times]
    ([0.2848, 0.4471, 0.2681], ['0.0000e+00', '2.0030e-04', '4.0002e-04'])
    """
    checked = check_modes(modes)
    solution = multimode.shortest_positive_root(checked, starts_per_axis)
    if solution is None:
        raise multimode.no_positive_root(checked, "convolve_modes")
    times, amplitudes = solution
    return ImpulseShaper(tuple(times), tuple(amplitudes))
