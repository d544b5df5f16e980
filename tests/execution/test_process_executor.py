"""The processes executor when a worker dies (graphvision.execution.process_executor): a
broken task fails only once the pool's other workers are gone, so that a batch settling
its files by their claims never clears a folder that a dying worker still writes."""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from pathlib import Path

import pytest

from graphvision.execution.executors import WorkerDiedError, make_executor
from graphvision.execution.process_executor import _after_exit


@pytest.fixture
def alone(monkeypatch):
    """No thread but this one, so that the pool's workers are forks of this process."""
    monkeypatch.setattr(threading, "enumerate", lambda: [threading.current_thread()])
    parallel = sys.modules.get("numba.np.ufunc.parallel")
    if parallel is not None:
        monkeypatch.setattr(parallel, "_is_initialized", False, raising=False)


def _running(pid: int) -> bool:
    """Whether the process can still run its code: it has its memory. An exiting process
    gives its memory up before it closes its files (which readies its sentinel) and before
    it becomes a zombie, so /proc's state alone would still say running there."""
    try:
        pages = int(Path(f"/proc/{pid}/statm").read_text().split()[0])
    except (FileNotFoundError, ProcessLookupError):
        return False
    return pages > 0


def _write_for_long(marks: str) -> int:
    """A task still writing when the other worker dies: its pid, then 60 s asleep."""
    Path(marks, "pid").write_text(str(os.getpid()))
    time.sleep(60)
    return os.getpid()


def _die_once_the_other_writes(marks: str) -> None:
    """Kill this worker once the other task runs."""
    for _ in range(1200):
        if Path(marks, "pid").exists():
            os.kill(os.getpid(), signal.SIGKILL)
        time.sleep(0.05)


# Neither is run again when its pool breaks (as a batch's task of several files is not).
_write_for_long.settles_its_files = True  # type: ignore[attr-defined]
_die_once_the_other_writes.settles_its_files = True  # type: ignore[attr-defined]


@pytest.mark.skipif(not Path("/proc/self/statm").exists(), reason="reads /proc")
def test_a_broken_task_fails_only_once_the_other_workers_are_gone(alone, tmp_path):
    pool = make_executor("processes", 2)
    try:
        assert pool.fork_workers()  # type: ignore[attr-defined]
        writing = pool.submit(_write_for_long, str(tmp_path))
        dying = pool.submit(_die_once_the_other_writes, str(tmp_path))
        other_ran, told = [], threading.Event()

        def tell(_):  # when the failure is told: whether the other worker still ran
            other_ran.append(_running(int((tmp_path / "pid").read_text())))
            told.set()

        dying.add_done_callback(tell)
        with pytest.raises(WorkerDiedError, match="running a task of several files"):
            dying.result(timeout=60)
        assert told.wait(timeout=60)
        assert other_ran == [False]  # ended by the pool before the failure was told
        with pytest.raises(WorkerDiedError, match="running a task of several files"):
            writing.result(timeout=60)
    finally:
        pool.shutdown(wait=False)


def test_after_exit_waits_for_every_process_and_no_longer(tmp_path):
    import multiprocessing

    start = multiprocessing.get_context("fork")
    sleeper = start.Process(target=time.sleep, args=(0.5,))
    sleeper.start()
    told = threading.Event()
    began = time.monotonic()
    _after_exit([sleeper], told.set)
    assert not told.is_set()  # the process still runs
    assert told.wait(timeout=30)
    assert time.monotonic() - began >= 0.4
    assert sleeper.exitcode is None or sleeper.exitcode == 0
    sleeper.join()
    done = threading.Event()
    _after_exit([sleeper], done.set)  # gone already: at once, in this thread
    assert done.is_set()
