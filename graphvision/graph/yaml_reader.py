"""Reading YAML once, bounded: one pass over the parser's events records each key's line
and refuses aliases that multiply, nesting past a depth, and files past a size, before
any value is built."""

from __future__ import annotations

from typing import Any

import yaml

from graphvision.errors import PipelineError, Problem
from graphvision.graph.schema import MAX_DEPTH, MIN_VALUE_BUDGET

__all__ = [
    "parse_value",
    "read_yaml",
]


_Loader: type = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml when installed
_MERGE = "tag:yaml.org,2002:merge"


class _RefusedError(Exception):
    """A file the reader will not read on: ``line`` and ``message`` say where and why."""

    def __init__(self, line: int, message: str) -> None:
        super().__init__(message)
        self.line, self.message = line, message


class _Open:
    """A mapping or sequence being read: its value, size so far, path, and pending key."""

    __slots__ = ("anchor", "key", "key_line", "merged", "path", "size", "value")

    def __init__(self, value: dict | list, path: list[str], anchor: str | None) -> None:
        self.value, self.path, self.anchor = value, path, anchor
        self.size = 1
        self.key: Any = _NO_KEY
        self.key_line = 0
        self.merged: dict[Any, Any] = {}


_NO_KEY = object()
_MERGE_KEY = object()


def read_yaml(text: str, file: str) -> tuple[Any, dict[str, int], list[Problem]]:
    """(data, line of every key by dotted path, duplicate-key problems) from one pass.

    The YAML events are turned into Python values as they stream, with a
    stack instead of recursion (nesting beyond :data:`MAX_DEPTH` is refused
    at its line). An anchored value is kept with its size (how many values it
    holds); an alias reuses the value, shared rather than copied, and adds its
    size to the count of values the file expands to, which may not exceed
    ``max(MIN_VALUE_BUDGET, 10 × values written)``: a billion laughs is
    refused at the alias that crosses the bound, a recursive alias at once.
    """
    try:
        return _stream(text, file)
    except _RefusedError as refused:
        raise PipelineError([Problem(refused.line, "yaml", refused.message, file)], file) from None
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        line = mark.line + 1 if mark else 0
        reason = getattr(error, "problem", None) or str(error)
        if "maximum nesting depth" in reason:  # libyaml >= 0.2.6 stops deep nesting itself
            nested = f"nested deeper than {MAX_DEPTH} levels"
            raise PipelineError([Problem(line, "yaml", nested, file)], file) from None
        raise PipelineError(
            [Problem(line, "yaml", f"malformed YAML: {reason}", file)], file
        ) from None


def _stream(text: str, file: str) -> tuple[Any, dict[str, int], list[Problem]]:
    reader = _Reader(file)
    loader = _Loader(text)
    try:
        while not loader.check_event(yaml.StreamEndEvent):
            reader.take(loader, loader.get_event())
    finally:
        loader.dispose()
    return reader.root, reader.lines, reader.problems


