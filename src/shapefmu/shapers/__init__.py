"""Shaper designs: impulse shapers (closed form and numerically solved) and sampled shapers.

Single-mode designs share one signature, ``design(omega, zeta, ...)`` with omega in rad/s;
multi-mode designs take a sequence of ``(omega, zeta)`` modes.
"""

from shapefmu.shapers.catalog import KINDS, design
from shapefmu.shapers.ei import ei, ei2, ei3
from shapefmu.shapers.impulse import ImpulseShaper, mzv, um_zv, zv, zv_dn, zvd, zvdd
from shapefmu.shapers.multimode import check_modes, convolve_modes, simultaneous
from shapefmu.shapers.sampled import SampledShaper

__all__ = [
    "KINDS",
    "ImpulseShaper",
    "SampledShaper",
    "check_modes",
    "convolve_modes",
    "design",
    "ei",
    "ei2",
    "ei3",
    "mzv",
    "simultaneous",
    "um_zv",
    "zv",
    "zv_dn",
    "zvd",
    "zvdd",
]
