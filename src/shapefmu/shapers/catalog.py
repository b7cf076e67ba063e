"""Impulse-shaper designs by name: what the command line and the Shaper FMU parameters select."""

from __future__ import annotations

import math
from collections.abc import Sequence

from shapefmu.runtime.checks import aliased_modes, check_count, check_positive, check_vtol
from shapefmu.shapers.ei import ei, ei2, ei3
from shapefmu.shapers.impulse import ImpulseShaper, mzv, um_zv, zv, zv_dn, zvd, zvdd
from shapefmu.shapers.multimode import Mode, check_modes, convolve_modes, simultaneous

SINGLE_MODE = {"zv": zv, "zvd": zvd, "zvdd": zvdd, "mzv": mzv, "um_zv": um_zv, "ei": ei, "ei2": ei2, "ei3": ei3}
EI_FAMILY = ("ei", "ei2", "ei3")
KINDS = (*SINGLE_MODE, "zv_dn", "simultaneous")


def design(kind: str, modes: Sequence[Mode], vtol: float = 0.05, n: int = 1) -> ImpulseShaper:
    """Design shaper ``kind`` for ``modes`` [(omega rad/s, zeta), ...].

    A single-mode kind given several modes is applied per mode and the results convolved (the
    convolution method of paper 002); ``simultaneous`` solves eq. (20) for all modes at once.
    ``vtol`` is used by the EI family, ``n`` by ``zv_dn``.
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
