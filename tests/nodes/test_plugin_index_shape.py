"""A plugin index whose digest fits but whose entries do not (hand-edited, hostile, written
by another release) is no index: the commands discover the plugins and write it again."""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import pytest

from graphvision.cli import main
from graphvision.nodes import plugin_index
from graphvision.nodes.index_shape import INDEX, Each, ListOf, fits


def _rewrite(edit: Callable[[dict[str, Any]], None]) -> None:
    """Edit the index's JSON and write it with a header that fits the edited bytes."""
    key = plugin_index.environment_key(plugin_index.installed_entry_points())
    path = plugin_index.index_path(key)
    index = json.loads(path.read_bytes().partition(b"\n")[2])
    edit(index)
    body = json.dumps(index).encode()
    header = {"key": key, "blake2b": plugin_index._header(key, body)["blake2b"]}
    path.write_bytes(json.dumps(header).encode() + b"\n" + body)


def _gaussian(index: dict[str, Any]) -> dict[str, Any]:
    return index["nodes"]["filters.gaussian"]


DAMAGES: dict[str, Callable[[dict[str, Any]], None]] = {
    "node is a string": lambda i: i["nodes"].update({"filters.gaussian": "oops"}),
    "no summary": lambda i: _gaussian(i).pop("summary"),
    "summary a number": lambda i: _gaussian(i).update(summary=3),
    "no description": lambda i: _gaussian(i).pop("description"),
    "inputs a number": lambda i: _gaussian(i)["description"].update(inputs=3),
    "an input without its type": lambda i: _gaussian(i)["description"]["inputs"]["image"].pop(
        "type"
    ),
    "params a list": lambda i: _gaussian(i)["description"].update(params=[]),
    "a parameter's schema a string": lambda i: _gaussian(i)["description"]["params"].update(
        properties={"sigma": "1.0"}
    ),
    "no text": lambda i: _gaussian(i)["description"].pop("text"),
    "backends a list": lambda i: _gaussian(i)["description"].update(backends=["numpy"]),
    "conformance a string": lambda i: _gaussian(i)["description"].update(conformance="x"),
    "a plugin's implementations of numbers": lambda i: i["plugins"]["filters"].update(
        implementations=[1]
    ),
    "a plugin's node ids of lists": lambda i: i["plugins"]["filters"].update(nodes=[[]]),
}


def _cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    status = main(list(args))
    out, err = capsys.readouterr()
    return status, out, err


@pytest.mark.parametrize(
    "command", [("nodes",), ("nodes", "--json"), ("describe", "filters.gaussian")]
)
@pytest.mark.parametrize("damage", list(DAMAGES), ids=list(DAMAGES))
def test_a_malformed_index_is_rebuilt_not_a_traceback(capsys, command, damage):
    status, sound, _ = _cli(capsys, *command)  # discovers, writes the index
    assert status == 0 and "filters.gaussian" in sound
    _rewrite(DAMAGES[damage])
    status, out, err = _cli(capsys, *command)
    assert (status, err) == (0, "")
    assert out == sound
    status, again, _ = _cli(capsys, *command)  # from the index written again
    assert status == 0 and again == sound


def test_the_shape_accepts_what_a_discovery_writes_and_names_what_it_needs():
    main(["nodes"])  # writes the index
    key = plugin_index.environment_key(plugin_index.installed_entry_points())
    assert plugin_index.read_index(key) is not None
    index = json.loads(plugin_index.index_path(key).read_bytes().partition(b"\n")[2])
    assert fits(index, INDEX)
    assert fits({"a": [1, 2]}, {"a": ListOf(int), "b?": str})
    assert not fits({"a": [1, "2"]}, {"a": ListOf(int)})
    assert not fits({"b": "x"}, {"a": int})  # a required key missing
    assert not fits({"a": 1, "b": 2}, {"a": int, "b?": str})  # an optional key of another type
    assert fits({"x": {"n": 1}}, Each({"n": int})) and not fits([], Each(int))
