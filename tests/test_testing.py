"""The plugin conformance check, run on every built-in plugin and on broken ones."""

from __future__ import annotations

import types
from importlib.metadata import entry_points
from typing import Annotated

import numpy as np
import pytest

import graphvision as gv
from graphvision.testing import PluginCheckError, check_plugin

BUILT_IN = sorted(
    e.value
    for e in entry_points(group="graphvision.plugins")
    if e.value.startswith("graphvision_plugins.")
)


@pytest.mark.parametrize("module", BUILT_IN)
def test_built_in_plugins_conform(module):
    registry = check_plugin(module)
    status = registry.plugins[module]
    assert status.nodes or status.implementations  # a backend only implements others' ops


class ImagePort(gv.ArrayPort):
    """A port type whose name clashes with the built-in ``Image``."""


class SecretPort(gv.ArrayPort):
    """A port type that the plugin below uses without exporting it."""


def test_a_port_type_used_by_a_node_is_registered_with_it():
    @gv.node("odd.one")
    def one(x: Annotated[np.ndarray, SecretPort]) -> gv.Float:
        """One.

        Parameters
        ----------
        x : the secret value
        """
        return 1.0

    module = types.ModuleType("odd_plugin")
    module.one = one
    assert check_plugin(module).port_types["Secret"] is SecretPort


def test_a_port_type_name_clash_is_reported():
    @gv.node("odd.one")
    def one(x: Annotated[np.ndarray, ImagePort]) -> gv.Float:
        """One.

        Parameters
        ----------
        x : the secret value
        """
        return 1.0

    module = types.ModuleType("odd_plugin")
    module.one = one
    with pytest.raises(PluginCheckError, match="port 'x' has type Image, but another port type"):
        check_plugin(module)


def test_a_bare_port_class_annotation_is_reported():
    @gv.node("odd.bare")
    def bare(x: gv.FloatPort) -> gv.FloatPort:  # type: ignore[valid-type]
        """The form before graphvision.types: the registry reads it, type checkers cannot."""
        return x

    module = types.ModuleType("odd_plugin")
    module.bare = bare
    with pytest.raises(PluginCheckError, match="'x' is annotated with the port class FloatPort"):
        check_plugin(module)


def test_a_plugin_without_nodes_is_reported():
    with pytest.raises(PluginCheckError, match="defines no node"):
        check_plugin(types.ModuleType("empty_plugin"))
