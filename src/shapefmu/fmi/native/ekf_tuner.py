"""The native C EKFTuner FMU: the pythonfmu EKFTuner's variables and numbers, no Python on the host.

``build_native_ekf_tuner(out_path, **start_values) -> Path`` writes an FMI 2.0 Co-Simulation FMU:
the generic FMI 2.0 layer, the EKF tuner's model part (``c/ekf_tuner_part.c``: runtime/ekf_tuner.py's
EKFTunedShaperKernel; ``c/resonance_ekf.c``: runtime/ekf.py's ResonanceEKF; operation for operation), the
absolute sample grid (``c/sample_clock.c``), the closed-form designs (``c/shaper_designs.c``) and
a generated ``model.c`` holding the variables and their start values. Nothing is designed at build
time: every parameter is used at the exit of initialisation in closed form, so each may be set
before it, as in the pythonfmu FMU. The start values are checked here by the kind's own
initialisation (``shapefmu.fmi.kinds.ekf_tuner``, as the pythonfmu FMU's); the C also refuses a
zv_dn order above 62 (64 impulses).
"""

from __future__ import annotations

from pathlib import Path

from shapefmu.fmi.native.kernel_fmu import designed_twin, write_table_twin

NAME = "EKFTuner"
SOURCES = ("ekf_tuner_part.c", "resonance_ekf.c", "sample_clock.c", "shaper_designs.c", "twin_variables.c")
HEADERS = ("ekf_tuner_model.h", "resonance_ekf.h", "sample_clock.h", "shaper_designs.h", "twin_variables.h")
MEANINGS = {"kind": "EKF_KIND", "n": "EKF_ORDER", "Ts": "EKF_PERIOD", "omega0": "EKF_OMEGA0",
            "amplitude": "EKF_AMPLITUDE", "retune_fraction": "EKF_RETUNE", "u": "EKF_COMMAND",
            "vibration": "EKF_VIBRATION", "y": "EKF_OUTPUT", "omega_est": "EKF_OMEGA_EST", "zeta_est": "EKF_ZETA_EST",
            "converged": "EKF_CONVERGED"}
MAX_ORDER = 62
NATIVE_NOTE = ("This FMU is the native C twin of the pythonfmu EKFTuner: the same variables, sampled semantics and "
               "numbers, no Python needed; sources/ holds its C code. Unlike the pythonfmu FMU it refuses a zv_dn "
               "order n above 62.")


def build_native_ekf_tuner(out_path, *, fmi_version: str = "2.0", clock: bool = False, **start_values) -> Path:
    """Build the native EKFTuner FMU with ``start_values`` (parameters of the pythonfmu EKFTuner)."""
    model, variables, values = designed_twin(NAME, start_values)
    if values["n"] > MAX_ORDER:
        raise ValueError(f"n must be an integer in [0, {MAX_ORDER}] for the native EKFTuner, got {values['n']}")
    return write_table_twin(NAME, out_path, (model, variables, values), "ekf_tuner_model.h", "ekf_tuner_model", MEANINGS,
                            SOURCES, HEADERS, NATIVE_NOTE, fmi_version=fmi_version, clock=clock)
