"""Writing a run's outputs, record and report to a folder.

Each output is written by its port type (images as PNG, arrays as ``.npy``,
tables as CSV and JSON, scalars as JSON); the run record goes to
``record.json`` and a human summary to ``report.md``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from ._compile import CompiledGraph
from ._ports import PortType, _ScalarPort
from ._run import RunRecord

__all__ = ["shown_value", "write_outputs", "write_report"]

SMALL_ARRAY = 16  # arrays of at most this many elements are shown by value (a homography)


def write_outputs(
    compiled: CompiledGraph, outputs: dict[str, Any], directory: Path
) -> dict[str, list[str]]:
    """Write every produced output to ``directory``; return output name -> file names."""
    directory.mkdir(parents=True, exist_ok=True)
    written = {}
    for name, value in outputs.items():
        files = compiled.output_type(name).write(value, directory / name)
        written[name] = [f.name for f in files]
    return written


def write_report(
    compiled: CompiledGraph,
    outputs: dict[str, Any],
    files: dict[str, list[str]],
    record: RunRecord,
    directory: Path,
) -> Path:
    """``record.json`` and ``report.md`` in ``directory``; returns the report's path."""
    (directory / "record.json").write_text(record.to_json() + "\n")
    graph = compiled.graph
    lines = [f"# {graph.name}", ""]
    if graph.description:
        lines += [graph.description.strip(), ""]
    lines += ["## Outputs", "", "| output | value | files |", "| --- | --- | --- |"]
    for name in compiled.outputs:
        if name not in outputs:
            lines.append(f"| {name} | not produced | |")
            continue
        shown = _cell(shown_value(compiled.output_type(name), outputs[name]))
        links = ", ".join(f"[{f}]({f})" for f in files.get(name, []))
        lines.append(f"| {name} | {shown} | {links} |")
    images = [f for fs in files.values() for f in fs if f.endswith(".png")]
    if images:
        lines += ["", *[f"![{f}]({f})" for f in images]]
    lines += ["", "## Run record", "", "```", record.table(), "```", ""]
    path = directory / "report.md"
    path.write_text("\n".join(lines))
    return path


def shown_value(kind: type[PortType], value: Any) -> str:
    """How the report shows a value: scalars as JSON, small arrays by value, else a summary.

    Works for every dtype an array port can hold (bool, integers, floats with
    NaN or inf): small arrays go through :func:`numpy.ndarray.tolist`, floats
    rounded to 6 decimals, never through arithmetic that a dtype may refuse.
    """
    if issubclass(kind, _ScalarPort):
        return json.dumps(value)
    summary = kind.summary(value)
    if isinstance(value, np.ndarray) and value.size <= SMALL_ARRAY:
        if np.issubdtype(value.dtype, np.floating):
            value = np.round(value.astype(np.float64), 6)
        return f"{summary}: `{json.dumps(value.tolist(), default=str)}`"
    return summary


def _cell(text: str) -> str:
    """``text`` safe inside a Markdown table cell (one line, pipes escaped)."""
    return " ".join(text.split()).replace("|", "\\|")
