"""The floor plan of DESIGN.md holds: no import circles, no module importing a layer above its own.

Every ``import`` of a shapefmu module counts, lazy ones inside functions too: a lazy import still
makes the two modules depend on each other.
"""

import ast
from pathlib import Path

import shapefmu
from shapefmu.cosim.graph import _strongly_connected

PACKAGE = Path(shapefmu.__file__).parent

# DESIGN.md's layers, lowest first; a module may import its own layer and the ones below.
LAYERS = {
    "runtime": 0,
    "shapers": 1, "analysis": 1, "estimation": 1, "stos": 1, "optimal": 1, "plants": 1, "plots": 1, "identification": 1,
    "motion": 1,
    "files": 1,
    "fmi": 2,
    "cosim": 3,
    "sweep": 4,
    "cli": 5, "__main__": 5,
}
LONGEST_MODULE = 600  # lines; DESIGN.md: past ~600 lines a room is usually two rooms
VENDORED = {"fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h",
            "fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h"}


def _module_name(path: Path) -> str:
    parts = ["shapefmu", *path.relative_to(PACKAGE).with_suffix("").parts]
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module_name(path): path for path in PACKAGE.rglob("*.py")}


def _resolve(name: str) -> str | None:
    """The shapefmu module an imported name lives in (``a.b.C`` -> ``a.b``), or None if foreign."""
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name or None


def _imports(module: str) -> set[str]:
    path = MODULES[module]
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join([*anchor, base] if base else anchor)
            names = [f"{base}.{alias.name}" for alias in node.names]
        else:
            continue
        found.update(target for name in names if (target := _resolve(name)) and target != module)
    return found


GRAPH = {module: _imports(module) for module in MODULES}


def _layer(module: str) -> int:
    parts = module.split(".")
    return LAYERS[parts[1]] if len(parts) > 1 else 0


def _cycles(graph):
    """Strongly connected components of more than one module: the master's own Tarjan (cosim.graph)."""
    return sorted(sorted(component) for component in _strongly_connected(sorted(graph), graph) if len(component) > 1)


def test_every_top_level_module_has_a_layer():
    assert {module.split(".")[1] for module in MODULES if "." in module} <= set(LAYERS)


def test_no_import_circle_between_modules():
    assert _cycles(GRAPH) == []


def test_no_module_imports_a_higher_layer():
    upward = sorted(
        f"{module} (layer {_layer(module)}) imports {target} (layer {_layer(target)})"
        for module, targets in GRAPH.items() for target in targets if _layer(target) > _layer(module)
    )
    assert upward == []


def test_the_checks_see_real_arrows():
    # Guards the two tests above against a resolver that finds nothing (they would pass vacuously).
    assert "shapefmu.runtime.checks" in GRAPH["shapefmu.fmi.python.slaves.shaper"]  # a relative import
    assert "shapefmu.cosim" in GRAPH["shapefmu.cli.simulate"]                      # a lazy import
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": set()}) == [["a", "b", "c"]]


def test_no_module_is_longer_than_a_room():
    long = sorted(
        f"{path.relative_to(PACKAGE)}: {n} lines"
        for path in PACKAGE.rglob("*")
        if path.suffix in {".py", ".c", ".h"} and path.name not in VENDORED
        and (n := len(path.read_text(encoding="utf-8").splitlines())) > LONGEST_MODULE
    )
    assert long == []
