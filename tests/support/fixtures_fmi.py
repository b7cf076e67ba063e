"""Session-scoped fixtures for the pythonfmu FMUs (see conftest.py), each built once by ``builds``,
and the start values the tests share."""

import functools
import math

import pytest


def pythonfmu_fixture(model: str, start_values: dict):
    """A session fixture: the path of the pythonfmu FMU ``model`` built with ``start_values``."""
    @pytest.fixture(scope="session")
    def fixture(builds):
        return builds.pythonfmu(model, **start_values)

    return fixture


# --- Shaper FMU (fmi/kinds/shaper.py) -------------------------------------------------------------

# A ZV shaper for 10 Hz sampled at 1 ms: its impulses (0 and 50 ms) lie on the grid, so the FMU's
# sampled output equals the continuous-time shaping of a held command exactly.
SHAPER_STARTS = {"kind": "zv", "f[1]": 10.0, "zeta[1]": 0.0, "Ts": 1e-3, "u0": -1.0}
# Two modes designed together (paper 002, eq. 20); impulses fall between samples and are split.
MULTIMODE_STARTS = {"kind": "simultaneous", "n_modes": 2, "f[1]": 20.0, "zeta[1]": 0.02, "f[2]": 55.0,
                    "zeta[2]": 0.01, "Ts": 1e-3}


shaper_fmu = pythonfmu_fixture("Shaper", SHAPER_STARTS)  # a ZV Shaper


multimode_shaper_fmu = pythonfmu_fixture("Shaper", MULTIMODE_STARTS)  # a simultaneous two-mode Shaper


# --- ImpulseTrain FMU (fmi/kinds/impulse_train.py): three impulses off the 1 ms grid, split onto it --

TRAIN_STARTS = {"n_impulses": 3, "impulse_time[2]": 0.0123, "impulse_time[3]": 0.0251, "impulse_amplitude[1]": 0.3,
                "impulse_amplitude[2]": 0.45, "impulse_amplitude[3]": 0.25, "Ts": 1e-3}


impulse_train_fmu = pythonfmu_fixture("ImpulseTrain", TRAIN_STARTS)


@pytest.fixture(scope="session")
def all_fmus(tmp_path_factory):
    """Every registered FMU with default start values (shapefmu.fmi.build_all)."""
    from shapefmu.fmi import build_all

    return build_all(tmp_path_factory.mktemp("fmu_all"))


def command_signal(n):
    """A command with a step up, a step down and a slow sine: exercises every tap of a shaper."""
    return [math.sin(0.05 * k) + (1.0 if 20 <= k < 60 else 0.0) for k in range(n)]


# --- ProfileGenerator, EKFTuner, ReferencePlayer, STOSController FMUs (fmi/kinds/*) -------------

# Paper 003's ten-pendula move (M-BC:TZ:TP, 3.5 rad/s, 1.7 m at 0.7 m/s), its kernel at 1 ms.
PROFILE_STARTS = {"profile": "M-BC:TZ:TP", "omega_n": 3.5, "distance": 1.7, "speed": 0.7, "attenuation": 0.05,
                  "Ts": 1e-3}
# Paper 001's case: a 10 Hz ring-down watched at 1 kHz from a 60 rad/s guess, ZVD shaping.
EKF_STARTS = {"kind": "zvd", "Ts": 1e-3, "omega0": 60.0, "amplitude": 1.0}
# Paper 002's disk drive (Table I): b = 2.7e3, U = 11 V, simultaneous shaper for 2 and 3 kHz.
STOS_STARTS = {"b": 2.7e3, "U": 11.0, "kind": "simultaneous", "n_modes": 2, "f[1]": 2000.0, "zeta[1]": 0.01,
               "f[2]": 3000.0, "zeta[2]": 0.01, "Ts": 1e-5}


profile_fmu = pythonfmu_fixture("ProfileGenerator", PROFILE_STARTS)  # paper 003's ten-pendula move


