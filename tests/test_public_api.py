"""Public names: one sorted list, each importable, a cheap import; the doctests hold."""

from __future__ import annotations

import doctest
import importlib
import subprocess
import sys
import types

import pytest

import graphvision


def test_all_is_unique_and_exported():
    assert len(set(graphvision.__all__)) == len(graphvision.__all__)  # order: ruff's RUF022
    public = {
        n
        for n in dir(graphvision)
        if not n.startswith("_")
        and (
            not isinstance(getattr(graphvision, n), types.ModuleType)
            or callable(getattr(graphvision, n))
        )
    }  # a callable package is public: gv.studio (graphvision.studio takes the call)
    assert public == set(graphvision.__all__)


@pytest.mark.parametrize(
    "module",
    [
        "graphvision.execution.scheduler",
        "graphvision.graph.order",
        "graphvision.values.file_bytes",
        "graphvision_plugins.colour._intensity",
        "graphvision_plugins.filters._linear",
        "graphvision_plugins.metrics._quality",
    ],
)
def test_doctests(module):
    result = doctest.testmod(importlib.import_module(module))
    assert result.attempted > 0 and result.failed == 0


def test_every_public_name_resolves_and_the_lists_agree() -> None:
    names = graphvision._public_names()
    assert set(names) == set(graphvision.__all__)
    for name in graphvision.__all__:
        assert getattr(graphvision, name) is not None


def test_an_unknown_name_is_an_attribute_error() -> None:
    try:
        graphvision.no_such_thing  # noqa: B018 - the attribute access is the test
    except AttributeError as error:
        assert "no_such_thing" in str(error)
    else:  # pragma: no cover
        raise AssertionError("expected AttributeError")


def test_importing_the_package_imports_no_numpy_pydantic_or_yaml() -> None:
    code = (
        "import sys, graphvision; print(sorted({'numpy', 'pydantic', 'yaml'} & sys.modules.keys()))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_pyproject_lists_every_package_so_a_wheel_holds_them_all():
    import tomllib
    from pathlib import Path

    root = Path(__file__).parents[1]
    listed = tomllib.loads((root / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"]
    engine = {"graphvision"} | {
        f"graphvision.{p.parent.name}" for p in (root / "graphvision").glob("*/__init__.py")
    }
    families = {"graphvision_plugins"} | {
        f"graphvision_plugins.{p.parent.name}" for p in (root / "plugins").glob("*/__init__.py")
    }
    data = {  # folders of files shipped with the code (the studio's built page): listed too,
        # or setuptools warns that they are absent from `packages`
        ".".join(folder.relative_to(root).parts)
        for folder in (root / "graphvision").rglob("*")
        if folder.is_dir()
        and folder.name != "__pycache__"
        and not (folder / "__init__.py").exists()
        and any(child.is_file() for child in folder.iterdir())
    }
    assert set(listed) == engine | families | data
