"""Writing a run's outputs, record and report to a folder.

Each output is written by its port type (images as PNG, arrays as ``.npy``,
tables as CSV and JSON, scalars as JSON); the run record goes to
``record.json`` and a human summary to ``report.md``.

A folder holds one run. graphvision owns exactly the files its
``record.json`` lists (``files``, plus the record and the report): writing a
new run removes those of the previous run, so no output of an earlier run
(an output this run did not produce, or could not because a node failed) is
left looking current (the previous run's files are kept, with its report, in
``history/``, and the new report links them, newest first); any other file is
the user's and is never removed nor overwritten: a run whose files would replace one is refused
(:class:`~graphvision.OutputFolderError`), before it runs when the CLI can
tell. The new files are written to a hidden staging folder first and moved
in, ``record.json`` last.
"""

from __future__ import annotations

import functools
import json
import os
import shutil
import tempfile
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from graphvision.compiler.compile import CompiledGraph
from graphvision.errors import OutputFolderError
from graphvision.execution.folders import STAGING, RunPage, earlier_of
from graphvision.execution.history import earlier_runs
from graphvision.execution.owned import RECORD, REPORT, REPORT_HTML, write_file
from graphvision.execution.provenance import file_sha256
from graphvision.execution.record import RunRecord, RunResult
from graphvision.nodes.registry import Registry
from graphvision.values.ports import PortType
from graphvision.values.scalars import _ScalarPort
from graphvision.views.html import write_html_report

__all__ = [
    "RUN_PAGES",
    "html_page",
    "markdown_page",
    "read_record",
    "rewrite_report",
    "shown_value",
    "write_report",
]

SMALL_ARRAY = 16  # arrays of at most this many elements are shown by value (a homography)


def write_report(
    compiled: CompiledGraph,
    outputs: dict[str, Any],
    files: dict[str, list[str]],
    record: RunRecord,
    directory: Path,
) -> Path:
    """``report.md`` in ``directory`` (with the folder's earlier runs); returns its path."""
    graph = compiled.graph
    lines = [f"# {_plain_text(graph.name)}", ""]
    if graph.description:  # written by whoever wrote the pipeline: text, never markup
        lines += [_plain_text(graph.description.strip()), ""]
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
    lines += ["", "## Provenance", "", *_provenance_lines(record)]
    lines += ["", "## Run record", "", "```", record.table(), "```", ""]
    earlier = earlier_of(directory)
    if earlier:
        lines += ["## Earlier runs (newest first)", ""]
        lines += [
            f"- [{run.date or run.folder}]({run.folder}/report.md): {_computed(run.record)} "
            f"computed, overrides `{json.dumps(run.record.get('overrides') or {}, default=str)}`"
            for run in earlier
        ]
        lines.append("")
    path = directory / "report.md"
    write_file(path, "\n".join(lines).encode())  # UTF-8, as report.html
    return path


def _computed(record: dict[str, Any]) -> int:
    """How many nodes an earlier run's record (JSON, as read back) says it computed."""
    nodes = record.get("nodes")
    return sum(
        isinstance(node, dict) and node.get("status") == "computed"
        for node in (nodes if isinstance(nodes, list) else [])
    )


def _plain_text(text: str) -> str:
    """``text`` shown as written by a Markdown viewer: HTML's special characters as
    entities, so a pipeline's ``<script>`` or ``<img onerror=...>`` is text, not markup."""
    from html import escape

    return escape(text, quote=False)


