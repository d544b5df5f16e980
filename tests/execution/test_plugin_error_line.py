"""An error raised inside one's own node (a local plugin) names the plugin's line it came
from, on every executor, as a plugin that fails to load does: a tryer's ``NameError`` named
the node but not where in ``my_nodes.py`` it was. An installed plugin's error is unchanged."""

from __future__ import annotations

import json

import pytest

import graphvision as gv
from graphvision.nodes.loading import note_plugin_line, plugin_line

PLUGIN = '''from graphvision import GrayImage, node


@node("own.broken")
def broken(*, scale: float = 1.0) -> GrayImage:
    """Calls a helper that names an undefined name."""
    return helper(scale)


def helper(scale):
    return undefined_name * scale
'''


@pytest.fixture(scope="module")
def plugin(tmp_path_factory):
    path = tmp_path_factory.mktemp("own") / "my_nodes.py"
    path.write_text(PLUGIN)
    return gv.discover([path]), path.resolve()


@pytest.mark.parametrize("executor", ["sync", "threads", "processes"])
def test_a_plugin_node_error_names_its_line_in_the_plugin(plugin, executor):
    registry, path = plugin
    graph = gv.Graph("own")
    graph.output("out", graph.add("b", "own.broken"))
    with pytest.raises(gv.RunError) as caught:
        gv.run(graph, registry, executor=executor, cache=None)
    failure = caught.value.failures["b"]
    assert str(failure).splitlines()[0] == (
        "node 'b' (op own.broken) failed: NameError: name 'undefined_name' is not defined "
        f"({path}:11)"
    )
    (node,) = (n for n in caught.value.record.nodes if n.name == "b")
    assert node.error.endswith(f"({path}:11)")


def test_an_installed_function_error_gets_no_line():
    try:
        json.loads("{")
    except ValueError as error:
        note_plugin_line(error, json.loads)
        assert plugin_line(error) == ""
