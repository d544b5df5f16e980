"""What a batch reads and writes around its runs: the files a pattern matches, one output
folder per file, the items and their summary (``batch.csv``)."""

from __future__ import annotations

import csv
import errno
import glob
import io
import os
import stat
import unicodedata
import warnings
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from graphvision.errors import OutputFolderError
from graphvision.execution.folder_glob import glob_once
from graphvision.execution.folders import RunPage
from graphvision.execution.manifest import FolderFiles, check_folder_files
from graphvision.execution.owned import check_output_folder

__all__ = [
    "BATCH_FILES",
    "NO_PAGES",
    "SUMMARY",
    "SUMMARY_PAGE",
    "BatchItem",
    "BatchPages",
    "BatchResult",
    "batch_files",
    "checked_folders",
    "common_parts",
    "output_folders",
    "pattern_root",
    "previous_folders",
    "summary_text",
    "unreadable_reason",
]

SUMMARY = "batch.csv"
SUMMARY_PAGE = "batch.html"  # written by the summary page of :class:`BatchPages`, when given
MANIFEST = "batch.json"  # what the batch wrote beside its folders (execution.manifest)
_COLUMNS = ("file", "output_dir", "status", "seconds", "error")  # batch.csv's first columns


@dataclass
class BatchItem:
    """One file of a batch: where its outputs went (None, as in ``batch.csv``, when it has
    no folder: it could not be read, failed with no earlier run kept, or did not run), how
    it went, its scalar outputs."""

    file: Path
    output_dir: Path | None
    status: str = "ok"
    seconds: float = 0.0
    error: str = ""
    scalars: dict[str, Any] = field(default_factory=dict)


@dataclass
class BatchResult:
    """Every item, and the summary table written to ``summary``.

    With one task per file (processes, Dask), ``value_bytes`` counts the
    encoded values the workers computed for the files after the first, and
    ``client_bytes`` what passed through the client for them (the batch's job
    sent once, each task's file and folder, each file's outcome; as pickled):
    the values stay on the workers.
    """

    items: list[BatchItem]
    summary: Path
    value_bytes: int = 0
    client_bytes: int = 0

    @property
    def failed(self) -> int:
        return sum(item.status != "ok" for item in self.items)


@dataclass(frozen=True)
class BatchPages:
    """The report pages a batch writes: ``run`` in each item folder, and ``summary`` (a
    function of the items and the batch folder giving the text of :data:`SUMMARY_PAGE`)."""

    run: Sequence[RunPage] = ()
    summary: Callable[[Sequence[BatchItem], Path], str] | None = None


NO_PAGES = BatchPages()


def batch_files(pattern: str, exclude: Path | None = None) -> tuple[list[Path], list[Path]]:
    """The paths a glob matches, sorted (``**`` matches any depth of folders), and those
    of them left out because they are under ``exclude``.

    ``exclude`` is the batch's output folder, when it lies inside the searched
    folders: a batch never reads its own outputs, and the caller says so when
    that leaves nothing. ``**`` searches each real folder once (:func:`.glob_once`).
    A file reached by several paths (a folder symlink, a link back up the tree) is
    taken once, by its shortest path (among the shortest, the one through the fewest
    symbolic links, then the first in name order), so that it runs once and has one
    folder; a warning names the path kept and those skipped (one line for the batch).
    A match that cannot be read as a file (a dangling or looping symbolic link, a
    pipe, and a folder when the pattern's last part names a suffix, as ``*.png``
    does) is kept, for the batch to list it as failed with :func:`unreadable_reason`;
    folders matched by a pattern that names no suffix (``photos/*``) are the folders
    searched.
    """
    skipped = exclude.resolve() if exclude is not None else None
    folders_are_matches = "." in Path(pattern).name
    found: dict[Path, list[Path]] = {}
    left_out: dict[Path, list[Path]] = {}
    matches = sorted(map(Path, glob_once(pattern)), key=lambda p: (len(p.parts), p))
    for path in matches:
        if path.is_dir() and not folders_are_matches:
            continue
        try:
            real = path.resolve(strict=path.is_file())
        except (OSError, RuntimeError):  # a symbolic link loop
            real = path.absolute()
        chosen = left_out if skipped is not None and skipped in real.parents else found
        chosen.setdefault(real, []).append(path)
    several = [_kept_first(paths) for paths in found.values() if len(paths) > 1]
    _warn_of_paths_taken_once(pattern, several)
    kept = [paths[0] for paths in found.values() if len(paths) == 1] + [p[0] for p in several]
    return sorted(kept), sorted(p[0] for p in left_out.values())


def _kept_first(paths: list[Path]) -> list[Path]:
    """``paths`` (the same file's) with the one to keep first: the one through the fewest
    symbolic links (its real folder before a link to it, shorter though the link may be),
    then the shortest, then by name."""
    kept = min(paths, key=lambda p: (sum(q.is_symlink() for q in (p, *p.parents)), len(p.parts), p))
    return [kept, *(p for p in paths if p != kept)]


