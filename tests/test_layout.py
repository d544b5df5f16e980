"""The engine stays small in its parts (issue 23): no module over 400 lines, no function over
60 (its docstring not counted), so that the long ones stay the steps they are."""

from __future__ import annotations

import ast
from pathlib import Path

ENGINE = Path(__file__).parents[1] / "graphvision"


def test_no_engine_module_is_over_400_lines():
    long = {
        str(path.relative_to(ENGINE)): lines
        for path in ENGINE.rglob("*.py")
        if (lines := len(path.read_text(encoding="utf-8").splitlines())) > 400
    }
    assert not long, long


def function_lengths(path: Path) -> dict[str, int]:
    lengths = {}
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            length = (node.end_lineno or node.lineno) - node.lineno + 1
            first = node.body[0]
            docstring = isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant)
            if docstring and isinstance(first.value.value, str):  # it does not count
                length -= (first.end_lineno or first.lineno) - first.lineno + 1
            lengths[f"{path.relative_to(ENGINE)}:{node.lineno} {node.name}"] = length
    return lengths


def test_no_engine_function_is_over_60_lines():
    lengths = {k: v for path in ENGINE.rglob("*.py") for k, v in function_lengths(path).items()}
    assert len(lengths) > 500  # the walk found the engine's functions
    long = {where: n for where, n in lengths.items() if n > 60}
    assert not long, long
