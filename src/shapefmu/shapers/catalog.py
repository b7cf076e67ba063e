"""Impulse-shaper designs by name (what the command line and the Shaper FMU parameters select), and the
rules every command that designs for measured modes shares: the damping a shaper is designed for
(``design_zeta``) and the default sampling period of a sampled shaper (``default_sampling_period``)."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

from shapefmu.runtime import shaper_designs
from shapefmu.runtime.checks import aliased_modes, check_count, check_positive, check_vtol
from shapefmu.runtime.units import Hz
from shapefmu.shapers.ei import ei, ei2, ei3
from shapefmu.shapers.impulse import ImpulseShaper, mzv, um_zv, zv, zv_dn, zvd, zvdd
from shapefmu.shapers.multimode import Mode, check_modes, convolve_modes, simultaneous

SINGLE_MODE = {"zv": zv, "zvd": zvd, "zvdd": zvdd, "mzv": mzv, "um_zv": um_zv, "ei": ei, "ei2": ei2, "ei3": ei3}
EI_FAMILY = ("ei", "ei2", "ei3")
# The kinds are the runtime's (what a Shaper FMU designs), in its order: one list for both.
KINDS = shaper_designs.KINDS
# The largest damping ratio a shaper is designed for from a measured mode. A mode this damped loses
# all but exp(-2 pi zeta / sqrt(1 - zeta^2)) = 2.7 % of its amplitude per period, so a fit that says
# more is beyond what a shaper can use and what the fits can resolve; the design stays underdamped.
MAX_DESIGN_ZETA = 0.5
# Samples per period of the highest mode at the default sampling period of a sampled shaper: the
# split of an impulse between two samples then shifts its zeros by well under 1 % of the frequency.
SAMPLES_PER_PERIOD = 100


def design(kind: str, modes: Sequence[Mode], vtol: float = 0.05, n: int = 1) -> ImpulseShaper:
    """Design shaper ``kind`` for ``modes`` [(omega rad/s, zeta), ...].

    A single-mode kind given several modes is applied per mode and the results convolved (the
    convolution method of paper 002); ``simultaneous`` solves eq. (20) for all modes at once.
    ``vtol`` is used by the EI family, ``n`` by ``zv_dn``.

    Examples
    --------
    >>> import math
    >>> design("zvd", [(2 * math.pi, 0.0)]).amplitudes
    (0.25, 0.5, 0.25)
    >>> design("zv", [(2 * math.pi, 0.0), (6 * math.pi, 0.0)]).times  # ZV per mode, convolved
    (0.0, 0.16666666666666666, 0.5, 0.6666666666666666)
    """
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}; got {kind!r}")
    modes = check_modes(modes)
    if kind == "simultaneous":
        return simultaneous(modes)
    if kind == "zv_dn":
        n = check_count(n, "n", minimum=0)
        return convolve_modes(modes, base=lambda w, z: zv_dn(w, z, n), name=kind)
    if kind in EI_FAMILY:
        vtol = check_vtol(vtol)
        base = SINGLE_MODE[kind]
        return convolve_modes(modes, base=lambda w, z: base(w, z, vtol), name=kind)
    return convolve_modes(modes, base=SINGLE_MODE[kind], name=kind)


def check_sampling(modes: Sequence[Mode], ts: float, allow_aliasing: bool = False) -> float:
    """Refuse a sampling period ``ts`` (s) that cannot resolve one of ``modes``; returns ``ts``.

    A shaper sampled at ``ts`` (a Shaper FMU's ``Ts``) places its zeros on frequencies below the
    Nyquist frequency pi/ts only: a mode whose damped frequency is at or above it aliases, and the
    shaped command leaves it ringing (up to its whole vibration). ``allow_aliasing=True`` lets it
    through for a deliberate experiment; the FMU still warns through its logger.

    Examples
    --------
    >>> import math
    >>> check_sampling([(2 * math.pi * 10.0, 0.0)], 1e-3)
    0.001
    >>> check_sampling([(2 * math.pi * 600.0, 0.0)], 1e-3)
    Traceback (most recent call last):
    ...
    ValueError: mode 1 (600 Hz) is at or above the Nyquist frequency 500 Hz of ts = 0.001 s, so a shaper sampled at ts leaves it ringing; use ts < 0.000833333 s, or pass allow_aliasing=True (--allow-aliasing) to build it anyway
    """
    ts = check_positive(ts, "ts")
    if allow_aliasing:
        return ts
    checked = check_modes(modes)
    aliased = aliased_modes(checked, ts)
    if aliased:
        omega, zeta = checked[aliased[0]]
        raise ValueError(f"mode {aliased[0] + 1} ({omega / (2 * math.pi):g} Hz) is at or above the Nyquist frequency "
                         f"{0.5 / ts:g} Hz of ts = {ts!r} s, so a shaper sampled at ts leaves it ringing; use "
                         f"ts < {math.pi / (omega * math.sqrt(1 - zeta * zeta)):.6g} s, or pass allow_aliasing=True "
                         f"(--allow-aliasing) to build it anyway")
    return ts


def design_zeta(zeta: float) -> float:
    """The damping ratio a shaper is designed for from a measured ``zeta``: at most ``MAX_DESIGN_ZETA``.

    Examples
    --------
    >>> design_zeta(0.05), design_zeta(0.8)
    (0.05, 0.5)
    """
    return min(zeta, MAX_DESIGN_ZETA)


def default_sampling_period(frequencies_hz: Iterable[Hz]) -> float:
    """The sampling period (s) of a sampled shaper for modes at ``frequencies_hz`` (Hz) when none is
    given: ``SAMPLES_PER_PERIOD`` samples per period of the highest.

    Examples
    --------
    >>> default_sampling_period([40.0, 95.0]) == 1 / (100 * 95.0)
    True
    """
    return 1.0 / (SAMPLES_PER_PERIOD * max(check_positive(f, "frequency") for f in frequencies_hz))
