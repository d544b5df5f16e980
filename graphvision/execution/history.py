"""The earlier runs of an output folder, kept in its ``history/`` subfolder.

Before a run replaces the files of the previous one, those files (its
``record.json``, ``report.md``, ``report.html`` and every output file its
record lists) are kept in ``history/<number>-<date>-<digest>/`` (numbered in
the order they were kept): hard links where the file system allows it (no
copy of the bytes; a run never writes into a file, it replaces it, so the
kept file stays as it was; a file that someone edits in place changes in both),
copies otherwise. A warm
re-run therefore no longer replaces the cold run's report: the folder shows
the newest run and links its predecessors, newest first.

``history/`` is graphvision's when it holds the marker file :data:`MARKER`
(a file, not a link). A ``history`` that someone else made (a file, a link, a
folder without the marker) is left alone, and a run that would replace a
previous one is refused instead (:func:`history_problem`): a run is never
replaced without being kept. The newest :data:`KEPT_RUNS` runs are kept, older
ones removed.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
import shutil
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from graphvision.errors import OutputFolderError

__all__ = [
    "HISTORY",
    "KEPT_RUNS",
    "MARKER",
    "Earlier",
    "earlier_runs",
    "history_problem",
    "keep_previous_run",
]

HISTORY = "history"
MARKER = ".graphvision-history"
KEPT_RUNS = 20
_ENTRY = re.compile(r"^(\d{6})-[0-9TZ.]*-([0-9a-f]{8})$")


@dataclass(frozen=True)
class Earlier:
    """One earlier run of a folder: its subfolder (relative to the run's folder, POSIX),
    when it ran, and its record read back as JSON (``{}`` when unreadable)."""

    folder: str
    date: str
    record: dict[str, Any]


def history_problem(directory: Path) -> str:
    """Why ``directory/history`` is not graphvision's (and cannot become so), or ''. One
    ``lstat`` when there is none (as in every new folder: each report page asks)."""
    folder = directory / HISTORY
    mode = _mode(folder)
    if mode is None:
        return ""
    if stat.S_ISLNK(mode):
        return f"{folder} is a symbolic link to {os.readlink(folder)}"
    if not stat.S_ISDIR(mode):
        return f"{folder} is a file, not graphvision's history folder"
    marker = _mode(folder / MARKER)
    if marker is not None and stat.S_ISLNK(marker):
        return f"{folder} is a folder graphvision did not make (its {MARKER} is a symbolic link)"
    if marker is None or not stat.S_ISREG(marker):
        return f"{folder} is a folder graphvision did not make (it has no file {MARKER})"
    return ""


def _mode(path: Path) -> int | None:
    """``path``'s own mode (a link's, not its target's), or None when there is nothing."""
    try:
        return os.lstat(path).st_mode
    except (FileNotFoundError, NotADirectoryError):
        return None


def _history(directory: Path) -> Path | None:
    """``directory/history`` when it is graphvision's (or free to become so), else None."""
    return None if history_problem(directory) else directory / HISTORY


def keep_previous_run(directory: Path, owned: set[str]) -> Path | None:
    """Keep the files of the run now in ``directory`` (``owned``, its record's list) in
    ``history/``; return the entry's folder, or None when there was no run to keep.
    Keeping the same run twice keeps it once.

    Raises
    ------
    OutputFolderError
        When there is a run to keep and ``history`` is not graphvision's
        (:func:`history_problem`): it is refused, not replaced unkept.
    """
    record = directory / "record.json"
    if not record.is_file() or record.is_symlink():
        return None
    problem = history_problem(directory)
    if problem:
        raise OutputFolderError(f"{problem}: the previous run in {directory} cannot be kept")
    history = directory / HISTORY
    raw = record.read_bytes()
    try:
        date = str(json.loads(raw).get("date", ""))
    except (ValueError, AttributeError):
        date = ""
    stamp = re.sub(r"[^0-9TZ.]", "", date.replace("+00:00", "Z"))
    digest = hashlib.sha256(raw).hexdigest()[:8]
    entries = _entries(history)
    same = [entry for entry in entries if entry.name.endswith(f"-{digest}")]
    if same:
        return same[0]
    names = [p.name for p in history.iterdir()] if history.is_dir() else []
    number = 1 + max((int(n[:6]) for n in names if _ENTRY.match(n)), default=0)  # links too
    entry = history / f"{number:06d}-{stamp}-{digest}"
    history.mkdir(exist_ok=True)
    (history / MARKER).touch()
    staging = history / f".{entry.name}.writing"
    if staging.is_symlink() or staging.is_file():  # planted or left: ours to replace
        staging.unlink()
    shutil.rmtree(staging, ignore_errors=True)
    staging.mkdir()
    for name in sorted(owned):
        source = directory / name
        if source.is_file() and not source.is_symlink():
            try:
                os.link(source, staging / name)
            except OSError:
                shutil.copy2(source, staging / name)
    os.replace(staging, entry)
    _prune(history)
    return entry


def _entries(history: Path) -> list[Path]:
    """The kept runs, newest first (their names start with the order they were kept in)."""
    if not history.is_dir():
        return []
    found = [
        p for p in history.iterdir() if _ENTRY.match(p.name) and p.is_dir() and not p.is_symlink()
    ]
    return sorted(found, key=lambda p: p.name, reverse=True)


def _prune(history: Path) -> None:
    for old in _entries(history)[KEPT_RUNS:]:
        shutil.rmtree(old, ignore_errors=True)


def earlier_runs(directory: Path) -> list[Earlier]:
    """The runs kept in ``directory``'s history, newest first; one ``lstat`` when there is
    none, as in every new folder (each report page asks)."""
    if _mode(directory / HISTORY) is None:
        return []
    history = _history(directory)
    if history is None:
        return []
    runs = []
    for entry in _entries(history):
        record: dict[str, Any] = {}
        with contextlib.suppress(OSError, ValueError):
            content = json.loads((entry / "record.json").read_text(encoding="utf-8"))
            record = content if isinstance(content, dict) else {}
        runs.append(Earlier(f"{HISTORY}/{entry.name}", str(record.get("date", "")), record))
    return runs
