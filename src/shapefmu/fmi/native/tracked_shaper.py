"""The native C TrackedShaper FMU: the pythonfmu TrackedShaper's variables and numbers, no Python on the host.

``build_native_tracked_shaper(out_path, **start_values) -> Path`` writes an FMI 2.0 or 3.0
Co-Simulation FMU: the generic FMI layer, the TrackedShaper's model part
(``c/tracked_shaper_part.c``: runtime/tracked_shaper.py's TrackedShaperKernel, operation for
operation), the shaper that follows its mode with no jump (``c/mode_following.c``:
runtime/scheduled_shaper.py's ModeFollowingShaper), the EKF of paper 001 (``c/resonance_ekf.c``),
the absolute sample grid (``c/sample_clock.c``), the closed-form designs (``c/shaper_designs.c``)
and a generated ``model.c`` holding the variables and their start values. Nothing is designed at
build time: every parameter is used at the exit of initialisation, so each may be set before it,
as in the pythonfmu FMU. The start values are checked here by the kind's own initialisation
(``shapefmu.fmi.kinds.tracked_shaper``). The C re-designs in closed form only, so this FMU refuses
the other kinds (ei, ei2, ei3, ...), a zv_dn order above 62 and a design with more than 10^6 taps
in flight (re-designs within one shaper length).
"""

from __future__ import annotations

from pathlib import Path

from shapefmu.fmi.native.kernel_fmu import closed_form_only, designed_twin, write_table_twin

NAME = "TrackedShaper"
SOURCES = ("tracked_shaper_part.c", "mode_following.c", "resonance_ekf.c", "sample_clock.c", "shaper_designs.c",
           "twin_variables.c")
HEADERS = ("tracked_shaper_model.h", "mode_following.h", "resonance_ekf.h", "sample_clock.h", "shaper_designs.h",
           "twin_variables.h")
MEANINGS = {"kind": "TRACK_KIND", "n": "TRACK_ORDER", "vtol": "TRACK_VTOL", "f0": "TRACK_F0", "zeta0": "TRACK_ZETA0",
            "noise": "TRACK_NOISE", "amplitude": "TRACK_AMPLITUDE", "drift": "TRACK_DRIFT", "gain": "TRACK_GAIN",
            "rest": "TRACK_REST", "band_low": "TRACK_BAND_LOW", "band_high": "TRACK_BAND_HIGH",
            "zeta_max": "TRACK_ZETA_MAX", "omega_tol": "TRACK_OMEGA_TOL", "sigma_tol": "TRACK_SIGMA_TOL",
            "resolution": "TRACK_RESOLUTION", "Ts": "TRACK_PERIOD", "u0": "TRACK_REST_COMMAND", "u": "TRACK_COMMAND",
            "measurement": "TRACK_MEASUREMENT", "y": "TRACK_OUTPUT", "f": "TRACK_FREQUENCY", "zeta": "TRACK_DAMPING"}
MAX_ORDER = 62  # c/mode_following.h's MF_MAX_ORDER: 64 impulses
NATIVE_NOTE = ("This FMU is the native C twin of the pythonfmu TrackedShaper: the same variables, sampled semantics "
               "and numbers, no Python needed; sources/ holds its C code. Unlike the pythonfmu FMU it designs the "
               "closed-form kinds only (zv, zvd, zvdd, zv_dn with n <= 62, mzv) and refuses a design with more than "
               "10^6 taps in flight.")


def build_native_tracked_shaper(out_path, *, fmi_version: str = "2.0", clock: bool = False, **start_values) -> Path:
    """Build the native TrackedShaper FMU with ``start_values`` (parameters of the pythonfmu TrackedShaper)."""
    model, variables, values = designed_twin(NAME, start_values)
    closed_form_only(NAME, values, MAX_ORDER)
    return write_table_twin(NAME, out_path, (model, variables, values), "tracked_shaper_model.h", "tracked_shaper_model",
                            MEANINGS, SOURCES, HEADERS, NATIVE_NOTE, fmi_version=fmi_version, clock=clock)
