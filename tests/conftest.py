"""Shared pytest plumbing.

FMU fixtures are session-scoped (each FMU is built once per test run) and live in one plugin module
per family, so the families do not share a file.
"""

from shapefmu.cosim.peer_hosts import preload_tbb

# ecospy needs oneTBB; the `tbb` wheel of the test extra provides it without a Debian package.
preload_tbb()

pytest_plugins = [
    "fixtures_fmi",     # pythonfmu FMUs: shapers, filters, profiles, EKF tuner, STOS, reference player
    "fixtures_plants",  # native C plant FMUs generated from models/
    "c_host",           # our C test host (hosts_c/fmi2_host.c), compiled once
    "fixtures_native",  # native C Shaper and ShapeFilter FMUs
]