class _Reader:
    """Values built from YAML events as they stream (see :func:`read_yaml`)."""

    def __init__(self, file: str) -> None:
        self.file = file
        self.anchors: dict[str, tuple[Any, int]] = {}
        self.open_anchors: set[str] = set()
        self.stack: list[_Open] = []
        self.lines: dict[str, int] = {}
        self.problems: list[Problem] = []
        self.root: Any = None
        self.written = self.expanded = self.documents = 0

    def take(self, loader: Any, event: Any) -> None:
        """One event: a scalar, a collection opened or closed, an alias, a document."""
        kind = type(event)
        line = event.start_mark.line + 1
        if kind is yaml.ScalarEvent:
            self.written += 1
            try:
                value = _scalar(loader, event)
            except ValueError as error:  # a number of more digits than Python reads, a date
                text = event.value  # of month 13: what it is, not Python's advice on its limit
                shown = text if len(text) <= 40 else f"{text[:20]}... ({len(text)} characters)"
                reason = str(error).split(";")[0]
                raise _RefusedError(line, f"{shown} cannot be read: {reason}") from None
            if event.anchor:
                self.anchors[event.anchor] = (value, 1)
            self.attach(value, 1, line, True)
        elif kind is yaml.MappingStartEvent or kind is yaml.SequenceStartEvent:
            self.open(event, line, {} if kind is yaml.MappingStartEvent else [])
        elif kind is yaml.MappingEndEvent or kind is yaml.SequenceEndEvent:
            self.close(line)
        elif kind is yaml.AliasEvent:
            if event.anchor in self.open_anchors:
                raise _RefusedError(line, f"alias *{event.anchor} refers to itself")
            if event.anchor not in self.anchors:
                raise _RefusedError(line, f"alias *{event.anchor} names no anchor before it")
            value, size = self.anchors[event.anchor]
            self.attach(value, size, line, not isinstance(value, dict | list))
        elif kind is yaml.DocumentStartEvent:
            self.documents += 1
            if self.documents > 1:
                raise _RefusedError(line, "a pipeline file holds one YAML document")

    def open(self, event: Any, line: int, container: dict | list) -> None:
        self.written += 1
        if len(self.stack) >= MAX_DEPTH:
            raise _RefusedError(line, f"nested deeper than {MAX_DEPTH} levels")
        self.stack.append(_Open(container, self.child_path(), event.anchor))
        if event.anchor:
            self.open_anchors.add(event.anchor)

    def close(self, line: int) -> None:
        done = self.stack.pop()
        value = done.value
        if done.merged and isinstance(value, dict):
            value = {**done.merged, **value}
        if done.anchor:
            self.open_anchors.discard(done.anchor)
            self.anchors[done.anchor] = (value, done.size)
        self.attach(value, done.size, line, False)

    def child_path(self) -> list[str]:
        if not self.stack:
            return []
        parent = self.stack[-1]
        if isinstance(parent.value, list):
            return [*parent.path, str(len(parent.value))]
        return [*parent.path, str(parent.key)]

    def attach(self, value: Any, size: int, line: int, is_scalar: bool) -> None:
        """Put a finished value into its parent (as an item, a key, or a key's value)."""
        self.expanded += size
        if self.expanded > MIN_VALUE_BUDGET and self.expanded > 10 * self.written:
            raise _RefusedError(
                line, "the file expands to too many values (aliases of aliases?); refused"
            )
        if not self.stack:
            self.root = value
            return
        parent = self.stack[-1]
        parent.size += size
        if isinstance(parent.value, list):
            self.lines.setdefault(".".join([*parent.path, str(len(parent.value))]), line)
            parent.value.append(value)
        elif parent.key is _NO_KEY:
            if not is_scalar:
                raise _RefusedError(line, "mapping keys must be plain values, not collections")
            parent.key, parent.key_line = value, line
        else:
            self.set_value(parent, value)

    def set_value(self, parent: _Open, value: Any) -> None:
        key, parent.key = parent.key, _NO_KEY
        if key is _MERGE_KEY:  # `<<: *defaults` (explicit keys win)
            sources = value if isinstance(value, list) else [value]
            if not all(isinstance(source, dict) for source in sources):
                raise _RefusedError(parent.key_line, "a merge key '<<' must name mappings")
            for source in sources:
                parent.merged = {**source, **parent.merged}
            return
        where = ".".join([*parent.path, str(key)])
        if key in parent.value:
            self.problems.append(
                Problem(parent.key_line, where, f"duplicate key '{key}'", self.file)
            )
        self.lines[where] = parent.key_line
        parent.value[key] = value


def _scalar(loader: Any, event: yaml.ScalarEvent) -> Any:
    """The Python value of a scalar event, as the safe loader would construct it."""
    if event.style and event.implicit[1]:  # quoted, no tag: a string as written
        return event.value
    tag = loader.resolve(yaml.ScalarNode, event.value, event.implicit)
    if tag == "tag:yaml.org,2002:str":
        return event.value
    if tag == _MERGE:
        return _MERGE_KEY
    node = yaml.ScalarNode(tag, event.value, event.start_mark, event.end_mark, event.style)
    return loader.construct_object(node)


def parse_value(text: str, where: str = "command line") -> Any:
    """One YAML value (``2``, ``true``, ``[1, 2]``, ``{a: 1}``), read with the same bounds.

    Raises
    ------
    PipelineError
        Naming what is wrong with the text.
    """
    data, _, problems = read_yaml(text, where)
    if problems:
        raise PipelineError(problems, where)
    return data
