"""Which files of a run's output folder are graphvision's, and where a run may write.

A run folder's ``record.json`` lists the files its run wrote: that list is how
the next run knows what is its to replace (after keeping it in ``history/``,
:mod:`graphvision.execution.history`). A run is refused before it starts, with
the path and what is wrong, when it would replace a file that is not
graphvision's or could not keep the run it replaces:

- a file named like one the run writes that no record there lists;
- a record that is a symbolic link, or not a record listing its files;
- a file the record lists that is now a link, a folder or a pipe (graphvision
  wrote a file there; replacing the link would lose it without a trace);
- a ``history`` that is not graphvision's (a link, a file, a folder without its
  marker) while there is a previous run to keep in it;
- for a batch's item folder, a symbolic link (or a file) on the way from the
  batch's folder down to it: a batch writes only inside its folder.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable
from pathlib import Path

from graphvision.errors import OutputFolderError
from graphvision.execution.history import history_problem

__all__ = [
    "OUTPUT_SUFFIXES",
    "RECORD",
    "REPORT",
    "REPORT_HTML",
    "check_output_folder",
    "owned_files",
    "refuse_links",
    "refuse_replacing",
    "write_file",
]

RECORD, REPORT, REPORT_HTML = "record.json", "report.md", "report.html"
OUTPUT_SUFFIXES = (".png", ".npy", ".npz", ".json", ".csv", ".ply")  # the built-in writers'


def owned_files(directory: Path) -> set[str]:
    """The file names in ``directory`` that a previous graphvision run wrote (its record's list).

    Raises
    ------
    OutputFolderError
        When ``directory`` has a ``record.json`` that is a symbolic link, or not a
        graphvision record listing its files (so what is ours there cannot be known).
    """
    record = directory / RECORD
    if record.is_symlink():
        raise OutputFolderError(
            f"{record} is a symbolic link to {os.readlink(record)}, not the record a run "
            "wrote there, so which files there are a previous run's is unknown; remove it, "
            "or choose another --output-dir"
        )
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


def check_output_folder(
    directory: Path, outputs: Iterable[str], inside: Path | None = None, *, absent: bool = False
) -> set[str]:
    """Refuse, before a run, a folder where the run's files would replace files not
    graphvision's, or replace the previous run without keeping it.

    A file counts as the run's when its name is ``record.json``, ``report.md``
    or an output name with a suffix a port type writes. Returns the previous
    run's files (:func:`owned_files`).

    Parameters
    ----------
    directory : Path
        The run's folder.
    outputs : iterable of str
        The names of the run's outputs.
    inside : Path, optional
        The batch's folder, when ``directory`` is one of its item folders: no
        symbolic link may lie between the two (:func:`refuse_links`).
    absent : bool
        Whether the caller found nothing at ``directory`` (not even a link) just before:
        then it is not looked at again.

    Raises
    ------
    OutputFolderError
        Naming the folder and the first file in the way, or an output named
        ``record`` (its file would be the record's).
    """
    if inside is not None:
        refuse_links(inside, directory, absent=absent)
    stems = set(outputs)
    there = not absent and os.path.lexists(directory)  # new (a batch's mostly): nothing in the way
    if there and directory.exists() and not directory.is_dir():
        raise OutputFolderError(f"output folder {directory} is a file")
    if Path(RECORD).stem in stems:
        raise OutputFolderError(
            f"output '{Path(RECORD).stem}' cannot be written to an output folder: its file "
            f"would be {RECORD}, the run record; rename the output"
        )
    if not there:
        return set()
    owned = owned_files(directory)
    if not directory.is_dir():
        return owned
    for path in sorted(directory.iterdir()):
        ours = path.name in (RECORD, REPORT, REPORT_HTML) or (
            path.stem in stems and path.suffix in OUTPUT_SUFFIXES
        )
        if ours and path.name not in owned:
            refuse_replacing(directory, path.name)
    if owned:
        _refuse_unkept(directory, owned)
    return owned


def _refuse_unkept(directory: Path, owned: set[str]) -> None:
    """Refuse a previous run whose files could not all be kept in ``history/``: one that
    the record lists is no longer a file, or ``history`` is not graphvision's."""
    for name in sorted(owned):
        path = directory / name
        if os.path.lexists(path) and (path.is_symlink() or not path.is_file()):
            raise OutputFolderError(
                f"{path} is {_what(path)}, where the previous run wrote a file; the run "
                "would replace it without keeping it in history/: move it, or choose "
                "another --output-dir"
            )
    problem = history_problem(directory)
    if problem:
        raise OutputFolderError(
            f"{problem}, so the previous run there ({directory / RECORD}) could not be kept "
            "before this run replaces it: move it, or choose another --output-dir"
        )


def _what(path: Path) -> str:
    if path.is_symlink():
        return f"a symbolic link to {os.readlink(path)}"
    return "a folder" if path.is_dir() else "not a regular file"


def refuse_links(inside: Path, directory: Path, *, absent: bool = False) -> None:
    """Refuse a symbolic link, or a file, on the way from ``inside`` (a batch's folder) down
    to ``directory`` (one of its item folders), ``directory`` included (unless ``absent``
    says the caller has just found nothing there): writing there would write outside
    ``inside``, or fail half-way.

    Raises
    ------
    OutputFolderError
        Naming the link and where it leads, or the file.
    """
    path = inside
    for part in directory.relative_to(inside).parts:
        path = path / part
        if absent and path == directory:
            return
        if path.is_symlink():
            raise OutputFolderError(
                f"{path} is a symbolic link to {os.readlink(path)}: the batch would write "
                f"{directory} through it, outside its output folder {inside}; remove the "
                "link, or choose another --output-dir"
            )
        if path != directory and path.exists() and not path.is_dir():
            raise OutputFolderError(
                f"{path} is a file, where the batch makes the folder {directory}: move it, "
                "or choose another --output-dir"
            )


def refuse_replacing(directory: Path, name: str) -> None:
    """Refuse a run that would replace ``name`` in ``directory``, a file no record lists."""
    raise OutputFolderError(
        f"output folder {directory} holds {name}, which no graphvision record there lists; "
        "the run would replace it: move it, or choose another --output-dir"
    )


_NEW_FILE = os.O_WRONLY | os.O_CREAT | os.O_TRUNC | getattr(os, "O_BINARY", 0)  # (Windows: binary)


def write_file(path: Path, data: bytes) -> None:
    """Write ``data`` to the file ``path`` (made, or emptied first), as ``open(path, "wb")``
    does, in three system calls (open, write, close) where a file object made six or seven
    (``fstat``, the ``ioctl`` asking whether it is a terminal, ``lseek``): each one releases
    the GIL and takes it again, a wait for it when another thread holds it (a batch on
    threads writes three pages per file)."""
    descriptor = os.open(path, _NEW_FILE, 0o666)
    try:
        view = memoryview(data)
        while view:  # (a regular file takes it all at once, but a signal may cut it short)
            view = view[os.write(descriptor, view) :]
    except OSError as error:  # os.write's error names no file (a full disk, ulimit -f)
        raise OSError(error.errno, error.strerror, str(path)) from None
    finally:
        os.close(descriptor)
