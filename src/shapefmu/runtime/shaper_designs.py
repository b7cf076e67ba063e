"""Impulse shapers by name for one or several modes, as the FMUs that shape a command design them.

``design_impulses(kind, modes, n=1, vtol=0.05) -> (times, amplitudes)``: ``kind`` is a single-mode
shaper (closed form, ``runtime.impulse_formulas``, or the extra-insensitive family, ``runtime.ei``),
applied per mode and convolved (the convolution method of paper 002, section II-A: the product of
the spectra vanishes wherever one factor does), or ``"simultaneous"`` (paper 002, eq. 20,
``runtime.multimode``). ``modes`` is a sequence of (omega rad/s, zeta) pairs; ``n`` is the
derivative order of ``zv_dn``, ``vtol`` the tolerable vibration of ei, ei2 and ei3. This is what
``shapefmu.shapers.catalog.design`` does for these kinds, without numpy.
"""

import math

from . import ei, impulse_formulas, multimode
from .checks import check_count, check_omega, check_positive, check_size, check_zeta

# Every single-mode design as (omega, zeta, n, vtol) -> (times, amplitudes).
SINGLE_MODE = {
    "zv": lambda w, z, n, vtol: impulse_formulas.zv_dn(w, z, 0),
    "zvd": lambda w, z, n, vtol: impulse_formulas.zv_dn(w, z, 1),
    "zvdd": lambda w, z, n, vtol: impulse_formulas.zv_dn(w, z, 2),
    "zv_dn": lambda w, z, n, vtol: impulse_formulas.zv_dn(w, z, n),
    "mzv": lambda w, z, n, vtol: impulse_formulas.mzv(w, z),
    "um_zv": lambda w, z, n, vtol: impulse_formulas.um_zv(w, z),
    "ei": lambda w, z, n, vtol: ei.ei(w, z, vtol),
    "ei2": lambda w, z, n, vtol: ei.ei2(w, z, vtol),
    "ei3": lambda w, z, n, vtol: ei.ei3(w, z, vtol),
}
KINDS = (*SINGLE_MODE, "simultaneous")
# The closed-form kinds, with their impulses per mode for the derivative order n: the kinds a native
# FMU re-designs in C (c/shaper_designs.c lists the same names, tests/test_closed_form_kinds.py checks
# it) and the EKF tuner re-designs at every re-tune.
CLOSED_FORM = {"zv": lambda n: 2, "zvd": lambda n: 3, "zvdd": lambda n: 4, "zv_dn": lambda n: n + 2, "mzv": lambda n: 3}

# Convolution makes coincident times (t_a + t_b == t_b + t_a); closer than this fraction of the
# shaper's length they are one impulse (as ImpulseShaper.from_impulses).
_MERGE = 1e-12


def design_impulses(kind, modes, n=1, vtol=0.05):
    """Sorted impulse times (s) and amplitudes of shaper ``kind`` for ``modes``."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    modes = multimode.check_modes(modes)
    if kind == "simultaneous":
        return multimode.simultaneous(modes)
    per_mode = [SINGLE_MODE[kind](omega, zeta, n, vtol) for omega, zeta in modes]
    check_impulse_count(kind, [len(times) for times, _ in per_mode])
    impulses = [(0.0, 1.0)]
    for times, amplitudes in per_mode:
        impulses = [(t + s, a * b) for t, a in impulses for s, b in zip(times, amplitudes)]
    impulses.sort()
    tolerance = _MERGE * max(impulses[-1][0] - impulses[0][0], 1.0)
    merged = [list(impulses[0])]
    for t, a in impulses[1:]:
        if t - merged[-1][0] <= tolerance:
            merged[-1][1] += a
        else:
            merged.append([t, a])
    return [t for t, _ in merged], [a for _, a in merged]


def check_impulse_count(kind, counts):
    """Refuse a convolved shaper whose impulse count, the product of the per-mode ``counts``, is
    past ``limits.MAX_IMPULSES``, before the convolution builds it."""
    total = math.prod(counts)
    check_size(total, "MAX_IMPULSES", f"{kind} convolved over {len(counts)} modes "
               f"({' x '.join(map(str, counts))}) would have", "impulses",
               "use fewer modes, a shorter single-mode shaper or the simultaneous method")
    return total


def parameter_modes(values, max_modes, frequency="f", hertz=True):
    """The (omega rad/s, zeta) modes an FMU's parameters ``values`` (name -> value) describe.

    ``n_modes`` (1..``max_modes``) modes with frequencies ``<frequency>[i]`` in Hz (in rad/s if
    ``hertz`` is false) and damping ratios ``zeta[i]``, i = 1..n_modes.
    """
    count = check_count(values["n_modes"], "n_modes", minimum=1)
    if count > max_modes:
        raise ValueError(f"n_modes must be in [1, {max_modes}], got {count}")
    modes = []
    for i in range(1, count + 1):
        name = f"{frequency}[{i}]"
        if hertz:
            omega = check_omega(2.0 * math.pi * check_positive(values[name], name), f"2*pi*{name}")
        else:
            omega = check_omega(values[name], name)
        modes.append((omega, check_zeta(values[f"zeta[{i}]"], f"zeta[{i}]")))
    return modes
