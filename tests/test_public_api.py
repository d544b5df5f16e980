"""The public names are what __all__ says, and the doctests hold."""

from __future__ import annotations

import doctest
import importlib
import types

import pytest

import graphvision


def test_all_is_sorted_and_exported():
    assert graphvision.__all__ == sorted(graphvision.__all__)
    public = {
        n
        for n in dir(graphvision)
        if not n.startswith("_") and not isinstance(getattr(graphvision, n), types.ModuleType)
    }
    assert public == set(graphvision.__all__)


@pytest.mark.parametrize(
    "module",
    [
        "graphvision._scheduler",
        "graphvision_plugins.color._color",
        "graphvision_plugins.filters._linear",
        "graphvision_plugins.metrics._quality",
    ],
)
def test_doctests(module):
    result = doctest.testmod(importlib.import_module(module))
    assert result.attempted > 0 and result.failed == 0