def _warn_of_paths_taken_once(pattern: str, several: list[list[Path]]) -> None:
    """One warning for the files ``pattern`` reaches by several paths (each list: the
    path kept, then those skipped), naming the first such file's paths (three of them at
    most: a link to its own folder reaches a file by dozens)."""
    if several:
        kept, *others = min(several)
        named = ", ".join(map(str, others[:3])) + (
            f" and {len(others) - 3} more paths" if len(others) > 3 else ""
        )
        more = f"; {len(several) - 1} more file(s) likewise" if len(several) > 1 else ""
        warnings.warn(
            f"batch '{pattern}': {kept} is also reached as {named} (symbolic links): "
            f"taken once, as {kept}{more}",
            stacklevel=5,  # run_batch's caller: _batch_paths, run_batch, the user's call
        )


def unreadable_reason(path: Path) -> str:
    """Why ``path`` cannot be read as an input file (``is a folder, not a file``), or ''."""
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        if path.is_symlink():
            return f"is a symbolic link to {os.readlink(path)}, which does not exist"
        return "does not exist (any more)"
    except OSError as error:
        if error.errno == errno.ELOOP:
            return "is a symbolic link loop: following it never reaches a file"
        return f"cannot be read ({error.strerror})"
    except RuntimeError:  # a symbolic link loop, as some Python versions report it
        return "is a symbolic link loop: following it never reaches a file"
    if stat.S_ISDIR(mode):
        return "is a folder, not a file"
    if not stat.S_ISREG(mode):
        return "is not a regular file (a pipe, a socket or a device): give it as a file"
    if not os.access(path, os.R_OK):
        return "cannot be read (permission denied)"
    return ""


def pattern_root(pattern: str) -> Path:
    """The folder before a glob's first wildcard (``photos`` for ``photos/**/*.png``)."""
    fixed = []
    for part in Path(pattern).parts:
        if glob.has_magic(part):
            break
        fixed.append(part)
    else:  # no wildcard: a single file, named by its own folder
        fixed = fixed[:-1]
    return Path(*fixed) if fixed else Path()


def output_folders(files: Sequence[Path], root: Path, out_dir: Path) -> list[Path]:
    """A distinct folder under ``out_dir`` for each file: its path below ``root`` without suffix.

    Two files whose paths differ only by suffix (``img.png``, ``img.jpg``) keep
    it (``img_png``, ``img_jpg``); any name still taken, or the name of one of the
    batch's own files (``batch.csv``, ``batch.html``, ``batch.json``), gets ``-2``,
    ``-3``... so the folders are always distinct; a part named like graphvision's hidden
    files (``.graphvision…``), or ``.`` or ``..`` (the folder of ``..png`` or ``...png``,
    which would be the batch's folder or the one above it), gets ``_`` before it.
    """
    relative = [_below(f, root) for f in files]
    plain = [_folder_path(r) for r in relative]
    counts: dict[Path, int] = {}
    for name in plain:
        counts[name] = counts.get(name, 0) + 1
    taken = {Path(SUMMARY), Path(SUMMARY_PAGE), Path(MANIFEST)}  # the batch's own files
    folders = []
    for rel, name in zip(relative, plain, strict=True):
        if counts[name] > 1 and rel.suffix:
            name = name.with_name(f"{name.name}_{rel.suffix[1:]}")
        candidate, number = name, 1
        while candidate in taken:
            number += 1
            candidate = name.with_name(f"{name.name}-{number}")
        taken.add(candidate)
        folders.append(out_dir / candidate)
    return folders


def _folder_path(relative: Path) -> Path:
    """The item folder of the file at ``relative`` (below the batch's root): its path without
    its suffix, each part that would not be a folder of its own below the batch's folder
    given ``_`` before it (:func:`_own_part`)."""
    stem = relative.name[: len(relative.name) - len(relative.suffix)]
    return Path(*(_own_part(part) for part in (*relative.parts[:-1], stem)))


def _own_part(part: str) -> str:
    """``part`` of an item folder's path, with ``_`` before it when it is ``.``, ``..`` or
    empty (the folder would be the one above, or the batch's own) or a name graphvision's
    hidden files could have (``.graphvision-lock``, a new folder's ``.graphvision-new-…``)."""
    if part in ("", ".", "..") or part.startswith(".graphvision"):
        return "_" + part
    return part


def _below(file: Path, root: Path) -> Path:
    try:
        return file.relative_to(root)
    except ValueError:  # outside the root: keep what can be kept, without '..' or an anchor
        return Path(*[p for p in file.parts if p not in ("..", file.anchor)])


def common_parts(parts: list[tuple[str, ...]]) -> tuple[str, ...]:
    common: tuple[str, ...] = parts[0] if parts else ()
    for other in parts[1:]:
        length = 0
        while length < min(len(common), len(other)) and common[length] == other[length]:
            length += 1
        common = common[:length]
    return common


