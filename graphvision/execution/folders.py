"""A run's output folder: writing a run into it.

A folder holds one run and keeps its predecessors in ``history/``
(:mod:`graphvision.execution.history`). Its ``record.json`` lists the files the run wrote;
that list is how the next run knows what is its to replace, and a file that
no record lists is never replaced (the run is refused before it starts:
:mod:`graphvision.execution.owned` says which files are graphvision's).
Files are written to a hidden staging folder and moved into place, the
record last, so an interrupted run leaves the previous run's folder whole. A
batch's folder that does not exist yet is written whole as a hidden sibling (in
the batch's output folder) and renamed into place: whole or absent, and one
folder made where two were made and one removed (on a disk that discards freed
blocks, as cloud VMs' do, removing a folder cost 0.2-3 ms: a fifth of a batch
file's engine cost).
What a report page shows is not decided here: pages are writers passed in
(:data:`graphvision.views.report.RUN_PAGES`).
"""

from __future__ import annotations

import contextlib
import glob
import os
import shutil
import stat
import tempfile
import warnings
from collections.abc import Callable, Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

from graphvision.compiler.compile import CompiledGraph
from graphvision.errors import OutputFolderError
from graphvision.execution.history import Earlier, earlier_runs, keep_previous_run
from graphvision.execution.owned import (
    OUTPUT_SUFFIXES,
    RECORD,
    REPORT,
    REPORT_HTML,
    check_output_folder,
    owned_files,
    refuse_links,
    refuse_replacing,
    write_file,
)
from graphvision.execution.provenance import file_sha256
from graphvision.execution.record import RunResult
from graphvision.execution.unchanged import previous_record, unchanged_outputs
from graphvision.graph.model import NAME, output_name_problem

__all__ = [
    "STAGING",
    "RunPage",
    "clear_unfinished",
    "earlier_of",
    "missing_folders",
    "new_folder",
    "remove_empty_folders",
    "remove_owned_files",
    "retire_left_files",
    "retire_run",
    "run_folder",
    "write_outputs",
    "write_run",
]

STAGING = ".graphvision-writing-"  # prefix of the hidden folder a run's files are written to
NEW = ".graphvision-new-"  # prefix of a new output folder written whole beside its place

RunPage = Callable[[RunResult, Path], list[str]]
"""A report page writer: given a run and a folder, writes its files there and names them."""


def run_folder(directory: Path) -> Path:
    """The output folder a page writer is writing for: ``directory`` itself, the folder
    that holds it when it is the hidden staging folder of :func:`write_run`, or the folder
    it becomes when it is a new folder written beside its place (:func:`new_folder`)."""
    if directory.name.startswith(NEW):
        return directory.with_name(directory.name[len(NEW) :])
    return directory.parent if directory.name.startswith(STAGING) else directory


def earlier_of(directory: Path) -> list[Earlier]:
    """The runs kept in the history of the folder a page writer is writing for
    (:func:`run_folder`); none, without a look, for a new folder written whole beside its
    place: it is renamed only onto nothing, or onto an empty folder (an ``lstat`` fewer per
    page, each releasing the GIL and taking it back)."""
    if directory.name.startswith(NEW):
        return []
    return earlier_runs(run_folder(directory))


def new_folder(directory: Path) -> Path:
    """Where :func:`write_run` writes ``directory`` whole when it does not exist yet: a
    hidden sibling, renamed to ``directory`` once every file is in it."""
    return directory.with_name(NEW + directory.name)


def remove_owned_files(directory: Path, names: Iterable[str]) -> None:
    """Delete the listed files of a previous run (plain files directly in ``directory`` only)."""
    for name in names:
        path = directory / name
        if path.is_file() or path.is_symlink():
            path.unlink()


def retire_run(directory: Path, inside: Path) -> None:
    """The run in ``directory``, an item folder of the batch in ``inside``, kept in its
    ``history/``, then its files removed, so that nothing there looks current (a batch's
    file that failed, or left the batch); never through a link below ``inside``."""
    refuse_links(inside, directory)
    owned = owned_files(directory)
    if owned:
        keep_previous_run(directory, owned)
        remove_owned_files(directory, owned)


def retire_left_files(folders: Iterable[Path], inside: Path) -> None:
    """:func:`retire_run` for the item folders of files no longer in the batch in ``inside``
    (batch.csv has no row for them), said in one warning: their folders were emptied
    without a word."""
    left = sorted(folders)
    for folder in left:
        retire_run(folder, inside)
    if left:
        warnings.warn(
            f"{len(left)} folder(s) of files no longer in the batch (such as {left[0]}) are "
            "emptied: each one's last run is kept in its history/",
            stacklevel=3,
        )


def missing_folders(*folders: Path) -> list[Path]:
    """The folders among ``folders`` and their parents that do not exist yet, deepest first:
    what making them creates, so that a command that stops can remove them again."""
    missing: set[Path] = set()
    for folder in folders:
        path = folder
        while path not in missing and not os.path.lexists(path):  # (a link's, even broken)
            missing.add(path)
            path = path.parent
    return sorted(missing, key=lambda path: len(path.absolute().parts), reverse=True)


