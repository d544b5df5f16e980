"""Tuned parameters written back into a pipeline file, keeping its comments and layout.

ruamel.yaml reads the file as a round-trip document (comments, key order, flow style
kept) and says where each value stands in the text. An override ``node.param`` or
``params.NAME`` of a value the file already writes as a single scalar is written over
that scalar's characters alone, so every other character of the file (aligned columns,
line breaks, inline comments) stays as it was; the text is read back and must hold
exactly the document with the overrides set. Otherwise (a new key, a list) the override
is set in the document and the document is written again, which keeps comments and key
order but lays the lines out anew. The file is written whole, then renamed into place,
after the pipeline loader has read it, so a save never leaves an invalid pipeline behind.
"""

from __future__ import annotations

import io
import re
import shlex
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from graphvision.execution.manifest import replace_bytes

__all__ = ["command_line", "save_parameters"]


def save_parameters(source: Path, overrides: dict[str, Any], target: Path | None = None) -> Path:
    """Write ``overrides`` into the pipeline ``source`` (or a copy at ``target``); its path.

    Raises
    ------
    KeyError
        An override names a node or a pipeline param the file does not have.
    PipelineError
        A value would read back from the written file as another (the pipeline loader
        reads YAML 1.1, the round trip writes YAML 1.2: ``no``, ``1e-05``), or a value
        the file shares through a YAML anchor would change another node's parameter too:
        nothing is written. A value a node takes through a merge key (``<<: *x``) is
        written in the node's own mapping.
    """
    from ruamel.yaml import YAML

    overrides = {k: v.item() if isinstance(v, np.generic) else v for k, v in overrides.items()}

    yaml = YAML()  # round trip: comments and layout kept
    yaml.preserve_quotes = True
    original = source.read_text(encoding="utf-8")
    document = yaml.load(original)
    places = []  # (mapping, key, value) to set, found while the positions are the file's
    shared_through: list[tuple[str, str]] = []  # (anchor, "params" or "node") of edited places
    for key, value in overrides.items():
        target_name, _, param = key.partition(".")
        if target_name == "params":
            if param not in (document.get("params") or {}):
                raise KeyError(f"the pipeline has no param '{param}'")
            places.append((document["params"], param, value))
            shared_through += [(document["params"].anchor.value, "params")]
            continue
        node = (document.get("nodes") or {}).get(target_name)
        if node is None:
            raise KeyError(f"the pipeline has no node '{target_name}'")
        if node.get("params") is None:
            node["params"] = {}
        places.append((node["params"], param, value))
        shared_through += [(node["params"].anchor.value, "params"), (node.anchor.value, "node")]
    text = _edited_in_place(original, places)
    for mapping, param, value in places:
        mapping[param] = value
    dumped = _dumped(yaml, document)
    if text is None or _loaded(yaml, text) != _loaded(yaml, dumped):
        text = dumped
    destination = target or source
    _check_read_back(text, overrides, destination)
    anchors = sorted({(anchor, kind) for anchor, kind in shared_through if anchor})
    _check_pipeline(original, text, overrides, destination, anchors)
    destination.parent.mkdir(parents=True, exist_ok=True)
    replace_bytes(destination, text.encode("utf-8"))
    return destination


_SCALAR = re.compile(r"""'(?:[^']|'')*'|"(?:[^"\\]|\\.)*"|[^,\]\}#\n]*[^,\]\}#\s]""")


def _edited_in_place(text: str, places: list[tuple[Any, str, Any]]) -> str | None:
    """``text`` with each value written over the scalar it replaces, or None when one of
    them is not a single scalar already in the file (a new key, a list, a mapping)."""
    lines = text.splitlines(keepends=True)
    starts = [0]
    for line in lines:
        starts.append(starts[-1] + len(line))
    edits = []
    for mapping, param, value in places:
        if param not in dict(mapping.non_merged_items()) or isinstance(value, (list, dict)):
            return None  # a new key, or one the mapping takes through a merge key (<<: *x)
        if isinstance(mapping[param], (list, dict)):
            return None
        row, column = mapping.lc.value(param)
        found = _SCALAR.match(lines[row], column)
        if found is None:
            return None
        written = yaml.safe_dump(value, default_flow_style=True, width=1 << 16)
        written = written.removesuffix("\n").removesuffix("\n...")
        edits.append((starts[row] + column, starts[row] + found.end(), written))
    for begin, end, written in sorted(edits, reverse=True):
        text = text[:begin] + written + text[end:]
    return text


