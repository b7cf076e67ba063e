"""Shared pytest plumbing.

FMU fixtures are session-scoped (each FMU is built once per test run, by ``builds``) and live in one
plugin module per family in tests/support, so the families do not share a file.
"""

from shapefmu.cosim.peer_hosts import preload_tbb

# ecospy needs oneTBB; the `tbb` wheel of the test extra provides it without a Debian package.
preload_tbb()

pytest_plugins = [
    "support.builds",           # every FMU built once per session
    "support.fixtures_fmi",     # pythonfmu FMUs: shapers, filters, profiles, EKF tuner, STOS, reference player
    "support.fixtures_plants",  # native C plant FMUs generated from models/
    "support.c_hosts",          # our C test hosts (hosts_c/fmi2_host.c, fmi3_host.c), compiled once
    "support.cross_platform",   # the C hosts for linux64, win64 (Wine) and aarch64 (qemu), compiled once
    "support.fixtures_native",  # native C Shaper and ShapeFilter FMUs
]
