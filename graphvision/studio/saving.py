"""Tuned parameters written back into a pipeline file, keeping its comments and layout.

ruamel.yaml reads the file as a round-trip document (comments, key order, flow style
kept); each override ``node.param`` or ``params.NAME`` is set in it and the document
is written again, to the same file or a new one (written whole, then renamed into place).
The result is read back by the pipeline loader before it replaces anything, so a save
never leaves an invalid pipeline behind.
"""

from __future__ import annotations

import io
import os
import shlex
import tempfile
from pathlib import Path
from typing import Any

__all__ = ["command_line", "save_parameters"]


def save_parameters(source: Path, overrides: dict[str, Any], target: Path | None = None) -> Path:
    """Write ``overrides`` into the pipeline ``source`` (or a copy at ``target``); its path.

    Raises
    ------
    KeyError
        An override names a node or a pipeline param the file does not have.
    """
    from ruamel.yaml import YAML

    yaml = YAML()  # round trip: comments and layout kept
    yaml.preserve_quotes = True
    document = yaml.load(source.read_text(encoding="utf-8"))
    for key, value in overrides.items():
        target_name, _, param = key.partition(".")
        if target_name == "params":
            if param not in (document.get("params") or {}):
                raise KeyError(f"the pipeline has no param '{param}'")
            document["params"][param] = value
            continue
        node = (document.get("nodes") or {}).get(target_name)
        if node is None:
            raise KeyError(f"the pipeline has no node '{target_name}'")
        if node.get("params") is None:
            node["params"] = {}
        node["params"][param] = value
    buffer = io.StringIO()
    yaml.dump(document, buffer)
    destination = target or source
    _check_pipeline(buffer.getvalue(), destination)
    _write_atomically(destination, buffer.getvalue())
    return destination


def _check_pipeline(text: str, where: Path) -> None:
    from graphvision.graph.pipeline_file import parse_pipeline

    parse_pipeline(text, file=str(where))


def _write_atomically(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as file:
            file.write(text)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


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
