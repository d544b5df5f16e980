"""A run's output folder before a run replaces it: the last run's record, and the outputs whose
files that run wrote for the same value (kept as they are: a warm re-run does not encode its
images again)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from graphvision.execution.owned import RECORD
from graphvision.execution.provenance import file_sha256
from graphvision.execution.record import RunResult

__all__ = ["previous_record", "unchanged_outputs"]


def previous_record(directory: Path) -> dict[str, Any]:
    """The last run's record in ``directory`` as JSON, or ``{}`` if there is none to trust."""
    try:
        content = json.loads((directory / RECORD).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return content if isinstance(content, dict) else {}


def unchanged_outputs(result: RunResult, directory: Path, owned: set[str]) -> dict[str, list[str]]:
    """Outputs whose files the last run in ``directory`` wrote for the same value (the same
    cache key) and that nobody changed since (their SHA-256 as recorded): kept as they are,
    so a warm re-run does not encode its images again."""
    previous = previous_record(directory)
    try:
        old_keys = {
            (node["name"], port): key
            for node in previous["nodes"]
            for port, key in node["keys"].items()
        }
        old_files, old_digests = previous["files"], previous["file_sha256"]
    except (KeyError, TypeError, AttributeError):
        return {}
    new_keys = {
        (node.name, port): key for node in result.record.nodes for port, key in node.keys.items()
    }
    kept: dict[str, list[str]] = {}
    for name, source in result.compiled.outputs.items():
        files = old_files.get(name) if isinstance(old_files, dict) else None
        if (
            name not in result.outputs
            or not isinstance(files, list)
            or not files
            or source not in new_keys
            or old_keys.get(source) != new_keys[source]
        ):
            continue
        intact = all(
            isinstance(f, str)
            and f in owned
            and (directory / f).is_file()
            and not (directory / f).is_symlink()
            and old_digests.get(f) == file_sha256(directory / f)
            for f in files
        )
        if intact:
            kept[name] = list(files)
    return kept
