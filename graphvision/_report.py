"""Writing a run's outputs, record and report to a folder.

Each output is written by its port type (images as PNG, arrays as ``.npy``,
tables as CSV and JSON, scalars as JSON); the run record goes to
``record.json`` and a human summary to ``report.md``.

A folder holds one run. graphvision owns exactly the files its
``record.json`` lists (``files``, plus the record and the report): writing a
new run removes those of the previous run, so no output of an earlier run
(an output this run did not produce, or could not because a node failed) is
left looking current; any other file is the user's and is never removed nor
overwritten: a run whose files would replace one is refused
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
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from ._compile import CompiledGraph
from ._errors import OutputFolderError
from ._graph import NAME, output_name_problem
from ._html import write_html_report
from ._ports import PortType, _ScalarPort
from ._provenance import file_sha256
from ._registry import Registry
from ._run import RunRecord, RunResult

__all__ = [
    "RECORD",
    "REPORT",
    "check_output_folder",
    "owned_files",
    "remove_owned_files",
    "rewrite_report",
    "shown_value",
    "write_outputs",
    "write_report",
    "write_run",
]

RECORD, REPORT, REPORT_HTML = "record.json", "report.md", "report.html"
STAGING = ".graphvision-writing-"  # prefix of the hidden folder a run's files are written to
OUTPUT_SUFFIXES = (".png", ".npy", ".npz", ".json", ".csv", ".ply")  # the built-in writers'
SMALL_ARRAY = 16  # arrays of at most this many elements are shown by value (a homography)


def owned_files(directory: Path) -> set[str]:
    """The file names in ``directory`` that a previous graphvision run wrote (its record's list).

    Raises
    ------
    OutputFolderError
        When ``directory`` has a ``record.json`` that is not a graphvision
        record listing its files (so what is ours there cannot be known).
    """
    record = directory / RECORD
    if not record.is_file():
        return set()
    try:
        content = json.loads(record.read_text())
        listed = content["files"]
        names = {name for files in listed.values() for name in files}
        if not all(
            isinstance(n, str) and n == Path(n).name and n not in ("", ".", "..") for n in names
        ):
            raise ValueError("a listed file is not a plain file name")
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as error:
        raise OutputFolderError(
            f"{record} is not a graphvision record listing its files ({type(error).__name__}), "
            "so which files there are a previous run's is unknown; choose another "
            "--output-dir or empty this one"
        ) from None
    return names | {RECORD, REPORT, REPORT_HTML}


def check_output_folder(directory: Path, outputs: Iterable[str]) -> set[str]:
    """Refuse, before a run, a folder where the run's files would replace files not graphvision's.

    A file counts as the run's when its name is ``record.json``, ``report.md``
    or an output name with a suffix a port type writes. Returns the previous
    run's files (:func:`owned_files`).

    Raises
    ------
    OutputFolderError
        Naming the folder and the first file in the way, or an output named
        ``record`` (its file would be the record's).
    """
    if directory.exists() and not directory.is_dir():
        raise OutputFolderError(f"output folder {directory} is a file")
    stems = set(outputs)
    if Path(RECORD).stem in stems:
        raise OutputFolderError(
            f"output '{Path(RECORD).stem}' cannot be written to an output folder: its file "
            f"would be {RECORD}, the run record; rename the output"
        )
    owned = owned_files(directory)
    if not directory.is_dir():
        return owned
    for path in sorted(directory.iterdir()):
        ours = path.name in (RECORD, REPORT, REPORT_HTML) or (
            path.stem in stems and path.suffix in OUTPUT_SUFFIXES
        )
        if ours and path.name not in owned:
            _refuse(directory, path.name)
    return owned


def _refuse(directory: Path, name: str) -> None:
    raise OutputFolderError(
        f"output folder {directory} holds {name}, which no graphvision record there lists; "
        "the run would replace it: move it, or choose another --output-dir"
    )


def remove_owned_files(directory: Path, names: Iterable[str]) -> None:
    """Delete the listed files of a previous run (plain files directly in ``directory`` only)."""
    for name in names:
        path = directory / name
        if path.is_file() or path.is_symlink():
            path.unlink()


def write_run(result: RunResult, directory: Path) -> dict[str, list[str]]:
    """Write outputs, ``record.json``, ``report.md`` and ``report.html``, replacing the last run's.

    Returns output name -> file names. The record lists the files
    (``record.files``), which is how the next run knows what is its to remove.

    Raises
    ------
    OutputFolderError
        When a file would replace one no graphvision record there lists.
    """
    owned = check_output_folder(directory, result.compiled.outputs)
    directory.mkdir(parents=True, exist_ok=True)
    for left in directory.glob(f"{STAGING}*"):  # from a run killed while writing
        shutil.rmtree(left, ignore_errors=True)
    kept = _unchanged_outputs(result, directory, owned)
    staging = Path(tempfile.mkdtemp(prefix=STAGING, dir=directory))
    try:
        changed = {name: v for name, v in result.outputs.items() if name not in kept}
        written = write_outputs(result.compiled, changed, staging)
        digests = {f: file_sha256(staging / f) for names in written.values() for f in names}
        previous = _previous_record(directory)
        for names in kept.values():
            digests.update({f: previous["file_sha256"][f] for f in names})
        files = {name: kept.get(name) or written[name] for name in result.outputs}
        result.record.files = files
        result.record.file_sha256 = digests
        write_report(result.compiled, result.outputs, files, result.record, staging)
        failures = {name: str(error) for name, error in result.failures.items()}
        write_html_report(
            result.compiled,
            result.outputs,
            result.record,
            staging,
            failures=failures,
            intermediates=result.intermediates,
        )
        new = [name for names in written.values() for name in names] + [REPORT_HTML, REPORT, RECORD]
        for name in new:
            if (directory / name).exists() and name not in owned:
                _refuse(directory, name)
        unchanged = {name for names in kept.values() for name in names}
        remove_owned_files(directory, owned - {RECORD} - unchanged)  # the record: replaced last
        for name in new:  # the record last, in one atomic replace
            os.replace(staging / name, directory / name)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return files


def _previous_record(directory: Path) -> dict[str, Any]:
    """The last run's record in ``directory`` as JSON, or ``{}`` if there is none to trust."""
    try:
        content = json.loads((directory / RECORD).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return content if isinstance(content, dict) else {}


def _unchanged_outputs(result: RunResult, directory: Path, owned: set[str]) -> dict[str, list[str]]:
    """Outputs whose files the last run in ``directory`` wrote for the same value (the same
    cache key) and that nobody changed since (their SHA-256 as recorded): kept as they are,
    so a warm re-run does not encode its images again."""
    previous = _previous_record(directory)
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


def write_outputs(
    compiled: CompiledGraph, outputs: dict[str, Any], directory: Path
) -> dict[str, list[str]]:
    """Write every produced output to ``directory``; return output name -> file names."""
    directory.mkdir(parents=True, exist_ok=True)
    written = {}
    for name, value in outputs.items():
        if not NAME.match(name):  # compile_graph refuses these; a port type may not add any
            raise OutputFolderError(output_name_problem(name))
        kind = compiled.output_type(name)
        files = kind.write(value, directory / name)
        for file in files:
            if file.parent != directory or file.is_symlink() or not file.is_file():
                raise OutputFolderError(
                    f"port type {kind.type_name()} wrote output '{name}' as {file}, which is "
                    f"not a plain file directly in {directory}"
                )
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
    path = directory / "report.md"
    path.write_text("\n".join(lines))
    return path


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


def rewrite_report(directory: Path, registry: Registry | None = None) -> Path:
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
    from ._compile import compile_graph
    from ._pipeline_file import load_pipeline
    from ._plugins import discover

    record_path = directory / RECORD
    if not directory.is_dir():
        raise OutputFolderError(f"{directory}: no such folder (give a run's -d folder)")
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
    outputs: dict[str, Any] = {}
    for name, names in record.files.items():
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
            outputs[name] = port.validate(port.read(paths))
        except Exception as error:  # files on disk, edited by anyone: any failure is theirs
            raise OutputFolderError(
                f"output '{name}' in {directory} cannot be read back as {port.type_name()} "
                f"({error})"
            ) from None
    written = {name: list(names) for name, names in record.files.items()}
    write_report(compiled, outputs, written, record, directory)
    return write_html_report(compiled, outputs, record, directory)


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
