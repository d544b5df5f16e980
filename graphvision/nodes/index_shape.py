"""The shape a plugin index must have to be served: every field its readers use, of the
type they use it as.

An index is a JSON file anyone can edit (or a disk can damage while its digest is written
again with it); its readers (``graphvision nodes`` and ``describe``, the choice of the
plugins a run imports, the backends a pipeline may name) index into it without checking.
An index that does not fit :data:`INDEX` is treated as no index: discovery imports the
plugins and writes it again (:func:`graphvision.nodes.plugin_index.read_index`).

A shape is a type (the value is an instance of it), a tuple of shapes (one of them fits),
:class:`Each` (a JSON object of any keys, each value of one shape), :class:`ListOf` (a list
of one shape), or a dict of key -> shape (a JSON object holding those keys; a key ending
in ``?`` may be absent; other keys are allowed).

>>> fits({"a": [1, 2]}, {"a": ListOf(int), "b?": str})
True
>>> fits({"a": ["1"]}, {"a": ListOf(int)})
False
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

__all__ = ["INDEX", "Each", "ListOf", "fits"]


@dataclass(frozen=True)
class Each:
    """A JSON object (string keys) whose every value fits ``shape``."""

    shape: Any


@dataclass(frozen=True)
class ListOf:
    """A JSON list whose every item fits ``shape``."""

    shape: Any


def fits(value: Any, shape: Any) -> bool:
    """Whether ``value`` (parsed JSON) has ``shape`` (see the module docstring)."""
    return _checker(shape)(value)


_Check = Callable[[Any], bool]


def _checker(shape: Any) -> _Check:
    """A function telling whether a value has ``shape``: the shape is read once, not at
    every value (the 400 nodes of the built-in plugins' index checked in 0.75 ms of CPU
    instead of 1.55, best of 30 interleaved; parsing its JSON takes 2.3)."""
    if isinstance(shape, type):
        return lambda value: isinstance(value, shape)
    if isinstance(shape, tuple):
        ones = [_checker(one) for one in shape]
        return lambda value: any(one(value) for one in ones)
    if isinstance(shape, Each):
        each = _checker(shape.shape)
        return lambda value: isinstance(value, dict) and all(map(each, value.values()))
    if isinstance(shape, ListOf):
        item = _checker(shape.shape)
        return lambda value: isinstance(value, list) and all(map(item, value))
    fields = [
        (key.removesuffix("?"), key.endswith("?"), _checker(one)) for key, one in shape.items()
    ]

    def check(value: Any) -> bool:
        if not isinstance(value, dict):
            return False
        for name, optional, inner in fields:
            if name in value:
                if not inner(value[name]):
                    return False
            elif not optional:
                return False
        return True

    return check


_NUMBER = (int, float)

_DESCRIPTION = {  # Registry.describe: what `describe` prints and `nodes --json` writes
    "id": str,
    "version": int,
    "plugin": str,
    "function": str,
    "inputs": Each({"type": str, "optional": bool}),
    "outputs": Each(str),
    "params": {"properties?": Each(dict)},
    "cache": bool,
    "conformance": (type(None), {"metric": str, "tolerance": _NUMBER, "note?": str}),
    "summary": str,
    "doc": str,
    "text": str,
    "backends": Each(bool),
    "unavailable?": Each(str),
}

_PLUGIN = {  # what each entry-point plugin provides (the choice of plugins a run imports)
    "nodes": ListOf(str),
    "port_types": ListOf(str),
    "sources": ListOf(str),
    "implementations?": ListOf(str),
    "exclusive?": dict,  # (read value by value: backends.exclusive_entries)
}

INDEX = {
    "nodes": Each({"summary": str, "description": _DESCRIPTION}),
    "plugins": Each(_PLUGIN),
    "modules?": Each(str),  # other modules of the plugins' distributions: name -> digest
}