def remove_empty_folders(folders: Iterable[Path]) -> None:
    """Remove each of ``folders`` (deepest first) that is empty; one holding anything stays."""
    for folder in folders:
        with contextlib.suppress(OSError):
            folder.rmdir()


def clear_unfinished(directory: Path, outputs: Iterable[str], *, placed: bool = False) -> None:
    """Leave ``directory`` as it was before a writer that died half-way through it: its
    staging folders removed, the files it placed (output files of ``outputs`` and pages that
    the record there does not list, or all of them when the record's own files no longer
    match their digests, or when the writer had ``placed`` the record itself, dying just
    after: the previous run stays in ``history/``), then the folder itself when nothing is
    left in it."""
    shutil.rmtree(new_folder(directory), ignore_errors=True)
    if not directory.is_dir() or directory.is_symlink():
        return
    for left in directory.glob(f"{STAGING}*"):
        shutil.rmtree(left, ignore_errors=True)
    try:
        owned = owned_files(directory)
    except OutputFolderError:
        owned = set()
    record = previous_record(directory)
    found = record.get("file_sha256")
    digests: dict[str, Any] = found if isinstance(found, dict) else {}
    intact = (
        bool(owned)
        and not placed
        and all(
            (directory / name).is_file() and digests.get(name) == file_sha256(directory / name)
            for name in owned - {RECORD, REPORT, REPORT_HTML}
            if name in digests
        )
    )
    stems = set(outputs)
    for path in directory.iterdir():
        ours = path.name in (RECORD, REPORT, REPORT_HTML) or (
            path.stem in stems and path.suffix in OUTPUT_SUFFIXES
        )
        if ours and path.is_file() and not (intact and path.name in owned):
            path.unlink()
    remove_empty_folders([directory])


def write_run(
    result: RunResult,
    directory: Path,
    pages: Sequence[RunPage] = (),
    *,
    inside: Path | None = None,
) -> dict[str, list[str]]:
    """Write outputs, ``record.json`` and ``pages``, replacing the last run's files.

    The previous run's files are kept first in ``history/`` (see
    :mod:`graphvision.execution.history`). Everything is written to a hidden
    staging folder first, then moved into place, the record last. Returns
    output name -> file names. The record lists the files (``record.files``),
    which is how the next run knows what is its to remove.

    Parameters
    ----------
    result : RunResult
        The run.
    directory : Path
        Its output folder.
    pages : sequence of RunPage
        Writers of report pages (:data:`graphvision.views.report.RUN_PAGES`
        writes ``report.md`` and ``report.html``); each writes into the folder
        it is given and returns the names of the files it wrote there.
    inside : Path, optional
        The batch's folder, when ``directory`` is one of its item folders: a new one is
        written whole beside its place, then renamed (:func:`new_folder`), and a symbolic
        link on the way from ``inside`` down to it is refused, not written through.

    Raises
    ------
    OutputFolderError
        As :func:`~graphvision.execution.owned.check_output_folder`: a file would
        replace one no graphvision record there lists, the previous run could not be
        kept, or (with ``inside``) a link would take the writes outside the batch.

    A folder made for the run (``directory`` and its missing parents) is
    removed again when writing fails or is interrupted before a file is in it (of a
    batch's item folder, only itself: the batch made its own folder, ``inside``).
    """
    if directory.parent == inside:  # (one lstat: whether the item folder is there)
        made = [] if os.path.lexists(directory) else [directory]
    else:
        made = missing_folders(directory)
    try:
        return _write_run(result, directory, pages, inside, directory in made)
    except BaseException:
        remove_empty_folders(made)
        raise


def _write_run(
    result: RunResult,
    directory: Path,
    pages: Sequence[RunPage],
    inside: Path | None,
    absent: bool,
) -> dict[str, list[str]]:
    """:func:`write_run` into ``directory``, ``absent`` when it was not there (nothing in the
    way, no link: looked at once, where each check looked again)."""
    owned = check_output_folder(directory, result.compiled.outputs, inside, absent=absent)
    if inside is not None and absent:
        written = _write_new(result, directory, pages)
        if written is not None:
            return written
        refuse_links(inside, directory)  # what was made meanwhile is not written through
    directory.mkdir(parents=True, exist_ok=True)
    for left in directory.glob(f"{STAGING}*"):  # from a run killed while writing
        shutil.rmtree(left, ignore_errors=True)
    if owned:  # the run now in the folder stays readable, its report and its files
        keep_previous_run(directory, owned)
    kept = unchanged_outputs(result, directory, owned)
    staging = Path(tempfile.mkdtemp(prefix=STAGING, dir=directory))
    try:
        with _named_in(directory, staging):
            files, new = _write_files(result, staging, pages, kept, previous_record(directory))
        for name in new:
            if os.path.lexists(directory / name) and name not in owned:
                refuse_replacing(directory, name)
        unchanged = {name for names in kept.values() for name in names}
        remove_owned_files(directory, owned - {RECORD} - unchanged)  # the record: replaced last
        for name in new:  # the record last, in one atomic replace
            os.replace(staging / name, directory / name)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return files