def _dumped(yaml: Any, document: Any) -> str:
    buffer = io.StringIO()
    yaml.dump(document, buffer)
    return buffer.getvalue()


def _loaded(yaml: Any, text: str) -> Any:
    import json

    try:
        return json.dumps(yaml.load(text), sort_keys=True, default=str)
    except Exception:  # a substitution that does not read back: write the document anew
        return None


def _check_read_back(text: str, overrides: dict[str, Any], where: Path) -> None:
    """Each override read back from ``text`` as the pipeline loader reads it, or
    PipelineError naming those that would read back as another value."""
    from graphvision.errors import PipelineError, Problem
    from graphvision.graph.yaml_reader import _Loader

    document = yaml.load(text, Loader=_Loader) or {}
    problems = []
    for key, value in overrides.items():
        target, _, param = key.partition(".")
        holder = document if target == "params" else (document.get("nodes") or {}).get(target)
        got = ((holder or {}).get("params") or {}).get(param)
        same_kind = all(isinstance(got, t) == isinstance(value, t) for t in (bool, str))
        if got != value or not same_kind:
            message = f"{value!r} would be read back from the file as {got!r}; not saved"
            problems.append(Problem(0, key, message, str(where)))
    if problems:
        raise PipelineError(problems)


def _check_pipeline(
    original: str,
    text: str,
    overrides: dict[str, Any],
    where: Path,
    anchors: list[tuple[str, str]],
) -> None:
    """``text`` is a valid pipeline whose parameters are the original file's with the
    overrides set, and no other changed: PipelineError naming a parameter that a save
    would change too, because the file shares it with an overridden one through a YAML
    anchor (``&x``) and an alias (``*x``, ``<<: *x``)."""
    from graphvision.errors import PipelineError, Problem
    from graphvision.graph.pipeline_file import parse_pipeline

    before, after = parse_pipeline(original, file=str(where)), parse_pipeline(text, str(where))
    problems, kept = [], _parameters(before)
    for key, new in _parameters(after).items():  # a save adds keys, and never removes one
        old = kept.get(key, _UNSET)
        if key in overrides or new == old:
            continue
        param = key.partition(".")[2]
        causes = [k for k in overrides if k.partition(".")[2] == param] or list(overrides)
        node = causes[0].partition(".")[0]
        message = (
            f"saving {', '.join(causes)} would change it too ({old!r} → {new!r}): the file "
            f"shares the value through {_shared(anchors)} and its aliases; not saved. "
            f"Set them all to the same value, or give {node} {_own_mapping(anchors, param)}"
        )
        problems.append(Problem(0, key, message, str(where)))
    if problems:
        raise PipelineError(problems)


def _shared(anchors: list[tuple[str, str]]) -> str:
    """The anchors a save's mappings are shared through, as a message names them."""
    if not anchors:
        return "a YAML anchor"
    names = ", ".join(f"&{anchor}" for anchor, _ in anchors)
    return f"the YAML anchor{'s' if len(anchors) > 1 else ''} {names}"


def _own_mapping(anchors: list[tuple[str, str]], param: str) -> str:
    """How a node gets a mapping of its own: merge the shared ``params`` and override,
    or write the node out in full instead of the alias of another node."""
    if anchors and all(kind == "params" for _, kind in anchors):
        return f"a mapping of its own (params: {{<<: *{anchors[0][0]}, {param}: ...}})"
    shared_nodes = [anchor for anchor, kind in anchors if kind == "node"]
    if shared_nodes:
        return f"a node mapping of its own instead of the alias *{shared_nodes[0]}"
    return "a mapping of its own"


class _Unset:
    """A parameter the file did not set before the save (a key it added to a shared mapping)."""

    def __repr__(self) -> str:
        return "unset"


_UNSET = _Unset()


def _parameters(graph: Any) -> dict[str, Any]:
    """Every parameter of a graph by its override key (``node.param``, ``params.NAME``)."""
    found = {f"params.{name}": value for name, value in graph.params.items()}
    for name, node in graph.nodes.items():
        found.update({f"{name}.{param}": value for param, value in node.params.items()})
    return found


def command_line(pipeline: str, overrides: dict[str, Any], inputs: dict[str, Any]) -> str:
    """The ``graphvision run`` command that runs the pipeline with these values."""
    import json

    parts = ["graphvision", "run", pipeline]
    for name, value in inputs.items():
        parts += ["-i", f"{name}={value}"]
    for key, value in overrides.items():
        shown = json.dumps(value) if not isinstance(value, str) else value
        parts += ["--set", f"{key}={shown}"]
    return shlex.join(parts)
