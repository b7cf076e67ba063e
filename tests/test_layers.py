"""The floor plan of DESIGN.md holds: no import circles, no module importing a layer above its own.

Every ``import`` of a shapefmu module counts, lazy ones inside functions too: a lazy import still
makes the two modules depend on each other. The C of the native FMUs and of the pythonfmu front end
follows the same plan: a C module is a ``.c`` with its ``.h``; one depends on another by including
its header, no two depend on each other, and a function defined in another module is called through
a header the caller includes (the fmi3_layer.c / fmi3_layer_clock.c pair through fmi3_layer.h).
"""

import ast
import re
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
    "sweep": 4, "compare": 4,
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
    assert "shapefmu.runtime.checks" in GRAPH["shapefmu.fmi.kinds.shaper"]  # a relative import
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


def test_the_native_fmus_import_nothing_of_the_pythonfmu_fmus():
    # Each FMU kind is declared once (fmi.kinds), for both: the native twins read it, not the slaves.
    crossing = sorted(f"{module} imports {target}" for module, targets in GRAPH.items()
                      if module.startswith("shapefmu.fmi.native") for target in targets
                      if target.startswith("shapefmu.fmi.python"))
    assert crossing == []


C_FOLDERS = (PACKAGE / "fmi" / "native" / "c", PACKAGE / "fmi" / "python" / "shim")
C_FILES = {path.name: path.read_text(encoding="utf-8") for folder in C_FOLDERS for path in folder.iterdir()
           if path.suffix in (".c", ".h") and path.name not in VENDORED}
_INCLUDE = re.compile(r'^#include "([\w.]+)"', re.M)
_DEFINITION = re.compile(r"^(?!static)[A-Za-z][\w \*]*?\b(\w+)\((?:[^;{]|\n)*?\)\s*\{", re.M)
_DECLARATION = re.compile(r"^[A-Za-z][\w \*]*?\b(\w+)\((?:[^;{]|\n)*?\);", re.M)
_COMMENT = re.compile(r"/\*.*?\*/|//[^\n]*", re.S)


def _code(name: str) -> str:
    return _COMMENT.sub(" ", C_FILES[name])


def _includes(name: str, seen=None) -> set[str]:
    """The headers ``name`` includes, transitively (the vendored FMI headers left out)."""
    seen = set() if seen is None else seen
    for header in _INCLUDE.findall(_code(name)):
        if header in C_FILES and header not in seen:
            seen.add(header)
            _includes(header, seen)
    return seen


def _c_graph() -> dict[str, set[str]]:
    """C module (file stem) -> the modules whose headers it includes."""
    graph: dict[str, set[str]] = {}
    for name in C_FILES:
        stem = name.rsplit(".", 1)[0]
        targets = {h.rsplit(".", 1)[0] for h in _INCLUDE.findall(_code(name)) if h in C_FILES}
        graph.setdefault(stem, set()).update(targets - {stem})
    return graph


def test_no_two_c_modules_depend_on_each_other():
    assert _cycles(_c_graph()) == []


def test_a_c_module_calls_another_only_through_a_header_it_includes():
    # Per program (the native layer and parts; the pythonfmu front end); the standard's API
    # (fmi2..., fmi3...) is declared by its own headers.
    unseen = []
    for folder in C_FOLDERS:
        names = [path.name for path in folder.iterdir() if path.name in C_FILES]
        defined = {function: name for name in names if name.endswith(".c")
                   for function in _DEFINITION.findall(_code(name)) if not re.match(r"fmi[23][A-Z]", function)}
        declared = {name: set(_DECLARATION.findall(_code(name))) for name in names if name.endswith(".h")}
        for name in (n for n in names if n.endswith(".c")):
            visible = set().union(*(declared.get(h, set()) for h in _includes(name)))
            for function in set(re.findall(r"\b(\w+)\s*\(", _code(name))):
                home = defined.get(function)
                if home is not None and home != name and function not in visible:
                    unseen.append(f"{name} calls {function} of {home} without a header declaring it")
    assert unseen == []


def test_the_c_checks_see_real_dependencies():
    # Guards the two tests above against parsers that find nothing.
    assert "model" in _c_graph()["layer_core"] and "fmi3_layer" in _c_graph()["fmi3_layer_clock"]
    assert "model_fail" in _DEFINITION.findall(_code("layer_core.c"))
    assert "model_fail" in _DECLARATION.findall(_code("model.h"))
    assert "fmi3_clocked" in _DEFINITION.findall(_code("fmi3_layer_clock.c"))
    assert "fmi3_clocked" in _DECLARATION.findall(_code("fmi3_layer.h"))  # how fmi3_layer.c reaches it