def _provenance_lines(record: RunRecord) -> list[str]:
    """Where the run came from, for a reader (``record.json`` has everything)."""
    lines = [f"- run {record.date or 'date unknown'}, {record.executor} executor"]
    if record.pipeline_file:
        commit = record.git_commit[:12] + (" with local changes" if record.git_dirty else "")
        lines.append(
            f"- pipeline `{record.pipeline_file}` (SHA-256 {record.pipeline_sha256[:12]}"
            f"{f', git {commit}' if record.git_commit else ''})"
        )
    for name, entry in record.inputs.items():
        digest = f" (SHA-256 {entry['sha256'][:12]})" if "sha256" in entry else ""
        lines.append(f"- input `{name}`: `{entry.get('path', entry.get('given', ''))}`{digest}")
    if record.overrides:
        lines.append(f"- overrides: `{json.dumps(record.overrides, default=str)}`")
    versions = ", ".join(
        f"{k} {v}" for k, v in record.versions.items() if not k.startswith("plugin ")
    )
    if versions:
        lines.append(f"- {versions}")
    return lines


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


def rewrite_report(directory: str | Path, registry: Registry | None = None) -> Path:
    """Make ``report.md`` and ``report.html`` of a run folder again from its files.

    The run's ``record.json`` names the pipeline file, the overrides and the
    files of each output; the outputs are read back by their port types (images
    from their PNGs, arrays from ``.npy``/``.npz``, scalars and tables from
    JSON, point clouds from PLY). Useful after editing outputs by hand, or to
    get the HTML page of a run written before it existed. Returns the page.

    Raises
    ------
    OutputFolderError
        Naming what is missing or unreadable: the folder, its record, the
        pipeline file, an output's file. Nothing is written then.
    """
    from graphvision.compiler.compile import compile_graph
    from graphvision.graph.pipeline_file import load_pipeline
    from graphvision.nodes.plugins import discover

    directory = Path(directory)
    record_path = directory / RECORD
    if not directory.is_dir():
        raise OutputFolderError(f"{directory}: no such folder (give a run's -d folder)")
    for name in (RECORD, REPORT, REPORT_HTML):  # the run's own files, or refused
        if (directory / name).is_symlink():
            raise OutputFolderError(
                f"{directory / name} is a symbolic link to {os.readlink(directory / name)}, "
                "not a file a run wrote there: the report replaces only a run's own pages; "
                "remove it"
            )
    if not record_path.is_file():
        raise OutputFolderError(f"{directory} has no {RECORD}: it is not a graphvision run folder")
    record = read_record(record_path)
    for name, names in record.files.items():
        outside = [file for file in names if Path(file).name != file]
        if outside:  # a record graphvision wrote names files in its own folder only
            raise OutputFolderError(
                f"{record_path} lists a file outside its folder for output '{name}': {outside[0]}"
            )
    source = Path(record.pipeline_file) if record.pipeline_file else None
    if source is None or not source.is_file():
        raise OutputFolderError(
            f"the pipeline file of the run in {directory} is gone ({record.pipeline_file or '?'}): "
            "the report draws its graph"
        )
    if record.pipeline_sha256 and file_sha256(source) != record.pipeline_sha256:
        warnings.warn(
            f"the pipeline file {source} changed since the run (its SHA-256 is not the "
            "record's): the report draws the graph as the file is now",
            stacklevel=2,
        )
    graph = load_pipeline(source)
    registry = registry or discover(graph.plugins)
    try:
        graph = graph.with_overrides(record.overrides) if record.overrides else graph
    except KeyError as error:
        raise OutputFolderError(
            f"the pipeline file {source} no longer fits the run in {directory}: {error.args[0]}"
        ) from None
    compiled = compile_graph(graph, registry, provided=set(record.inputs))
    outputs = {
        name: _read_output(name, names, compiled, record, (directory, source))
        for name, names in record.files.items()
    }
    return _write_pages(compiled, outputs, record, directory)


def _write_pages(
    compiled: CompiledGraph, outputs: dict[str, Any], record: RunRecord, directory: Path
) -> Path:
    """``report.md`` and ``report.html`` written to a staging folder in ``directory``, then
    moved into place, each whole (as a run places them); returns the page."""
    written = {name: list(names) for name, names in record.files.items()}
    staging = Path(tempfile.mkdtemp(prefix=STAGING, dir=directory))
    try:
        write_report(compiled, outputs, written, record, staging)
        write_html_report(compiled, outputs, record, staging, earlier=earlier_runs(directory))
        for name in (REPORT, REPORT_HTML):
            os.replace(staging / name, directory / name)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return directory / REPORT_HTML