@contextlib.contextmanager
def _named_in(directory: Path, staging: Path) -> Iterator[None]:
    """An ``OSError`` writing a file into ``staging`` names the file of ``directory`` it was
    written for (``out/k.npy``), not the hidden folder the run writes first."""
    try:
        yield
    except OSError as error:
        where = Path(error.filename) if isinstance(error.filename, str) else None
        if where is None or not where.is_relative_to(staging):
            raise
        shown = str(directory / where.relative_to(staging))
        raise OSError(error.errno, error.strerror, shown) from None


def _write_new(
    result: RunResult, directory: Path, pages: Sequence[RunPage]
) -> dict[str, list[str]] | None:
    """A folder that does not exist yet, written whole beside its place (:func:`new_folder`,
    a killed writer's removed first) and renamed into it; None, nothing written, when it
    cannot be (made meanwhile, a name too long): the caller writes it as an existing one."""
    staging = new_folder(directory)
    if not _made_anew(staging):
        return None
    placed = False
    try:
        with _named_in(directory, staging):
            files = _write_files(result, staging, pages, {}, {})[0]
        try:
            os.rename(staging, directory)  # onto nothing, or onto a folder made meanwhile, empty
            placed = True
        except OSError:
            if not os.path.lexists(directory):
                raise
            return None  # made meanwhile, not empty: written as an existing one
    finally:
        if not placed:  # the write failed, was cut short, or is done again
            shutil.rmtree(staging, ignore_errors=True)
    return files


def _made_anew(staging: Path) -> bool:
    """Make the empty folder ``staging`` (a killed writer's removed first, its parent made when
    missing), False when it cannot be: one ``mkdir`` in a batch, where four calls each released
    the GIL and took it again."""
    for _ in range(2):
        try:
            staging.mkdir()
            return True
        except FileExistsError:
            shutil.rmtree(staging, ignore_errors=True)
        except FileNotFoundError:
            with contextlib.suppress(OSError):
                staging.parent.mkdir(parents=True, exist_ok=True)
        except OSError:
            return False
    return False


def _write_files(
    result: RunResult,
    staging: Path,
    pages: Sequence[RunPage],
    kept: dict[str, list[str]],
    previous: dict[str, Any],
) -> tuple[dict[str, list[str]], list[str]]:
    """The run's changed outputs (those not ``kept`` from the ``previous`` record), its
    record and its pages, written to ``staging``: output name -> file names, and the names
    written there (outputs, pages, the record last)."""
    changed = {name: v for name, v in result.outputs.items() if name not in kept}
    written = write_outputs(result.compiled, changed, staging, made=True)
    digests = {f: file_sha256(staging / f) for names in written.values() for f in names}
    for names in kept.values():
        digests.update({f: previous["file_sha256"][f] for f in names})
    files = {name: kept.get(name) or written[name] for name in result.outputs}
    result.record.files = files
    result.record.file_sha256 = digests
    write_file(staging / RECORD, f"{result.record.to_json()}\n".encode())  # (ASCII)
    shown = [name for page in pages for name in page(result, staging)]
    return files, [name for names in written.values() for name in names] + shown + [RECORD]


def write_outputs(
    compiled: CompiledGraph, outputs: dict[str, Any], directory: Path, *, made: bool = False
) -> dict[str, list[str]]:
    """Write every produced output to ``directory`` (made first, unless ``made`` says the
    caller has just made it: a run's staging folder); return output name -> file names."""
    if not made and not directory.is_dir():
        directory.mkdir(parents=True, exist_ok=True)
    written = {}
    for name, value in outputs.items():
        if not NAME.match(name):  # compile_graph refuses these; a port type may not add any
            raise OutputFolderError(output_name_problem(name))
        kind = compiled.output_type(name)
        try:
            files = kind.write(value, directory / name)
        except OSError as error:  # a port type's writer (Pillow's) may name no file
            if error.filename is not None:
                raise
            begun = next(directory.glob(f"{glob.escape(name)}.*"), directory / name)
            raise OSError(error.errno, error.strerror or str(error), str(begun)) from None
        for file in files:
            if file.parent != directory or not _plain_file(file):
                raise OutputFolderError(
                    f"port type {kind.type_name()} wrote output '{name}' as {file}, which is "
                    f"not a plain file directly in {directory}"
                )
        written[name] = [f.name for f in files]
    return written


def _plain_file(path: Path) -> bool:
    """Whether ``path`` is a regular file, not a link to one (one ``lstat``)."""
    try:
        return stat.S_ISREG(os.lstat(path).st_mode)
    except OSError:
        return False
