"""Every public function and class of the design layer (shapers, analysis, estimation, stos,
optimal, plants) carries a runnable Examples section, as scipy.signal.windows does, and every
example gives what its docstring shows: the closed forms and the papers' numbers written there.
"""

import ast
import doctest
import importlib
import io
from pathlib import Path

import pytest

import shapefmu

PACKAGE = Path(shapefmu.__file__).parent
DESIGN_LAYER = ("shapers", "optimal", "plants", "analysis.py", "estimation.py", "stos.py")


def _modules() -> list[str]:
    paths = []
    for entry in DESIGN_LAYER:
        path = PACKAGE / entry
        paths += sorted(path.glob("*.py")) if path.is_dir() else [path]
    return [".".join(["shapefmu", *p.relative_to(PACKAGE).with_suffix("").parts]) for p in paths
            if p.name != "__init__.py"]


def _public(module: str) -> list[tuple[str, str]]:
    """(name, docstring) of every public top-level function and class of ``module``'s source."""
    path = PACKAGE.joinpath(*module.split(".")[1:]).with_suffix(".py")
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return [(node.name, ast.get_docstring(node) or "") for node in tree.body
            if isinstance(node, (ast.FunctionDef, ast.ClassDef)) and not node.name.startswith("_")]


def _examples():
    finder = doctest.DocTestFinder(exclude_empty=True)
    for name in _modules():
        yield from (test for test in finder.find(importlib.import_module(name)) if test.examples)


def test_every_public_function_and_class_shows_an_example():
    missing = [f"{module}.{name}" for module in _modules() for name, doc in _public(module) if ">>>" not in doc]
    assert missing == []


@pytest.mark.parametrize("example", sorted(_examples(), key=lambda test: test.name), ids=lambda test: test.name)
def test_the_example_gives_what_its_docstring_shows(example):
    out = io.StringIO()
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    result = runner.run(example, out=out.write)
    assert result.failed == 0, out.getvalue()