def _read_output(
    name: str,
    names: list[str],
    compiled: CompiledGraph,
    record: RunRecord,
    where: tuple[Path, Path],
) -> Any:
    """Output ``name`` read back from its files, or OutputFolderError saying why it cannot be
    (its type changed, a file is gone); a warning when a file was edited since the run."""
    directory, source = where
    recorded = record.outputs.get(name, "").split(" ", 1)[0]
    now = compiled.output_type(name).type_name() if name in compiled.outputs else None
    if now != recorded:
        change = f"is now {now}" if now else "is no longer an output"
        raise OutputFolderError(
            f"the pipeline file {source} no longer fits the run in {directory}: output "
            f"'{name}' was {recorded or 'not recorded'} and {change}"
        )
    paths = [directory / file for file in names]
    missing = [p.name for p in paths if not p.is_file()]
    if missing:
        raise OutputFolderError(
            f"output '{name}' of the run in {directory} is gone ({', '.join(missing)}): "
            "run the pipeline again to write it"
        )
    edited = [
        p.name
        for p in paths
        if p.name in record.file_sha256 and file_sha256(p) != record.file_sha256[p.name]
    ]
    if edited:
        warnings.warn(
            f"output '{name}' in {directory} was edited since the run ({', '.join(edited)}): "
            "the report shows it as it is now",
            stacklevel=2,
        )
    port = compiled.output_type(name)
    try:
        return port.validate(port.read(paths))
    except Exception as error:  # files on disk, edited by anyone: any failure is theirs
        raise OutputFolderError(
            f"output '{name}' in {directory} cannot be read back as {port.type_name()} ({error})"
        ) from None


def markdown_page(result: RunResult, directory: Path) -> list[str]:
    """``report.md`` of ``result`` in ``directory`` (a :data:`RunPage`)."""
    files = result.record.files
    write_report(result.compiled, result.outputs, files, result.record, directory)
    return [REPORT]


def html_page(result: RunResult, directory: Path) -> list[str]:
    """``report.html`` of ``result`` in ``directory`` (a :data:`RunPage`)."""
    write_html_report(
        result.compiled,
        result.outputs,
        result.record,
        directory,
        failures={name: str(error) for name, error in result.failures.items()},
        intermediates=result.intermediates,
        earlier=earlier_of(directory),
    )
    return [REPORT_HTML]


RUN_PAGES: tuple[RunPage, ...] = (markdown_page, html_page)
"""The pages of a run folder: ``report.md`` and ``report.html``."""


def read_record(path: Path) -> RunRecord:
    """The run record in ``path``, every field checked against :class:`RunRecord`'s types.

    Raises
    ------
    OutputFolderError
        Naming the file and the first field that is not what a graphvision
        record holds (a hand-edited or damaged ``record.json``).
    """
    import pydantic

    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        if not isinstance(data, dict):
            raise ValueError(f"a JSON {type(data).__name__}, not an object")
        known = {key: value for key, value in data.items() if key in _RECORD_FIELDS}
        return _record_adapter().validate_python(known)
    except pydantic.ValidationError as error:
        first = error.errors()[0]
        where = ".".join(str(p) for p in first["loc"]) or "the record"
        raise OutputFolderError(
            f"{path} is not a graphvision run record: {where}: {first['msg']}"
        ) from None
    except (OSError, ValueError) as error:
        raise OutputFolderError(f"{path} is not a graphvision run record ({error})") from None


_RECORD_FIELDS = frozenset(RunRecord.__dataclass_fields__)


@functools.cache
def _record_adapter() -> Any:
    import pydantic

    return pydantic.TypeAdapter(RunRecord)