def _summary_folders(summary: Path) -> list[str]:
    """The ``output_dir`` column of a batch summary (ValueError when it is none)."""
    with summary.open(newline="", encoding="utf-8") as handle:
        reader = csv.DictReader(handle)
        if not _summary_header(reader.fieldnames or []):
            raise ValueError("not a batch summary")
        return [row.get("output_dir") or "" for row in reader]


def _is_summary(path: Path) -> bool:
    """Whether ``path`` is ``batch.csv`` as a batch wrote it before it kept ``batch.json``:
    its header starts with the columns :func:`summary_text` writes first."""
    if path.name != SUMMARY:
        return False
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            return _summary_header(next(csv.reader(handle), []))
    except (OSError, UnicodeDecodeError, csv.Error):
        return False


def _summary_header(columns: Sequence[str]) -> bool:
    """Whether ``columns`` start as :func:`summary_text` writes them."""
    return list(columns[: len(_COLUMNS)]) == list(_COLUMNS)


BATCH_FILES = FolderFiles(
    MANIFEST, "batch", lambda name: name in (SUMMARY, SUMMARY_PAGE), _is_summary
)
"""A batch's own files in its folder, listed with their digests in ``batch.json``."""


def previous_folders(out_dir: Path) -> set[Path]:
    """The item folders a previous ``batch.csv`` lists, only those inside ``out_dir`` (where
    they lead, as paths below ``out_dir``: ``out_dir`` itself may be reached by a link).

    Raises
    ------
    OutputFolderError
        When ``out_dir`` holds a ``batch.csv`` that is not a graphvision
        summary (the batch would overwrite it).
    """
    summary = out_dir / SUMMARY
    if not summary.is_file():
        return set()
    try:
        listed = _summary_folders(summary)
    except (OSError, UnicodeDecodeError, ValueError, csv.Error):
        raise OutputFolderError(
            f"{summary} is not a graphvision batch summary; the batch would replace it: "
            "move it, or choose another --output-dir"
        ) from None
    root = out_dir.resolve()
    folders = {Path(folder).resolve() for folder in listed if folder}
    return {
        out_dir / folder.relative_to(root)
        for folder in folders
        if root in folder.parents and folder.is_dir()
    }


def summary_text(items: Sequence[BatchItem]) -> str:
    """``batch.csv``: file, output_dir, status, seconds, error, then every scalar output.

    ``output_dir`` names a folder that is there: it is empty for a file that has none (one
    that could not be read or failed, with no earlier run kept in its ``history/``, or that
    did not run), so every folder the summary names can be opened; the items say the same
    (:func:`~graphvision.execution.batch_write.settle_folders`)."""
    rows = [
        {
            "file": str(item.file),
            "output_dir": "" if item.output_dir is None else str(item.output_dir),
            "status": item.status,
            "seconds": round(item.seconds, 4),
            "error": item.error,
            **item.scalars,
        }
        for item in items
    ]
    columns = list(dict.fromkeys(key for row in rows for key in row))
    text = io.StringIO(newline="")
    writer = csv.DictWriter(text, fieldnames=columns)
    writer.writeheader()
    writer.writerows(rows)
    return text.getvalue()


def checked_folders(out_dir: Path, folders: list[Path], outputs: Collection[str]) -> set[Path]:
    """Refuse, before anything runs, a batch that would replace files graphvision did not
    write (in an item folder, or ``batch.csv`` and ``batch.html``), write through a link,
    or replace a run it cannot keep; return the folders of files that left the batch."""
    present = _names_in(out_dir)  # a folder whose first part is not there is new: no check
    depth = len(out_dir.parts)
    for k, folder in enumerate(folders):  # (the first always: it checks the output names)
        below = folder.parts[depth:]
        if folder.parts[:depth] != out_dir.parts or not below or ".." in below:
            raise OutputFolderError(f"{folder} is not a folder below {out_dir}")
        if k == 0 or _folded(below[0]) in present:
            check_output_folder(folder, outputs, out_dir)
    check_folder_files(out_dir, BATCH_FILES)
    previous = previous_folders(out_dir)
    current = {folder.resolve() for folder in folders} if previous else set()
    stale = {folder for folder in previous if folder.resolve() not in current}
    for folder in stale:  # its run is kept in its history/ before its files go
        check_output_folder(folder, (), out_dir)
    return stale


def _names_in(folder: Path) -> set[str]:
    """The names in ``folder`` (none when it is not a folder), in one listing, as
    :func:`_folded` gives them."""
    try:
        return {_folded(name) for name in os.listdir(folder)}
    except OSError:
        return set()


def _folded(name: str) -> str:
    """``name`` as a case-insensitive file system (macOS's, Windows') compares names: a
    folder made there under another case or Unicode form would be the same folder."""
    return unicodedata.normalize("NFC", name).casefold()
