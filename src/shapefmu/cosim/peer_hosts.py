"""What the peer hosts the master is measured against need from this machine: oneTBB for ecospy.

ecospy's native library links ``libtbb.so.12`` (oneTBB). The ``tbb`` wheel (test and bench extras)
ships it in ``<prefix>/lib``, where the dynamic linker does not look; loading it globally before
ecospy is imported makes the linker resolve ecospy's dependency to that copy by its soname, so no
Debian package (libtbb12) is needed. The tests (tests/conftest.py) and the benchmarks
(benchmarks/cosim.py) both call :func:`preload_tbb`.
"""

from __future__ import annotations

import ctypes
from importlib import metadata
from pathlib import Path


def tbb_library() -> Path | None:
    """libtbb.so.12 of the ``tbb`` wheel, or None if the wheel is not installed."""
    try:
        files = metadata.files("tbb") or []
    except metadata.PackageNotFoundError:
        return None
    found = [Path(f.locate()).resolve() for f in files if f.name == "libtbb.so.12"]
    return found[0] if found and found[0].is_file() else None


def preload_tbb() -> None:
    """Load the wheel's libtbb.so.12 globally (before ecospy is imported); nothing without the wheel."""
    library = tbb_library()
    if library is not None:
        ctypes.CDLL(str(library), mode=ctypes.RTLD_GLOBAL)
