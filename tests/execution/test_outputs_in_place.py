"""A node with several outputs has its own arrays frozen where they lie, as a node with one
output has (no copy), and only those: an array the node still holds elsewhere, or returns
twice, is copied, so nothing the node keeps can change a value of the run."""

from __future__ import annotations

import sys

import numpy as np
import pytest

import graphvision as gv

PLUGIN = '''
from typing import NamedTuple
import numpy as np
from graphvision import GrayImage, Int, node

ADDRESSES = {}
KEPT = []

class Two(NamedTuple):
    first: GrayImage
    second: GrayImage
    count: Int

@node("own.two")
def two(*, keep: bool = False, twice: bool = False) -> Two:
    """Two new 200x200 images; ``keep``: the first is also kept in a list; ``twice``: the
    first is returned in both ports."""
    first = np.full((200, 200), 0.25, np.float32)
    second = first if twice else np.full((200, 200), 0.5, np.float32)
    ADDRESSES["first"] = first.__array_interface__["data"][0]
    ADDRESSES["second"] = second.__array_interface__["data"][0]
    if keep:
        KEPT.append(first)
    return Two(first, second, 2)
'''


@pytest.fixture(scope="module")
def plugin(tmp_path_factory):
    path = tmp_path_factory.mktemp("own") / "own_plugin.py"
    path.write_text(PLUGIN)
    registry = gv.discover([path], entry_points=False)
    func = registry.node("own.two").func
    return registry, sys.modules[func.__module__]


def outputs(registry: gv.Registry, executor: str, **params: bool) -> dict[str, np.ndarray]:
    graph = gv.Graph("own")
    node = graph.add("node", "own.two", params=dict(params))
    for port in ("first", "second", "count"):
        graph.output(port, node[port])
    return gv.run(graph, registry, executor=executor).outputs


def address(array: np.ndarray) -> int:
    return array.__array_interface__["data"][0]


@pytest.mark.parametrize("executor", ["sync", "threads"])
def test_the_arrays_of_a_tuple_are_frozen_where_the_node_made_them(plugin, executor):
    registry, module = plugin
    out = outputs(registry, executor)
    assert address(out["first"]) == module.ADDRESSES["first"]  # no copy
    assert address(out["second"]) == module.ADDRESSES["second"]
    assert np.all(out["first"] == 0.25) and np.all(out["second"] == 0.5) and out["count"] == 2
    for port in ("first", "second"):
        with pytest.raises(ValueError, match="WRITEABLE"):
            out[port].flags.writeable = True


def test_an_array_the_node_still_holds_is_copied(plugin):
    registry, module = plugin
    out = outputs(registry, "sync", keep=True)
    assert address(out["first"]) != module.ADDRESSES["first"]
    assert address(out["second"]) == module.ADDRESSES["second"]
    module.KEPT[-1][...] = 1.0  # the node's own array changes, the run's value does not
    assert np.all(out["first"] == 0.25) and not out["first"].flags.writeable


def test_an_array_returned_in_two_ports_is_copied(plugin):
    registry, module = plugin
    out = outputs(registry, "sync", twice=True)
    assert module.ADDRESSES["first"] not in (address(out["first"]), address(out["second"]))
    assert np.all(out["first"] == 0.25) and np.all(out["second"] == 0.25)
