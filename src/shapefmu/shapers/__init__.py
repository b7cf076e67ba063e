"""Shaper designs: impulse shapers, window shape filters, twin-pulse and time-frequency profiles.

Single-mode designs share one signature, ``design(omega, zeta, ...)`` with omega in rad/s;
multi-mode designs take a sequence of ``(omega, zeta)`` modes. Every signature says its unit: a
frequency's name carries it (``omega``: rad/s, ``f``: Hz) and its annotation too (``RadPerSecond``,
``Hz`` of ``shapefmu.runtime.units``, where the convention is written). Design layer: imports ``runtime``
(whose formulas the FMUs re-run) and numpy / scipy, nothing above.
"""

from shapefmu.shapers.catalog import KINDS, check_sampling, design
from shapefmu.shapers.ei import ei, ei2, ei3
from shapefmu.shapers.impulse import ImpulseShaper, mzv, um_zv, zv, zv_dn, zvd, zvdd
from shapefmu.shapers.multimode import check_modes, convolve_modes, simultaneous
from shapefmu.shapers.profile import MotionProfile, velocity_profile
from shapefmu.shapers.sampled import SampledShaper
from shapefmu.shapers.scheduled import Schedule, ScheduledShaper
from shapefmu.shapers.time_frequency import (
    TimeFrequencyProfile,
    energy_leakage,
    optimal_scale,
    time_frequency_profile,
    tradeoff_curve,
)
from shapefmu.shapers.twin_pulse import (
    TWIN_PULSE_PROFILES,
    TwinPulseProfile,
    bc_tz,
    bc_vr,
    m_bc_tp,
    m_bc_tz,
    m_bc_tz_tp,
    m_tp_bc,
    m_tp_tz_bc,
    m_tz_bc,
    tp,
    tp_bc,
)
from shapefmu.shapers.window import (
    WINDOW_FILTERS,
    blackman_filter,
    convolved_filter,
    differenced_filter,
    get_window,
    hamming_filter,
    hamming_null_depth,
    hanning_filter,
    rectangle_filter,
    three_hanning_filter,
)

__all__ = [
    "KINDS",
    "TWIN_PULSE_PROFILES",
    "WINDOW_FILTERS",
    "ImpulseShaper",
    "MotionProfile",
    "SampledShaper",
    "Schedule",
    "ScheduledShaper",
    "TimeFrequencyProfile",
    "TwinPulseProfile",
    "bc_tz",
    "bc_vr",
    "blackman_filter",
    "check_modes",
    "check_sampling",
    "convolve_modes",
    "convolved_filter",
    "design",
    "differenced_filter",
    "ei",
    "ei2",
    "ei3",
    "energy_leakage",
    "get_window",
    "hamming_filter",
    "hamming_null_depth",
    "hanning_filter",
    "m_bc_tp",
    "m_bc_tz",
    "m_bc_tz_tp",
    "m_tp_bc",
    "m_tp_tz_bc",
    "m_tz_bc",
    "mzv",
    "optimal_scale",
    "rectangle_filter",
    "simultaneous",
    "three_hanning_filter",
    "time_frequency_profile",
    "tp",
    "tp_bc",
    "tradeoff_curve",
    "um_zv",
    "velocity_profile",
    "zv",
    "zv_dn",
    "zvd",
    "zvdd",
]
