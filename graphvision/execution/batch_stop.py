"""A stopped batch's folders: whole or absent, as ``batch.csv`` says.

Stopped (Ctrl-C, SIGTERM), a batch on processes used to summarise at once
and exit, while its workers (which ignore Ctrl-C) went on: a file a worker
finished after the summary got a whole folder that ``batch.csv`` called
``interrupted``, and a worker that was writing a folder when the client exited
ended half-way (it ends with the client), leaving outputs without their
record or an empty folder.

Here the client and the processes writing folders (its workers, its own file
lanes) share a :class:`StopFlag`, a folder of the client's on this machine:

- a writer claims the folder it is about to write (a ``writing-`` file named
  after it), then looks at the flag: when the batch has stopped, it writes
  nothing and drops its claim;
- the stopping client raises the flag, then waits for the claims made before
  it to be dropped (each one's folder then whole) and counts those files as
  finished, with their results.

A writer that found the flag down after claiming had claimed before the flag
was raised, so the client sees its claim. A flag folder that is gone counts as
raised. On Dask, whose workers may be on other machines, there is no flag: a
stopped batch leaves its workers' files to them.
"""

from __future__ import annotations

import contextlib
import hashlib
import shutil
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path

__all__ = ["INTERRUPTED", "StopFlag", "writing"]

INTERRUPTED = "the batch stopped while this file ran; re-run the batch to finish it"

_STOPPED = "stopped"
_CLAIM = "writing-"


class StopFlag:
    """The flag of one batch, in ``folder`` (see the module docstring); picklable."""

    def __init__(self, folder: str) -> None:
        self.folder = folder

    @classmethod
    def make(cls) -> StopFlag:
        return cls(tempfile.mkdtemp(prefix="graphvision-batch-"))

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

    @contextlib.contextmanager
    def writing(self, folder: str | Path, stopped: Callable[[], bool] | None) -> Iterator[bool]:
        """Whether to write ``folder`` now (False once the batch has stopped, by the flag or
        by ``stopped()``); claimed while the caller writes it."""
        claim = Path(self.folder, self.name(folder))
        try:
            claim.touch()
        except OSError:  # the flag's folder is gone: the batch has ended
            yield False
            return
        try:
            yield not (self.is_raised() or (stopped is not None and stopped()))
        finally:
            claim.unlink(missing_ok=True)

    def claims(self) -> set[str]:
        with contextlib.suppress(OSError):
            return {p.name for p in Path(self.folder).glob(_CLAIM + "*")}
        return set()

    def wait(self, finished: Callable[[set[str]], set[str]], seconds: float = 30.0) -> None:
        """After :meth:`raise_`: wait for the claims made until now to be dropped and for
        ``finished(names)`` (the claims whose files the client has the results of) to hold
        them all, ``seconds`` at most."""
        waiting = self.claims()
        deadline = time.monotonic() + seconds
        while waiting and time.monotonic() < deadline:
            waiting = (waiting & self.claims()) | (waiting - finished(waiting))
            time.sleep(0.005)

    def remove(self) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)


@contextlib.contextmanager
def writing(
    stop: StopFlag | None, folder: str | Path, stopped: Callable[[], bool] | None
) -> Iterator[bool]:
    """Whether to write a file's ``folder`` now, claimed meanwhile when there is a flag
    (:meth:`StopFlag.writing`); without one (Dask), whether ``stopped()`` is still false."""
    if stop is None:
        yield not (stopped is not None and stopped())
        return
    with stop.writing(folder, stopped) as allowed:
        yield allowed
