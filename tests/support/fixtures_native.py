"""Session-scoped fixtures for the native C Shaper and ShapeFilter FMUs (shapefmu.fmi.native.twins).

Every Shaper kind is built once: a closed-form kind for two modes (single-mode runs re-design it in
C through n_modes = 1), every other kind for one and for two modes, since its design is made only
at build time. The builds run two at a time (``builds``).
"""

import math

import pytest

H = 1e-3
# Modes off the sample grid of H, so that impulses are split: one mode, and two.
ONE_MODE = {"n_modes": 1, "f[1]": 13.0, "zeta[1]": 0.05}
TWO_MODES = {"n_modes": 2, "f[1]": 13.0, "zeta[1]": 0.05, "f[2]": 31.0, "zeta[2]": 0.02}
CLOSED_FORM = ("zv", "zvd", "zvdd", "zv_dn", "mzv")
BUILD_TIME_ONLY = ("um_zv", "ei", "ei2", "ei3", "simultaneous")
# n for zv_dn (ZV convolved four times), vtol for the EI family.
DESIGN_OPTIONS = {"n": 3, "vtol": 0.05}
# ShapeFilter kinds with the parameters the pythonfmu tests use (f_d = 10 Hz makes windows whole).
FILTER_ZETA = 0.05
FILTER_F = 10.0 / math.sqrt(1.0 - FILTER_ZETA**2)
FILTERS = {
    "hanning2": {"kind": "hanning", "f": FILTER_F, "zeta": FILTER_ZETA, "order": 2, "Ts": H, "u0": -1.0},
    "rectangle": {"kind": "rectangle", "f": FILTER_F, "zeta": FILTER_ZETA, "Ts": H},
    "blackman": {"kind": "blackman", "f": FILTER_F, "zeta": FILTER_ZETA, "Ts": H},
    "three-hanning": {"kind": "three-hanning", "f": FILTER_F, "zeta": FILTER_ZETA, "Ts": H, "c": 0.3, "adjust_Ts": True},
    "convolved": {"kind": "convolved", "f": FILTER_F, "zeta": FILTER_ZETA, "Ts": H, "base": "blackman",
                  "adjust_Ts": True},
    "TP:BC": {"kind": "TP:BC", "f": 7.0, "Ts": H, "null": 3},
    "M-BC:TZ:TP": {"kind": "M-BC:TZ:TP", "f": 7.0, "Ts": H, "delta_f": 0.5},
    "time-frequency": {"kind": "time-frequency", "f": 7.0, "Ts": H, "move_time": 0.2},
}


def shaper_starts(kind, modes):
    return {"kind": kind, **DESIGN_OPTIONS, **modes, "Ts": H, "u0": 0.0 if kind != "zvd" else -0.5}


@pytest.fixture(scope="session")
def native_shapers(builds):
    """{(kind, n_modes built for): (FMU path, start values)} of native Shaper FMUs."""
    jobs = {(kind, 2): shaper_starts(kind, TWO_MODES) for kind in CLOSED_FORM}
    for kind in BUILD_TIME_ONLY:
        jobs[(kind, 1)] = shaper_starts(kind, ONE_MODE)
        jobs[(kind, 2)] = shaper_starts(kind, TWO_MODES)
    paths = builds.many({key: ("native", ("Shaper",), starts) for key, starts in jobs.items()})
    return {key: (paths[key], jobs[key]) for key in jobs}


@pytest.fixture(scope="session")
def native_filters(builds):
    """{name: (FMU path, start values)} of native ShapeFilter FMUs (FILTERS)."""
    paths = builds.many({name: ("native", ("ShapeFilter",), starts) for name, starts in FILTERS.items()})
    return {name: (paths[name], FILTERS[name]) for name in FILTERS}
