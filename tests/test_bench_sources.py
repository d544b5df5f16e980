"""The benchmarks reuse the tests' scenes: every test module a benchmark names must exist.

``make bench`` is not part of ``make test``, so a test module moved or renamed would
otherwise break a benchmark silently until someone ran it.
"""

from __future__ import annotations

import ast
import importlib.machinery
import importlib.util
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "bench"


def _imported_modules(path: Path) -> list[tuple[int, str]]:
    """(line, module) for every ``import tests...`` / ``from tests... import`` in a file."""
    found: list[tuple[int, str]] = []
    for statement in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(statement, ast.ImportFrom) and statement.module and statement.level == 0:
            if statement.module.split(".")[0] == "tests":
                found.append((statement.lineno, statement.module))
                if _is_package(statement.module):
                    # the tests' packages are empty: a name imported from one is a module
                    found += [
                        (statement.lineno, f"{statement.module}.{alias.name}")
                        for alias in statement.names
                    ]
        elif isinstance(statement, ast.Import):
            found += [
                (statement.lineno, alias.name)
                for alias in statement.names
                if alias.name.split(".")[0] == "tests"
            ]
    return found


def _is_package(name: str) -> bool:
    spec = _spec(name)
    return spec is not None and spec.submodule_search_locations is not None


def _spec(name: str) -> importlib.machinery.ModuleSpec | None:
    try:
        return importlib.util.find_spec(name)
    except ModuleNotFoundError:
        return None


def _is_module(name: str) -> bool:
    try:
        return importlib.util.find_spec(name) is not None
    except ModuleNotFoundError:
        return False


@pytest.mark.parametrize("path", sorted(BENCH.glob("*.py")), ids=lambda p: p.name)
def test_every_test_module_a_benchmark_imports_exists(path: Path) -> None:
    missing = [
        f"{path.name}:{line}: {module}"
        for line, module in _imported_modules(path)
        if not _is_module(module)
    ]
    assert not missing, "benchmark imports a test module that does not exist: " + "; ".join(missing)
