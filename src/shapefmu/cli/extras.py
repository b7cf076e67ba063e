"""The optional parts of shapefmu (the extras of pyproject.toml) and the one line that names the
extra when a command needs a package that is not installed.

A user of one command installs little: ``pip install shapefmu`` is enough for ``design``,
``sensitivity``, ``profile``, ``plant list|show``, ``identify``, ``recommend`` and
``build`` of a single pythonfmu FMU; the extras add the rest. ``tests/test_wheel.py`` checks that
this table and pyproject.toml's extras agree.
"""

from __future__ import annotations

# The top-level module a command imports -> (the extra that installs it, what needs it).
EXTRAS = {
    "casadi": ("optimal", "time-optimal moves (optimal, stos, compare) and native plant FMUs (build, plant build)"),
    "mpmath": ("optimal", "the exact refinement of time-optimal moves (optimal, stos, compare)"),
    "fmpy": ("cosim", "running FMUs (simulate, compare, sweep)"),
    "pyarrow": ("parquet", "Parquet files (--out *.parquet, Parquet recordings)"),
    "dask": ("dask", "sweeps on a Dask cluster (sweep)"),
    "distributed": ("dask", "sweeps on a Dask cluster (sweep)"),
}


def explain(error: ImportError) -> str | None:
    """The one-line message for a missing package of an extra, None for any other import error."""
    name = (getattr(error, "name", None) or "").partition(".")[0]
    if name not in EXTRAS or not isinstance(error, ModuleNotFoundError):
        return None
    extra, purpose = EXTRAS[name]
    return (f"{name} is not installed; it is needed for {purpose}: pip install 'shapefmu[{extra}]' "
            f"(or 'shapefmu[all]' for every extra)")
