"""Extra-insensitive (EI) shapers with one, two and three humps, exact for damping in [0, 0.3].

(Within the measured domain: for larger vtol the multi-hump designs stop short of zeta = 0.3.)

The design is that of ``shapefmu.runtime.ei``, the standard-library module a Shaper FMU runs,
returned here as an ``ImpulseShaper``: one implementation, so what is analysed is exactly what the
FMU runs. Its module docstring carries the whole method: the definition (N + 1 zeros and N humps of
height exactly vtol around nu = 1), the 4N + 3 equations in the impulses and the hump and zero
frequencies, the pseudo-arclength continuation from the closed-form undamped design, why the first
crossing of the requested zeta along the branch is returned, where the branches end, and the
measured domain (``_DOMAIN``) that every refusal message names. Designs are cached there
(``functools.lru_cache``), so asking again for one is free.
"""

from __future__ import annotations

from shapefmu.runtime import ei as runtime_ei
from shapefmu.runtime.ei import NU_MAX, VTOL_MAX, VTOL_MIN, ZETA_MAX  # noqa: F401  (the limits, re-exported)
from shapefmu.runtime.units import RadPerSecond
from shapefmu.shapers.impulse import ImpulseShaper


def ei(omega: RadPerSecond, zeta: float = 0.0, vtol: float = 0.05) -> ImpulseShaper:
    """Extra-insensitive shaper: 3 impulses over one damped period, V(omega) = vtol.

    Undamped it is (1+V)/4, (1-V)/2, (1+V)/4 at 0, T/2, T; with damping the constraints in the
    module docstring of ``shapefmu.runtime.ei`` are solved exactly. I(5 %) = 0.399 at zeta = 0
    (ZVD: 0.287).

    Examples
    --------
    >>> import math
    >>> s = ei(2 * math.pi, 0.0, 0.05)  # 1 Hz: (1 + V)/4, (1 - V)/2, (1 + V)/4 at 0, 0.5, 1 s
    >>> s.times, [round(a, 12) for a in s.amplitudes]
    ((0.0, 0.5, 1.0), [0.2625, 0.475, 0.2625])
    """
    return _shaper(runtime_ei.ei(omega, zeta, vtol))


def ei2(omega: RadPerSecond, zeta: float = 0.0, vtol: float = 0.05) -> ImpulseShaper:
    """Two-hump EI: 4 impulses over 1.5 periods, zero at omega, humps of vtol either side.

    Examples
    --------
    >>> import math
    >>> s = ei2(2 * math.pi)
    >>> s.times, round(s.gain, 12)
    ((0.0, 0.5, 1.0, 1.5), 1.0)
    """
    return _shaper(runtime_ei.ei2(omega, zeta, vtol))


def ei3(omega: RadPerSecond, zeta: float = 0.0, vtol: float = 0.05) -> ImpulseShaper:
    """Three-hump EI: 5 impulses over 2 periods, humps of vtol at omega and either side.

    Examples
    --------
    >>> from math import pi
    >>> from shapefmu.analysis import residual_vibration
    >>> round(residual_vibration(ei3(2 * pi), 2 * pi, 0.0), 12)  # the middle hump, vtol at omega
    0.05
    """
    return _shaper(runtime_ei.ei3(omega, zeta, vtol))


def _shaper(design) -> ImpulseShaper:
    times, amplitudes = design
    return ImpulseShaper(tuple(times), tuple(amplitudes))
