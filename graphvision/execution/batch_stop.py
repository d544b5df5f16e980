"""A stopped batch's folders: whole or absent, as ``batch.csv`` says.

Stopped (Ctrl-C, SIGTERM), a batch on processes used to summarise at once
and exit, while its workers (which ignore Ctrl-C) went on: a file a worker
finished after the summary got a whole folder that ``batch.csv`` called
``interrupted``, and a worker that was writing a folder when the client exited
ended half-way (it ends with the client), leaving outputs without their
record or an empty folder.

Here the client and the processes writing folders (its workers, its own file
lanes) share a :class:`StopFlag`, a folder of the client's on this machine (in
memory, ``/dev/shm``, where there is one: a claim is a file made per batch file):

- a writer claims the folder it is about to write: a ``writing-`` file named
  after it, which appears already locked by the writer (``fcntl.flock``; the
  operating system drops the lock when the writer's process dies, however it
  dies), then looks at the flag: when the batch has stopped, it writes
  nothing and drops its claim;
- a writer that has written the folder whole writes the file's item (status,
  seconds, scalar outputs) into its claim before unlocking it; the client
  drops the claim once it has the file's result;
- the stopping client raises the flag, then waits while any claim is locked
  (a live writer: its folder will be whole), never for a dead one. A claim
  left unlocked holds the item of a whole folder (its writer died, or its
  result did not reach the client yet: the client counts it as finished, from
  the claim) or nothing (its writer died half-way: the client removes what it
  wrote, :func:`~graphvision.execution.folders.clear_unfinished`).

A writer that found the flag down after claiming had claimed before the flag
was raised, so the client sees its claim. A flag folder that is gone counts as
raised. On Dask, whose workers may be on other machines, the flag is a hidden
folder in the batch's output folder (``.graphvision-stop-*``), on the storage
the workers write the files' folders to (a claim's lock is then the shared
file system's: ``flock`` on a local disk, NFS's locks over NFS); a task's
files that start after the stop are not run at all.

The flag's own folder holds an ``owner`` file that the client keeps locked
while the batch runs. A client killed with ``kill -9`` cannot remove its
flag; the next batch that makes a flag beside it removes every sibling flag
whose owner lock it can take (its client is dead), and nothing else.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
import stat
import string
import tempfile
import time
import uuid
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from graphvision.execution.batch_files import BatchItem
from graphvision.execution.flag_folder import local_folder
from graphvision.execution.owned import RECORD

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows: a claim is a live writer's until it is written
    fcntl = None  # type: ignore[assignment]

__all__ = ["INTERRUPTED", "NOT_STARTED", "STOP_FOLDER", "Claim", "StopFlag", "writing"]

INTERRUPTED = "the batch stopped while this file ran; re-run the batch to finish it"
NOT_STARTED = "the batch stopped before this file started"

STOP_FOLDER = ".graphvision-stop-"  # a Dask batch's flag, in its output folder
_STOPPED = "stopped"
_CLAIM = "writing-"
_RECORD_KEY = "record_before"  # in a claim: the folder's record.json digest when claimed
_TOKEN = 12  # hexadecimal digits ending a flag's name
_OWNER = "owner"  # in a flag's folder, locked by its client while the batch runs
_FLAG_FILES = {_OWNER, _STOPPED}  # what a flag's folder holds: these, and claims
_FLAG_PREFIXES = (_CLAIM, ".claim-", ".owner-")
_OWNED: dict[str, int] = {}  # this process's flags: folder -> the owner file's descriptor


@dataclass
class Claim:
    """A writer's claim on a folder (see the module docstring); true when it may write.
    ``record`` is the SHA-256 of the folder's ``record.json`` when it was claimed (None:
    there was none), noted in the claim from the start."""

    allowed: bool
    path: Path | None = None
    fd: int = -1
    done: bool = False
    record: str | None = None

    def __bool__(self) -> bool:
        return self.allowed

    def written(self, item: BatchItem) -> None:
        """The folder is written (whole, or cleared when the file failed): ``item`` is kept
        in the claim, for a client whose result from this writer never comes (written over
        what the claim held: never an empty claim, even if killed now). What it held, the
        claim's own field, is shorter than the item, which holds that field too: nothing
        of it is left past the item's end, so the claim is not truncated (a system call
        fewer, each releasing the GIL and taking it back)."""
        self.done = True
        if self.fd < 0:
            return
        os.pwrite(self.fd, json.dumps({**_item_json(item), _RECORD_KEY: self.record}).encode(), 0)


def _item_json(item: BatchItem) -> dict:
    kept = {name: getattr(item, name) for name in ("status", "seconds", "error", "scalars")}
    return {"file": str(item.file), "output_dir": str(item.output_dir), **kept}


def _unwritten(fd: int) -> bool:
    """Whether the claim open as ``fd`` holds no file's item yet."""
    return _json_item(os.pread(fd, 1 << 16, 0).decode(errors="replace")) is None


