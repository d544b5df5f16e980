"""The files graphvision writes beside run folders (a batch's ``batch.csv`` and
``batch.html``; a sweep's ``sweep.csv``, pages and charts), and how it knows, before
replacing one, that it wrote it.

A manifest in the folder (``batch.json``, ``sweep.json``) lists each file with the
SHA-256 of what was written. A file of a writer's names is replaced only when the
manifest lists it with the digest of what it holds now; one that no manifest lists,
one that changed since (a user's page saved over it, a ``batch.csv`` edited in a
spreadsheet), a symbolic link or a folder in its place is refused, naming it, before
anything runs. Why digests and not a name list, a marker or a signature: a name says a
writer once wrote a file so called, not that the file there now is that file; a marker
has no place in every format (a CSV) and stays in a copy someone edits; a signature
(``batch.csv``'s header) is matched by anyone's file of the same shape. A run folder's
``record.json`` is the same kind of list (names and digests).

Replacing is done in three steps, so that a writer killed at any point leaves a folder
the next one accepts: the manifest first lists the old and the new digest of every file
about to change, then each file is replaced whole (a temporary file beside it and a
rename: a link in its place is replaced, never written through), the files no longer
written are removed, and the manifest lists the new digests only. Every file is
written whole beside its place before the first step, so a file that cannot be written
(a full disk, ``ulimit -f``) changes nothing: the folder and its manifest stay as they
were, and the error, an ``OSError`` (:class:`FileWriteError`), names the file.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
import stat
import threading
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from graphvision.errors import FileWriteError, OutputFolderError
from graphvision.execution.provenance import file_sha256

__all__ = [
    "FolderFiles",
    "check_folder_files",
    "replace_bytes",
    "replace_folder_files",
]

Digests = frozenset[str] | None  # the digests a listed file may have; None: any (no digests)


def _nothing(path: Path) -> bool:
    return False


@dataclass(frozen=True)
class FolderFiles:
    """The files one kind of writer puts in a folder.

    ``manifest`` is the manifest's name; ``label`` the writer (``batch``,
    ``sweep``), written in the manifest and named in messages; ``names`` says
    whether a file name is one the writer writes; ``written_before`` recognises
    a file such a writer wrote before it kept a manifest (the folder has none).
    """

    manifest: str
    label: str
    names: Callable[[str], bool]
    written_before: Callable[[Path], bool] = field(default=_nothing)


def check_folder_files(
    directory: Path, kind: FolderFiles, writing: Collection[str] | None = None
) -> dict[str, Digests]:
    """Refuse a folder where ``kind``'s writer would replace a file it did not write;
    return what its manifest lists (name -> digests). Given the names the writer is about
    to write (``writing``), a file of ``kind``'s names that is neither among them nor
    listed is left alone: nothing would touch it (a user's ``sweep_mine.svg``).

    Raises
    ------
    OutputFolderError
        Naming the folder and the file: the folder is a file; the manifest is a
        link or not ``kind``'s manifest; a file of ``kind``'s names is not listed,
        changed since it was written, or is a link or a folder.
    """
    return _checked_files(directory, kind, writing)[0]


def _checked_files(
    directory: Path, kind: FolderFiles, writing: Collection[str] | None = None
) -> tuple[dict[str, Digests], dict[str, str]]:
    """:func:`check_folder_files`, and the digest of each of ``kind``'s files there now
    (each file read once)."""
    if directory.exists() and not directory.is_dir():
        raise OutputFolderError(f"output folder {directory} is a file")
    if not directory.is_dir():
        return {}, {}
    manifest = directory / kind.manifest
    listed = _read_manifest(manifest, kind)
    held: dict[str, str] = {}
    for path in sorted(directory.iterdir()):
        if path.name == kind.manifest or not kind.names(path.name):
            continue
        if writing is not None and path.name not in writing and path.name not in listed:
            continue  # neither replaced nor removed
        problem = _not_written(path, listed, kind, os.path.lexists(manifest))
        if not problem:
            held[path.name] = digest = file_sha256(path)
            allowed = listed.get(path.name)  # (None: any content)
            if allowed is not None and digest not in allowed:
                problem = f"which changed since the {kind.label} wrote it"
        if problem:
            raise OutputFolderError(
                f"output folder {directory} holds {path.name}, {problem}; the {kind.label} "
                "would replace it: move it, or choose another --output-dir"
            )
    return listed, held


def _read_manifest(manifest: Path, kind: FolderFiles) -> dict[str, Digests]:
    """The manifest's list, ``{}`` when there is none; a list of names without digests
    (what a sweep wrote before digests) accepts any content."""
    if not os.path.lexists(manifest):
        return {}
    try:
        if manifest.is_symlink():
            raise ValueError("a symbolic link")
        content = json.loads(manifest.read_text(encoding="utf-8"))
        if not isinstance(content, dict) or content.get("graphvision") != kind.label:
            raise ValueError(f"not written by a {kind.label}")
        files = content.get("files")
        if isinstance(files, list) and all(isinstance(n, str) for n in files):
            listed: dict[str, Digests] = dict.fromkeys(files)
        elif isinstance(files, dict) and all(
            isinstance(d, list) and all(isinstance(x, str) for x in d) for d in files.values()
        ):
            listed = {name: frozenset(digests) for name, digests in files.items()}
        else:
            raise ValueError(f"not a {kind.label} manifest")
        if not all(kind.names(n) and n == Path(n).name for n in listed):
            raise ValueError(f"it lists a file a {kind.label} does not write")
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as error:
        raise OutputFolderError(
            f"{manifest} is not a graphvision {kind.label} manifest ({error}), so which files "
            f"there are a previous {kind.label}'s is unknown; choose another --output-dir or "
            "empty this one"
        ) from None
    return listed


def _not_written(
    path: Path, listed: dict[str, Digests], kind: FolderFiles, has_manifest: bool
) -> str:
    """Why ``path`` is not a file ``kind``'s writer wrote, by its name and kind, or ''."""
    if path.is_symlink():
        return f"a symbolic link to {os.readlink(path)}, which no {kind.label} wrote"
    if not path.is_file():
        return f"which is not a file a {kind.label} wrote"
    if path.name not in listed:
        if not has_manifest and kind.written_before(path):
            return ""
        if not has_manifest:  # (graphvision kept no manifest before 2026-11-27)
            return (
                f"and no {kind.manifest} says a {kind.label} wrote it (an earlier graphvision "
                f"kept none: if it is an earlier {kind.label}'s, delete it and the {kind.label} "
                "writes it again)"
            )
        return f"which no graphvision {kind.label} there wrote"
    return ""  # (whether it changed since: its digest, by the caller)


def replace_folder_files(
    directory: Path, kind: FolderFiles, contents: Mapping[str, str]
) -> list[Path]:
    """Write ``contents`` (file name -> text) into ``directory`` as ``kind``'s files,
    replacing the previous ones and removing those no longer written, then the manifest
    (in the three steps of the module docstring). Returns the paths written.

    All or nothing: every file is first written whole beside its place; one that cannot
    be (a full disk, a size limit) leaves the folder and its manifest as they were.

    Raises
    ------
    OutputFolderError
        As :func:`check_folder_files` (checked again here: a file may have come since).
    FileWriteError
        Naming the file that could not be written (an ``OSError``: exit 1, as any
        failure of the environment).
    """
    listed, held = _checked_files(directory, kind, contents)
    directory.mkdir(parents=True, exist_ok=True)
    _remove_dead_writers_temporaries(directory, kind)
    data = {name: text.encode("utf-8") for name, text in contents.items()}
    new = {name: _sha256(content) for name, content in data.items()}
    during = {name: {digest} for name, digest in new.items()}
    for name, digest in held.items():  # each is a file the kind wrote (checked): kept too
        during.setdefault(name, set()).add(digest)
    staged: dict[Path, Path] = {}
    try:
        for name, content in data.items():
            staged[directory / name] = _staged(directory / name, content)
        _write_manifest(directory, kind, during)  # a writer killed from here on: either is its
        for path, temp in staged.items():
            _published(temp, path)
    finally:
        for temp in staged.values():  # (a file published has none left)
            with contextlib.suppress(OSError):
                temp.unlink(missing_ok=True)
    for name in sorted(set(listed) - set(data)):
        (directory / name).unlink(missing_ok=True)
    _write_manifest(directory, kind, {name: {digest} for name, digest in new.items()})
    return list(staged)


def _remove_dead_writers_temporaries(directory: Path, kind: FolderFiles) -> None:
    """Remove the temporary files of :func:`replace_bytes` that a writer killed before its
    rename left for ``kind``'s files (``.NAME.PID.THREAD.tmp``, its process gone): one
    writer at a time holds the folder (:mod:`graphvision.execution.folder_lock`)."""
    for path in directory.glob(".*.tmp"):
        found = _TEMPORARY.fullmatch(path.name)
        if found is None or not (kind.names(found[1]) or found[1] == kind.manifest):
            continue
        if int(found[2]) != os.getpid() and not _alive(int(found[2])) and not path.is_dir():
            path.unlink(missing_ok=True)


_TEMPORARY = re.compile(r"\.(.+)\.(\d+)\.(\d+)\.tmp")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)  # (signal 0: only asks whether the process exists)
    except (ProcessLookupError, OverflowError):  # none has that number
        return False
    except PermissionError:  # another user's
        return True
    return True


