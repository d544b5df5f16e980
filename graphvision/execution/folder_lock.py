"""One writer at a time per output folder.

Two runs or batches writing into one folder at once would undo each other: each
replaces the other's files, the last ``batch.csv`` wins, and a batch that clears
what a killed run left in a file's folder could remove files the other is still
writing. So whatever writes an output folder (``graphvision run -d``, a batch,
a sweep) holds an exclusive lock on it while it writes: ``fcntl.flock`` on the
file ``.graphvision-lock`` in the folder, which names the process holding it.
A second writer is refused at once, with that name, before it runs anything.

The lock belongs to the open file, so a writer killed by ``kill -9`` or a
power cut holds nothing: the file it leaves behind is taken over by the next
writer, and removed when that one ends. Where the file system has no
``flock`` (Windows), nothing is locked.
"""

from __future__ import annotations

import contextlib
import os
import stat
from collections.abc import Iterator
from pathlib import Path

from graphvision.errors import OutputFolderError
from graphvision.execution.folders import missing_folders, remove_empty_folders

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]

__all__ = ["LOCK_FILE", "only_writer"]

LOCK_FILE = ".graphvision-lock"


@contextlib.contextmanager
def only_writer(directory: Path, doing: str = "run") -> Iterator[None]:
    """Hold ``directory``'s writer lock for the ``with`` block (``doing``: what for, as the
    refusal of a second writer names it). The folder is made if it does not exist, and
    removed at the end with the parents made for it if the block left them empty.

    Raises
    ------
    OutputFolderError
        When another process holds the lock (naming it and what it is doing), or when
        the lock's name in ``directory`` is taken by something that is not a plain file.
    """
    if fcntl is None:  # pragma: no cover - Windows
        yield
        return
    made = missing_folders(directory)
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / LOCK_FILE
    try:
        descriptor = _locked(path, directory)
    except BaseException:
        remove_empty_folders(made)
        raise
    try:
        try:
            os.ftruncate(descriptor, 0)
            os.pwrite(descriptor, f"{os.getpid()} {doing}\n".encode(), 0)
        except OSError as error:  # a full disk: say where
            raise OutputFolderError(
                f"{directory}: cannot write its lock file {LOCK_FILE} ({error.strerror}): "
                "free space there or choose another output folder"
            ) from None
        yield
    finally:
        with contextlib.suppress(OSError):
            if _same_file(descriptor, path):
                path.unlink()
        os.close(descriptor)
        remove_empty_folders(made)


def _locked(path: Path, directory: Path) -> int:
    """An open descriptor of ``path`` holding its exclusive lock."""
    flags = os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_NONBLOCK  # (a pipe: no wait)
    while True:
        try:
            descriptor = os.open(path, flags, 0o644)
        except OSError as error:
            if os.path.lexists(path):  # a link or a folder by that name: not ours to use
                raise OutputFolderError(_not_ours(directory, str(error.strerror))) from None
            raise OutputFolderError(
                f"output folder {directory} cannot be written ({error.strerror})"
            ) from None
        found = os.fstat(descriptor)
        if not stat.S_ISREG(found.st_mode) or found.st_nlink != 1:  # a pipe, a hard link
            os.close(descriptor)  # (to a file of the user's): nothing written nor removed
            kind = "another name of a file" if stat.S_ISREG(found.st_mode) else "not a file"
            raise OutputFolderError(_not_ours(directory, kind))
        held = os.pread(descriptor, 200, 0).split(maxsplit=1)
        if held and not held[0].isdigit():  # a lock holds "<pid> <what>", or nothing yet
            os.close(descriptor)
            raise OutputFolderError(_not_ours(directory, "it holds something else"))
        try:
            fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(descriptor, 200, 0).decode(errors="replace").split()
            os.close(descriptor)
            raise OutputFolderError(_busy(directory, holder)) from None
        # its last holder may have removed the file between our open and our lock: then
        # the lock is on a file nobody else will open, so take the one now at the path
        if _same_file(descriptor, path):
            return descriptor
        os.close(descriptor)


def _same_file(descriptor: int, path: Path) -> bool:
    try:
        found = path.stat(follow_symlinks=False)
    except FileNotFoundError:
        return False
    held = os.fstat(descriptor)
    return (found.st_dev, found.st_ino) == (held.st_dev, held.st_ino)


def _not_ours(directory: Path, why: str) -> str:
    return (
        f"output folder {directory} holds {LOCK_FILE}, which is not graphvision's lock file "
        f"({why}): remove it"
    )


def _busy(directory: Path, holder: list[str]) -> str:
    who = f"process {holder[0]} ({' '.join(holder[1:])})" if holder else "another process"
    return (
        f"output folder {directory} is being written by {who}; two writers in one folder "
        "would replace each other's files: wait for it to finish, or choose another "
        "--output-dir"
    )
