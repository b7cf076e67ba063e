"""Impulse-shaper designs by name: what the command line and the Shaper FMU parameters select."""

from __future__ import annotations

from collections.abc import Sequence

from shapefmu.runtime.checks import check_count, check_vtol
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
        return convolve_modes(modes, base=lambda w, z: zv_dn(w, z, n))
    if kind in EI_FAMILY:
        vtol = check_vtol(vtol)
        base = SINGLE_MODE[kind]
        return convolve_modes(modes, base=lambda w, z: base(w, z, vtol))
    return convolve_modes(modes, base=SINGLE_MODE[kind])
