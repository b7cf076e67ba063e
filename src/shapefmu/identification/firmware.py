"""What each printer firmware can run, as impulses to judge and the line that sets it (issue 32, item 3).

Names are spelled as each firmware spells them. Each shaper here is the impulse train the firmware
itself builds from the line, so the judge scores what the printer will do.

Klipper (``[input_shaper]``, docs/Config_Reference.md at commit 84104bbb): ``shaper_type_<axis>`` one of
zv, mzv, zvd, ei, 2hump_ei, 3hump_ei, ``shaper_freq_<axis>`` in Hz, ``damping_ratio_<axis>`` (default
0.1); the shapers are ``klipper.SHAPERS``.

RepRapFirmware (``M593``, Duet3D GCode dictionary, "M593: Configure Input Shaping"; the trains as
src/Movement/AxisShaper.cpp builds them, RepRapFirmware commit 4f218659):
``M593 P"<type>" F<Hz> S<damping>`` with type zvd, zvdd, zvddd, mzv, ei2, ei3, or
``M593 P"custom" H<h1>:...:<h(n-1)> T<d1>:...:<d(n-1)>`` for a train of n <= 5 impulses (4 besides the
last: ``MaxExtraImpulses``). H lists the cumulative amplitudes after each impulse but the last (that
reaches 1, so H rises in (0, 1)), T the time from each impulse to the next, in seconds: the dictionary
calls them "amplitudes of each impulse except the last" and "durations", and AxisShaper.cpp adds the
T into the impulse times and reports its own zvd as H = 1/(1+K)^2 : (1+2K)/(1+K)^2. F is accepted in
[StepClockRate / 131070, 1000] Hz (the lower end 5.7 to 7.2 Hz by board), S in [0, 0.99]. RRF's built-in
trains, with K = exp(-zeta pi / df) and the damped period P = 1 / (f df): zvd, zvdd, zvddd the binomial
ZV-D^k amplitudes at P/2 steps; mzv the amplitudes 1 - 1/sqrt 2, (sqrt 2 - 1) K', (1 - 1/sqrt 2) K'^2
(K' = exp(-0.75 zeta pi / df)) taken in reverse order (AxisShaper.cpp starts the cumulative list with the
K'^2 one), at 3/8 P steps; ei2 and ei3 Singhose's multi-hump EI fits (the coefficients of
``klipper``'s 2hump_ei and 3hump_ei) with their times in damped periods P (Klipper's are in 1/f), the
last amplitude whatever the others leave of 1.

Marlin (MarlinDocumentation ``_gcode/M593.md`` and ``_gcode/M493.md`` at commit 9ceeb6e4): ``M593 X F<Hz>
D<zeta>`` sets the planner's integrated ZV shaper; the fixed-time motion planner takes
``M493 S1 X C<mode> A<Hz> I<zeta> Q<vtol>`` with modes 1 ZV, 2 ZVD, 3 ZVDD, 4 ZVDDD, 5 EI, 6 2HEI,
7 3HEI, 8 MZV, zeta in [0.01, 1] and vtol in [0, 1]. Its trains (Marlin src/module/ft_motion.cpp,
``set_axis_shaping_A`` / ``_N``): impulses every half damped period, rounded to the trajectory's
1 ms grid (``FTM_FS`` = 1000 Hz), MZV every 3/8; ZV-D^k the binomial amplitudes in K; EI, 2HEI and 3HEI
Singhose's undamped closed forms in vtol with impulse i scaled by K^i, then normalised.
"""

from __future__ import annotations

import math

import numpy as np

from shapefmu.identification import klipper

FIRMWARES = ("klipper", "rrf", "marlin", "fmu")
RRF_TYPES = ("zvd", "zvdd", "zvddd", "mzv", "ei2", "ei3")
RRF_MAX_IMPULSES = 5
RRF_FREQ = (750e3 / 131070, 1000.0)  # Hz: F's range (StepClockRate / (2 * 65535) on a Duet 3, 1000)
MARLIN_MODES = {"ZV": 1, "ZVD": 2, "ZVDD": 3, "ZVDDD": 4, "EI": 5, "2HEI": 6, "3HEI": 7, "MZV": 8}
MARLIN_FS = 1000.0  # Hz: FTM_FS, the fixed-time planner's trajectory rate
MARLIN_VTOL = 0.05  # Q's default (FTM_SHAPING_V_TOL)
DAMPING = 0.1  # the damping every firmware designs for by default


def _damped(freq, zeta):
    df = math.sqrt(1 - zeta * zeta)
    return math.exp(-zeta * math.pi / df), 1 / (freq * df)


def _binomial(k, order):
    return [math.comb(order, i) * k**i for i in range(order + 1)]


def rrf_train(kind: str, freq: float, damping: float = DAMPING) -> tuple[np.ndarray, np.ndarray]:
    """(times s, amplitudes) of RepRapFirmware's built-in shaper ``kind`` (module docstring).

    >>> times, amplitudes = rrf_train("zvd", 50.0, 0.0)
    >>> [round(float(t), 6) for t in times], [float(a) for a in amplitudes]
    ([0.0, 0.01, 0.02], [0.25, 0.5, 0.25])
    """
    k, period = _damped(freq, damping)
    if kind in ("zvd", "zvdd", "zvddd"):
        order = ("zvd", "zvdd", "zvddd").index(kind) + 2
        amplitudes, steps = _binomial(k, order), [0.5] * order
    elif kind == "mzv":
        k_mzv = math.exp(-0.75 * damping * math.pi / math.sqrt(1 - damping * damping))
        side = 1 - 1 / math.sqrt(2)
        amplitudes, steps = [side * k_mzv**2, (math.sqrt(2) - 1) * k_mzv, side], [0.375, 0.375]
    elif kind in ("ei2", "ei3"):
        times, fitted = (np.asarray(c) for c in (klipper._TWO_HUMP if kind == "ei2" else klipper._THREE_HUMP))
        powers = damping ** np.arange(4)
        amplitudes = list(fitted @ powers)
        amplitudes[-1] = 1 - sum(amplitudes[:-1])
        steps = list(np.diff(times @ powers))
    else:
        raise ValueError(f"RepRapFirmware's shaper type must be one of {', '.join(RRF_TYPES)}, got {kind!r}")
    times = np.concatenate([[0.0], np.cumsum(steps) * period])
    amplitudes = np.asarray(amplitudes, dtype=float)
    return times, amplitudes / amplitudes.sum()


