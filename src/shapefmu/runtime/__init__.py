"""Per-sample kernels that every FMU executes.

Standard library ONLY: this package is copied into every FMU and must run in whatever Python the
host tool embeds. ``tests/test_runtime_imports.py`` enforces it. The design layer calls the same
functions, so what is analysed is exactly what an FMU runs.
"""
