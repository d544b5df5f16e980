"""The engine and the plugins stay small in their parts (issue 23): no module over 400 lines,
no function over 60 (its docstring not counted), so that the long ones stay the steps they
are. The engine is graphvision/, the plugins are plugins/ (every family and shared/)."""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
ENGINE = ROOT / "graphvision"
PLUGINS = ROOT / "plugins"

# Found by the walk: a walk that misses a folder's files would pass for nothing.
LEAST_FUNCTIONS = {ENGINE: 500, PLUGINS: 1000}


def module_lengths(folder: Path) -> dict[str, int]:
    return {
        str(path.relative_to(ROOT)): len(path.read_text(encoding="utf-8").splitlines())
        for path in folder.rglob("*.py")
    }


def statements(node: ast.AST) -> Iterator[ast.AST]:
    """The statements in ``node``, at any depth (a def is a statement: expressions, where
    most of the nodes are, hold none, so they are not visited)."""
    for child in ast.iter_child_nodes(node):
        if isinstance(child, ast.stmt | ast.excepthandler | ast.match_case):
            yield child
            yield from statements(child)


def function_lengths(path: Path) -> dict[str, int]:
    lengths = {}
    for node in statements(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            length = (node.end_lineno or node.lineno) - node.lineno + 1
            first = node.body[0]
            docstring = isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant)
            if docstring and isinstance(first.value.value, str):  # it does not count
                length -= (first.end_lineno or first.lineno) - first.lineno + 1
            where = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path
            lengths[f"{where}:{node.lineno} {node.name}"] = length
    return lengths


@pytest.mark.parametrize("folder", [ENGINE, PLUGINS], ids=["graphvision", "plugins"])
def test_no_module_is_over_400_lines(folder):
    lengths = module_lengths(folder)
    assert len(lengths) > 100  # the walk found the folder's modules
    long = {name: n for name, n in lengths.items() if n > 400}
    assert not long, long


@pytest.mark.parametrize("folder", [ENGINE, PLUGINS], ids=["graphvision", "plugins"])
def test_no_function_is_over_60_lines(folder):
    lengths = {k: v for path in folder.rglob("*.py") for k, v in function_lengths(path).items()}
    assert len(lengths) > LEAST_FUNCTIONS[folder]  # the walk found the folder's functions
    long = {where: n for where, n in lengths.items() if n > 60}
    assert not long, long


def test_a_function_counts_its_body_and_signature_but_not_its_docstring(tmp_path):
    body = "".join(f"    x{i} = {i}\n" for i in range(59))
    source = tmp_path / "module.py"
    docstring = '    """One\n    two."""\n'
    nested = "class C:\n    if True:\n        async def g():\n            pass\n"
    source.write_text(f"def f(\n    a,\n):\n{docstring}{body}\n\n{nested}")
    assert function_lengths(source) == {
        f"{source}:1 f": 3 + 59,  # the signature's 3 lines and the body's 59
        f"{source}:69 g": 2,  # found inside a class and an if
    }