def rrf_custom(times, amplitudes) -> tuple[str, np.ndarray, np.ndarray]:
    """The ``M593 P"custom"`` line of a train of at most 5 impulses, and the train that line sets (H to
    6 decimals, T to the microsecond: what RRF will run, so what is judged).

    >>> rrf_custom([0.0, 0.01, 0.02], [0.25, 0.5, 0.25])[0]
    'M593 P"custom" H0.250000:0.750000 T0.010000:0.010000'
    """
    times, amplitudes = np.asarray(times, dtype=float), np.asarray(amplitudes, dtype=float)
    if not 2 <= times.size <= RRF_MAX_IMPULSES:
        raise ValueError(f"RepRapFirmware's custom shaper holds 2 to {RRF_MAX_IMPULSES} impulses, got {times.size}")
    cumulative = np.round(np.cumsum(amplitudes / amplitudes.sum())[:-1], 6)
    steps = np.round(np.diff(times), 6)
    if np.any(np.diff(np.r_[0.0, cumulative, 1.0]) <= 0) or np.any(steps <= 0):
        raise ValueError("RepRapFirmware's custom shaper needs positive amplitudes and increasing times")
    line = (f'M593 P"custom" H{":".join(f"{h:.6f}" for h in cumulative)} '
            f'T{":".join(f"{d:.6f}" for d in steps)}')
    return line, np.r_[0.0, np.cumsum(steps)], np.diff(np.r_[0.0, cumulative, 1.0])


def rrf_line(kind: str, freq: float, damping: float = DAMPING) -> str:
    """``M593 P"<kind>" F<Hz> S<damping>``, checked against RRF's ranges."""
    if not RRF_FREQ[0] <= freq <= RRF_FREQ[1]:
        raise ValueError(f"RepRapFirmware takes F in [{RRF_FREQ[0]:.2f}, {RRF_FREQ[1]:g}] Hz, got {freq!r}")
    return f'M593 P"{kind}" F{freq:.2f} S{damping:g}'


def marlin_train(mode: str, freq: float, damping: float = DAMPING, vtol: float = MARLIN_VTOL):
    """(times s, amplitudes) of Marlin's fixed-time shaper ``mode`` (module docstring), its times on
    the 1 ms trajectory grid.

    >>> times, amplitudes = marlin_train("ZV", 50.0, 0.0)
    >>> [round(float(t), 6) for t in times], [float(a) for a in amplitudes]
    ([0.0, 0.01], [0.5, 0.5])
    """
    k, period = _damped(freq, damping)
    if mode in ("ZV", "ZVD", "ZVDD", "ZVDDD"):
        amplitudes = _binomial(k, ("ZV", "ZVD", "ZVDD", "ZVDDD").index(mode) + 1)
    elif mode == "EI":
        amplitudes = [0.25 * (1 + vtol), 0.5 * (1 - vtol) * k, 0.25 * (1 + vtol) * k * k]
    elif mode == "2HEI":
        x = (vtol * vtol * (math.sqrt(1 - vtol * vtol) + 1)) ** (1 / 3)
        first = (3 * x * x + 2 * x + 3 * vtol * vtol) / (16 * x)
        amplitudes = [first, (0.5 - first) * k, (0.5 - first) * k * k, first * k**3]
    elif mode == "3HEI":
        first = 0.0625 * (1 + 3 * vtol + 2 * math.sqrt(2 * (vtol + 1) * vtol))
        second = 0.25 * (1 - vtol)
        amplitudes = [first, second * k, (0.5 * (1 + vtol) - 2 * first) * k * k, second * k**3, first * k**4]
    elif mode == "MZV":
        amplitudes = [1.0, math.sqrt(2) * k, k * k]
    else:
        raise ValueError(f"Marlin's shaper mode must be one of {', '.join(MARLIN_MODES)}, got {mode!r}")
    step = round((0.375 if mode == "MZV" else 0.5) * period * MARLIN_FS) / MARLIN_FS
    amplitudes = np.asarray(amplitudes, dtype=float)
    return np.arange(amplitudes.size) * step, amplitudes / amplitudes.sum()


def marlin_line(mode: str, freq: float, axes, damping: float = DAMPING) -> str:
    """``M493`` (fixed-time motion) for ``mode`` on ``axes``; ``M593`` for the planner's own ZV."""
    flags = "".join(a.upper() for a in axes)
    if mode == "M593 ZV":
        return f"M593 {flags} F{freq:.2f} D{damping:g}"
    return f"M493 S1 {flags} C{MARLIN_MODES[mode]} A{freq:.2f} I{damping:g} Q{MARLIN_VTOL:g}"


def klipper_line(name: str, freq: float, axes) -> str:
    """Klipper's ``[input_shaper]`` lines (``klipper.config_lines``)."""
    return klipper.config_lines(name, freq, tuple(axes))
