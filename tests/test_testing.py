"""The plugin conformance check, run on every built-in plugin and on broken ones."""

from __future__ import annotations

import types
from importlib.metadata import entry_points

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
    assert check_plugin(module).nodes


class Secret(gv.Array):
    """A port type that the plugin below does not export."""


def test_a_private_port_type_is_reported():
    @gv.node("odd.one")
    def one(x: Secret) -> gv.Float:
        """One."""
        return 1.0

    module = types.ModuleType("odd_plugin")
    module.one = one
    with pytest.raises(PluginCheckError, match="port 'x' has type Secret, which no plugin"):
        check_plugin(module)


def test_a_plugin_without_nodes_is_reported():
    with pytest.raises(PluginCheckError, match="defines no node"):
        check_plugin(types.ModuleType("empty_plugin"))