def _record_digest(folder: str | Path) -> str | None:
    """The SHA-256 of ``folder``'s ``record.json``, or None when it has none."""
    try:
        return hashlib.sha256(Path(folder, RECORD).read_bytes()).hexdigest()
    except OSError:
        return None


def _json_item(text: str) -> BatchItem | None:
    try:
        data = json.loads(text)
        return BatchItem(
            Path(data["file"]), Path(data["output_dir"]), str(data["status"]),
            float(data["seconds"]), str(data["error"]), dict(data["scalars"]),
        )  # fmt: skip
    except (ValueError, KeyError, TypeError):
        return None


def _is_flag(folder: Path, prefix: str) -> bool:
    """Whether ``folder`` is a stop flag: named ``prefix`` and a token, a real folder whose
    ``owner`` is a plain file and which holds nothing but a flag's own files."""
    token = folder.name[len(prefix) :]
    if len(token) != _TOKEN or token.strip(string.hexdigits.lower()) or folder.is_symlink():
        return False
    try:
        if not stat.S_ISREG(os.lstat(folder / _OWNER).st_mode):
            return False
        names = os.listdir(folder)
    except OSError:
        return False
    return all(name in _FLAG_FILES or name.startswith(_FLAG_PREFIXES) for name in names)


class StopFlag:
    """The flag of one batch, in ``folder`` (see the module docstring); picklable."""

    def __init__(self, folder: str) -> None:
        self.folder = folder

    @classmethod
    def planned(cls, inside: Path | None = None) -> StopFlag:
        """A new flag, made by :meth:`create`: a folder on this machine
        (:func:`~graphvision.execution.flag_folder.local_folder`), or a hidden one ``inside``
        a folder (a Dask batch's output folder, which its workers share)."""
        token = uuid.uuid4().hex[:_TOKEN]
        if inside is None:
            return cls(str(Path(local_folder(), f"graphvision-batch-{token}")))
        return cls(str(inside / f"{STOP_FOLDER}{token}"))

    @classmethod
    def make(cls, inside: Path | None = None) -> StopFlag:
        flag = cls.planned(inside)
        flag.create()
        return flag

    def create(self) -> None:
        """Make the flag's folder (and the folders it is in), down: no writer may write
        before (a batch makes it as its files start, so a Ctrl-C before leaves nothing)."""
        Path(self.folder).parent.mkdir(parents=True, exist_ok=True)
        Path(self.folder).mkdir(mode=0o700)
        if fcntl is not None:
            with contextlib.suppress(OSError):  # a file system without locks: nothing to sweep
                self._own()
                self._sweep()

    def _own(self) -> None:
        """The owner file, locked before it has its name (a sweep never sees it unlocked
        while this client lives)."""
        fd, temp = tempfile.mkstemp(prefix=".owner-", dir=self.folder)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            os.replace(temp, Path(self.folder, _OWNER))
        except OSError:
            os.close(fd)
            raise
        _OWNED[self.folder] = fd

    def _sweep(self) -> None:
        """Remove the flags beside this one (same name but for the token) whose owner lock
        can be taken: their clients died before removing them. A flag without an owner file
        (being made, or made by an older version) is left alone."""
        here = Path(self.folder)
        prefix = here.name[:-_TOKEN]
        for other in here.parent.glob(f"{prefix}*"):
            if other == here or not _is_flag(other, prefix):
                continue
            try:
                fd = os.open(other / _OWNER, os.O_RDONLY | os.O_NOFOLLOW)
            except OSError:
                continue
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                continue  # its client is alive
            finally:
                os.close(fd)
            shutil.rmtree(other, ignore_errors=True)

    def raise_(self) -> None:
        """The batch has stopped: no writer starts a folder from now on."""
        with contextlib.suppress(OSError):
            Path(self.folder, _STOPPED).touch()

    def is_raised(self) -> bool:
        folder = Path(self.folder)
        return not folder.is_dir() or (folder / _STOPPED).exists()

    @staticmethod
    def name(folder: str | Path) -> str:
        """What a claim on the output folder ``folder`` is called."""
        return _CLAIM + hashlib.blake2b(str(folder).encode(), digest_size=10).hexdigest()

    def _locked_claim(self, folder: str | Path, record: str | None) -> tuple[Path, int] | None:
        """A new claim on ``folder`` noting its ``record`` digest, locked by this writer before
        it has its name (so no reader ever sees it unlocked while its writer lives); None
        when the flag is gone (the batch has ended, or someone removed it).

        Raises
        ------
        OSError
            When the flag is there but no claim can be made in it (its file system is
            full), naming the folder: the file fails with it, rather than being left
            unwritten under the name of a batch that stopped.
        """
        try:
            fd, temp = tempfile.mkstemp(prefix=".claim-", dir=self.folder)
        except OSError as error:
            self._raise_unless_gone(folder, error)
            return None
        try:
            os.write(fd, json.dumps({_RECORD_KEY: record}).encode())
            if fcntl is not None:  # a file system without locks: alive until written
                with contextlib.suppress(OSError):
                    fcntl.flock(fd, fcntl.LOCK_EX)
            claim = Path(self.folder, self.name(folder))
            os.replace(temp, claim)
        except OSError as error:  # (a full file system makes the file, then refuses its bytes)
            os.close(fd)
            with contextlib.suppress(OSError):
                os.unlink(temp)
            self._raise_unless_gone(folder, error)
            return None
        return claim, fd

    def _raise_unless_gone(self, folder: str | Path, error: OSError) -> None:
        """The claim's ``error``, naming the folder, unless the flag is gone (no claim)."""
        if os.path.isdir(self.folder):
            raise OSError(
                error.errno,
                f"cannot mark {folder} as being written in {self.folder}: {error.strerror}",
            ) from None

    @contextlib.contextmanager
    def writing(self, folder: str | Path, stopped: Callable[[], bool] | None) -> Iterator[Claim]:
        """Whether to write ``folder`` now (false once the batch has stopped, by the flag or
        by ``stopped()``); claimed while the caller writes it. The caller calls
        :meth:`Claim.written` once the folder is written; else the claim is dropped."""
        record = _record_digest(folder)
        locked = self._locked_claim(folder, record)
        if locked is None:
            yield Claim(False)
            return
        path, fd = locked
        allowed = not (self.is_raised() or (stopped is not None and stopped()))
        claim = Claim(allowed, path, fd, record=record)
        try:
            if not claim:
                path.unlink(missing_ok=True)
            yield claim
            if not claim.done:  # nothing written: nothing to count
                path.unlink(missing_ok=True)
        finally:  # cut short (Ctrl-C in the client's main thread): left for the client to clear
            os.close(fd)  # the lock goes with it

    def written_whole(self, folder: str | Path) -> BatchItem | None:
        """The item a writer that is gone kept in its claim on ``folder`` (the folder is
        whole: a task run again after its worker died need not write it again), else None."""
        name = self.name(folder)
        try:
            item = _json_item(Path(self.folder, name).read_text())
        except OSError:  # no claim (every first run): not written in this batch
            return None
        return None if item is None or self.writer_alive(name) else item

    def dropped(self, folder: str | Path) -> None:
        """The client has the result of ``folder``'s file: its claim is no longer needed."""
        with contextlib.suppress(OSError):
            Path(self.folder, self.name(folder)).unlink()

    def in_worker(self) -> StopFlag:
        """This flag for a worker that runs the first file the client's way: it drops no
        claim (the client does, once it has the result; stopped before, it counts the
        folder from the claim; dropped here, a whole folder was listed ``interrupted``)."""
        return _WorkersFlag(self.folder)

    def claims(self) -> set[str]:
        with contextlib.suppress(OSError):
            return {p.name for p in Path(self.folder).glob(_CLAIM + "*")}
        return set()

    def writer_alive(self, name: str) -> bool:
        """Whether the claim ``name`` is locked: its writer lives and is writing. Where there
        are no locks (Windows, a file system without them), a claim is taken for a live
        writer's until it holds its file's item (a dead writer is waited for, up to the
        deadline of :meth:`wait`)."""
        try:
            fd = os.open(Path(self.folder, name), os.O_RDONLY)
        except OSError:
            return False  # dropped
        try:
            if fcntl is None:  # pragma: no cover - Windows
                return _unwritten(fd)
            fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            return True
        except OSError:  # no locks on this file system
            return _unwritten(fd)
        finally:
            os.close(fd)
        return False

    def wait(self, seconds: float = 30.0) -> None:
        """After :meth:`raise_`: wait while a claim is locked (its writer is writing), never
        for a writer that has died; ``seconds`` at most."""
        deadline = time.monotonic() + seconds
        waiting = self.claims()
        while waiting and time.monotonic() < deadline:
            waiting = {name for name in waiting if self.writer_alive(name)}
            if waiting:
                time.sleep(0.005)

    def left(self) -> dict[str, BatchItem | None]:
        """The claims no writer holds now, each with the item its writer kept (its folder
        whole) or None (its writer died half-way through the folder)."""
        found: dict[str, BatchItem | None] = {}
        for name in self.claims():
            if self.writer_alive(name):
                continue
            with contextlib.suppress(OSError):
                found[name] = _json_item(Path(self.folder, name).read_text())
        return found

    def placed_record(self, name: str, folder: str | Path) -> bool:
        """Whether the writer of claim ``name``, which died half-way (:meth:`left` gives it
        None), had replaced ``folder``'s ``record.json`` (the last file a run moves into
        place): the run there is then that writer's, not the previous one."""
        try:
            before = json.loads(Path(self.folder, name).read_text())[_RECORD_KEY]
        except (OSError, ValueError, KeyError, TypeError):
            return False  # not known: the record there is taken for the previous run's
        now = _record_digest(folder)
        return now is not None and now != before

    def remove(self) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)
        fd = _OWNED.pop(self.folder, None)
        if fd is not None:
            os.close(fd)


class _WorkersFlag(StopFlag):
    def dropped(self, folder: str | Path) -> None:  # (:meth:`StopFlag.in_worker`)
        """Left to the client."""


@contextlib.contextmanager
def writing(
    stop: StopFlag | None, folder: str | Path, stopped: Callable[[], bool] | None
) -> Iterator[Claim]:
    """Whether to write a file's ``folder`` now, claimed meanwhile when there is a flag
    (:meth:`StopFlag.writing`); without one (a file task run outside a batch), whether
    ``stopped()`` is still false."""
    if stop is None:
        yield Claim(not (stopped is not None and stopped()))
        return
    with stop.writing(folder, stopped) as claim:
        yield claim
