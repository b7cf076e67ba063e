"""runtime/ is copied into every FMU: it may import only the standard library and itself."""

import ast
import sys
from pathlib import Path

import shapefmu.runtime

RUNTIME = Path(shapefmu.runtime.__file__).parent


def _imported_modules(path):
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            yield from (alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            yield "." if node.level else node.module


def test_runtime_imports_only_the_standard_library():
    foreign = {
        f"{path.name}: {name}"
        for path in RUNTIME.glob("*.py")
        for name in _imported_modules(path)
        if name != "." and name.split(".")[0] not in sys.stdlib_module_names
    }
    assert not foreign, f"runtime/ imports outside the standard library: {sorted(foreign)}"


def test_the_import_check_sees_every_runtime_module():
    # Guards the test above against an empty glob (a moved folder would make it pass vacuously).
    assert {"checks.py", "impulse_formulas.py", "shaper_filter.py"} <= {p.name for p in RUNTIME.glob("*.py")}