ekf_fmu = pythonfmu_fixture("EKFTuner", EKF_STARTS)  # paper 001's EKF tuner


stos_fmu = pythonfmu_fixture("STOSController", STOS_STARTS)  # the disk drive's STOS controller

# --- ScheduledShaper FMU (fmi/kinds/scheduled_shaper.py) ------------------------------------------

# The bed of models/printer_bed.toml on its added mass: 0 g at 30 Hz, zeta 0.05; 300 g at 30 / sqrt(1.3)
# Hz, zeta 0.05 / sqrt(1.3); sampled at 2 kHz, re-designed at every change of the scheduling input.
SCHEDULED_STARTS = {"n_rows": 2, "values[1]": 0.0, "values[2]": 300.0, "f[1]": 30.0, "f[2]": 30.0 / math.sqrt(1.3),
                    "zeta[1]": 0.05, "zeta[2]": 0.05 / math.sqrt(1.3), "Ts": 5e-4, "resolution": 0.0}
scheduled_zv_fmu = pythonfmu_fixture("ScheduledShaper", SCHEDULED_STARTS | {"kind": "zv"})
# --- TrackedShaper FMU (fmi/kinds/tracked_shaper.py): the bed's guess 10 % off its 30 Hz, at 2 kHz -----
tracked_fmu = pythonfmu_fixture("TrackedShaper", {"f0": 33.0, "Ts": 5e-4})


@functools.cache
def time_optimal_solution():
    """The time-optimal move of a rigid body with paper 002's 2 kHz mode (five bangs), X = 1 mm."""
    from shapefmu.optimal import time_optimal
    from shapefmu.plants import rigid_flexible

    b2 = 2.7e3
    return time_optimal(rigid_flexible(b2, [(2 * math.pi * 2.0e3, 0.0, -b2)]), 1e-3, 11.0)


@pytest.fixture(name="time_optimal_solution", scope="session")
def time_optimal_solution_fixture():
    return time_optimal_solution()


@pytest.fixture(scope="session")
def reference_fmu(tmp_path_factory, time_optimal_solution):
    """Path of a ReferencePlayer FMU built by ``shapefmu build reference solution.json -o ...``."""
    from shapefmu.cli import main

    folder = tmp_path_factory.mktemp("fmu_reference")
    (folder / "solution.json").write_text(time_optimal_solution.to_json())
    out = folder / "TimeOptimal.fmu"
    assert main(["build", "reference", str(folder / "solution.json"), "-o", str(out)]) == 0
    return out


# --- ShapeFilter FMU (fmi/kinds/shape_filter.py) ------------------------------------------------

# The mode for which Ts = 1 ms makes every window length whole: f_d = f sqrt(1 - zeta^2) = 10 Hz, so
# M = 1 / (f_d Ts) = 100 (rectangle), 200 (Hanning, Hamming), 300 (Blackman); zeta exercises the
# damping compensation (paper 000, section 3).
SHAPE_FILTER_ZETA = 0.05
SHAPE_FILTER_F = 10.0 / math.sqrt(1.0 - SHAPE_FILTER_ZETA**2)
# Hanning of order 2: f[0] = 0, so y does not feed through from u.
SHAPE_FILTER_STARTS = {"kind": "hanning", "f": SHAPE_FILTER_F, "zeta": SHAPE_FILTER_ZETA, "order": 2, "Ts": 1e-3,
                       "u0": -1.0}
# Rectangle: f[0] = 1/M != 0, so y feeds through; built declaring it, the FMU accepts every kind.
FEEDTHROUGH_FILTER_STARTS = {"kind": "rectangle", "f": SHAPE_FILTER_F, "zeta": SHAPE_FILTER_ZETA, "Ts": 1e-3}


shape_filter_fmu = pythonfmu_fixture("ShapeFilter", SHAPE_FILTER_STARTS)  # a second-order damped Hanning filter


feedthrough_filter_fmu = pythonfmu_fixture("ShapeFilter", FEEDTHROUGH_FILTER_STARTS)  # y feeds through from u