def _write_manifest(directory: Path, kind: FolderFiles, files: Mapping[str, set[str]]) -> None:
    listing = {name: sorted(digests) for name, digests in sorted(files.items())}
    text = json.dumps({"graphvision": kind.label, "files": listing}, indent=1) + "\n"
    replace_bytes(directory / kind.manifest, text.encode("utf-8"))


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def replace_bytes(path: Path, data: bytes) -> None:
    """Write ``path`` whole or not at all (a temporary file beside it, then a rename: a
    link in its place is replaced, not written through).

    A file replaced keeps its permissions; a new one gets the process's default (its
    umask). The temporary file's name is this thread's own, so two threads writing the
    same path at once each publish a whole file.

    Raises
    ------
    FileWriteError
        Naming ``path``; nothing is left beside it.
    """
    temp = _staged(path, data)
    try:
        _published(temp, path)
    finally:
        with contextlib.suppress(OSError):
            temp.unlink(missing_ok=True)


def _staged(path: Path, data: bytes) -> Path:
    """The temporary file beside ``path`` holding ``data`` whole, with ``path``'s permissions
    if it exists; a FileWriteError naming ``path`` (and no temporary file left) if not."""
    temp = path.with_name(f".{path.name}.{os.getpid()}.{threading.get_ident()}.tmp")
    try:
        temp.unlink(missing_ok=True)  # a killed writer's, or a link put there: made anew
        with os.fdopen(os.open(temp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666), "wb") as out:
            out.write(data)
        with contextlib.suppress(FileNotFoundError):
            os.chmod(temp, stat.S_IMODE(path.stat().st_mode))
    except OSError as error:
        with contextlib.suppress(OSError):
            temp.unlink(missing_ok=True)
        raise FileWriteError(error.errno, error.strerror or str(error), str(path)) from None
    return temp


def _published(temp: Path, path: Path) -> None:
    """Rename ``temp`` to ``path`` (a FileWriteError naming ``path`` if it cannot be)."""
    try:
        os.replace(temp, path)
    except OSError as error:
        raise FileWriteError(error.errno, error.strerror or str(error), str(path)) from None
