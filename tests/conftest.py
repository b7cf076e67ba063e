"""Shared pytest plumbing.

FMU fixtures are session-scoped (each FMU is built once per test run) and live in one plugin module
per family, so the families do not share a file.
"""

pytest_plugins = [
    "fixtures_fmi",     # pythonfmu FMUs: shapers, filters, profiles, EKF tuner, STOS, reference player
    "fixtures_plants",  # native C plant FMUs generated from models/
    "fixtures_native",  # native C Shaper and ShapeFilter FMUs
]
