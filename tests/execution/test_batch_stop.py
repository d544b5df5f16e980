"""A stopped batch's folders are whole or absent, as batch.csv says
(graphvision.execution.batch_stop): a file a worker finishes after the stop writes nothing,
and one being written when the batch stops is finished and counted."""

from __future__ import annotations

import csv
import errno
import threading
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any

import pytest

import graphvision as gv
from graphvision.execution import batch_stop, flag_folder
from graphvision.execution.batch_files import BatchItem
from graphvision.execution.batch_stop import StopFlag

from .test_batch import _counting_graph, photo


class _Workers:
    """Two 'worker' threads whose file tasks travel as to other processes
    (``encodes_values``); the task of the file named ``held`` waits for ``gate``."""

    encodes_values = True
    name = "held"
    width = 2

    def __init__(self, held: str) -> None:
        self.held, self.gate = held, threading.Event()
        self.tasks: list[Future] = []
        self._pool = ThreadPoolExecutor(2)

    def submit(self, fn: Any, /, *args: Any) -> Future:
        def run() -> Any:
            if len(args) > 1 and str(args[1]).endswith(self.held) and not self.gate.wait(60):
                raise TimeoutError("never released")
            return fn(*args)

        self.tasks.append(self._pool.submit(run))
        return self.tasks[-1]

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        self.gate.set()
        self._pool.shutdown(wait=wait, cancel_futures=cancel_futures)


def test_a_file_a_worker_finishes_after_the_stop_leaves_no_folder(tmp_path):
    graph, registry, _ = _counting_graph(tmp_path)
    files = [photo(tmp_path / "in" / f"{name}.png", 50) for name in "abc"]
    pool = _Workers("c.png")

    def stop_at_second(number: int, total: int, item: Any) -> None:
        if number == 2:  # a and b done, c still on its worker: Ctrl-C
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        gv.run_batch(
            graph,
            [str(f) for f in files],
            input="image",
            output_dir=tmp_path / "out",
            registry=registry,
            cache=None,
            executor=pool,
            on_item=stop_at_second,
        )
    pool.shutdown()  # c's worker goes on, after the client has summarised
    for task in pool.tasks:
        task.result(timeout=60)
    rows = {r["file"]: r["status"] for r in csv.DictReader((tmp_path / "out" / "batch.csv").open())}
    assert rows == {str(files[0]): "ok", str(files[1]): "ok", str(files[2]): "interrupted"}
    assert (tmp_path / "out" / "a" / "record.json").is_file()
    assert not (tmp_path / "out" / "c").exists()  # not whole: absent


def test_a_folder_being_written_at_the_stop_is_finished_and_counted(tmp_path):
    flag = StopFlag.make()
    finished: set[str] = set()
    claimed, release = threading.Event(), threading.Event()

    def writer() -> None:
        with flag.writing(tmp_path / "a", None) as claim:
            assert claim  # claimed before the stop: it writes
            claimed.set()
            release.wait(60)
            finished.add(StopFlag.name(tmp_path / "a"))  # its folder is written
            claim.written(BatchItem(tmp_path / "a.png", tmp_path / "a"))

    thread = threading.Thread(target=writer)
    thread.start()
    try:
        assert claimed.wait(60)
        flag.raise_()
        with flag.writing(tmp_path / "b", None) as allowed:
            assert not allowed  # after the stop: nothing is started
        threading.Timer(0.05, release.set).start()
        flag.wait()
        assert finished == {StopFlag.name(tmp_path / "a")}  # waited for, not left half-way
        assert flag.left()[StopFlag.name(tmp_path / "a")].status == "ok"  # counted from it
    finally:
        release.set()
        thread.join()
        flag.remove()


def test_without_locks_a_writer_still_writes_and_its_claim_is_live_until_written(
    tmp_path, monkeypatch
):
    """A Dask batch's claims are on the storage its workers share: one without locks (flock
    fails there) must not stop every folder from being written."""

    def no_locks(fd: int, operation: int) -> None:
        raise OSError(errno.ENOLCK, "No locks available")

    monkeypatch.setattr(batch_stop.fcntl, "flock", no_locks)
    flag = StopFlag.make(tmp_path / "out")
    name = StopFlag.name(tmp_path / "out" / "a")
    try:
        with flag.writing(tmp_path / "out" / "a", None) as claim:
            assert claim  # it writes, unlocked
            assert flag.writer_alive(name)  # taken for a live writer's: waited for
            claim.written(BatchItem(tmp_path / "a.png", tmp_path / "out" / "a"))
        assert not flag.writer_alive(name)
        assert flag.left()[name].status == "ok"
    finally:
        flag.remove()


def test_a_flag_left_by_a_killed_client_is_removed_by_the_next_batch_and_nothing_else(
    tmp_path,
):
    """A client killed with ``kill -9`` leaves its flag; the next flag made beside it removes
    it (its owner lock is free), and keeps a live client's flag, a flag without an owner
    file, a folder that is no flag, and folders named like flags that hold more than a
    flag does."""
    import os
    import signal
    import subprocess
    import sys
    import time

    made = tmp_path / "made"
    child = subprocess.Popen(
        [sys.executable, "-c",
         "import sys, time; from pathlib import Path\n"
         "from graphvision.execution.batch_stop import StopFlag\n"
         "flag = StopFlag.make(Path(sys.argv[1]))\n"
         "Path(sys.argv[2]).write_text(flag.folder)\n"
         "time.sleep(60)", str(tmp_path), str(made)],
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 30  # for the child to make its flag
        while not (made.exists() and made.read_text()):
            assert child.poll() is None and time.monotonic() < deadline, "no flag made"
            time.sleep(0.05)
        dead = made.read_text()
    finally:
        os.kill(child.pid, signal.SIGKILL)
        child.wait(timeout=30)
    alive = StopFlag.make(tmp_path)
    unowned = tmp_path / f"{batch_stop.STOP_FOLDER}0123456789ab"
    unowned.mkdir()
    other = tmp_path / "photo-1"
    other.mkdir()
    decoys = [  # named like flags, with an unlocked "owner": not flags all the same
        tmp_path / f"{batch_stop.STOP_FOLDER}notes",  # no token
        tmp_path / f"{batch_stop.STOP_FOLDER}0123456789cd",  # a file of the user's beside
        tmp_path / f"{batch_stop.STOP_FOLDER}0123456789ef",  # "owner" a folder
    ]
    for decoy in decoys:
        decoy.mkdir()
    (decoys[0] / "owner").touch()
    (decoys[1] / "owner").touch()
    (decoys[1] / "precious.txt").write_text("keep")
    (decoys[2] / "owner").mkdir()
    newest = StopFlag.make(tmp_path)
    try:
        assert not os.path.exists(dead)
        for kept in (alive.folder, unowned, other, newest.folder, *decoys):
            assert os.path.isdir(kept), kept
    finally:
        alive.remove()
        newest.remove()


def test_a_local_batchs_flag_and_claims_are_made_in_memory_where_the_machine_has_it(
    tmp_path, monkeypatch
):
    """A claim is a file made per batch file: in memory (``/dev/shm``) it costs no disk; a
    machine without one keeps the flag in the system's temporary folder."""
    import tempfile
    from pathlib import Path

    memory, folder = tmp_path / "shm", tmp_path / "out" / "photo-1"
    memory.mkdir()
    monkeypatch.setattr(flag_folder, "MEMORY", str(memory))
    flag = StopFlag.make()
    try:
        assert Path(flag.folder).parent == memory
        with flag.writing(folder, None) as claim:
            assert claim and flag.claims() == {StopFlag.name(folder)}
            assert flag.writer_alive(StopFlag.name(folder))  # locked while it writes
    finally:
        flag.remove()
    assert list(memory.iterdir()) == []
    monkeypatch.setattr(flag_folder, "MEMORY", str(tmp_path / "no-shm"))
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    assert Path(StopFlag.planned().folder).parent == tmp_path / "tmp"


def test_a_full_memory_folder_leaves_the_flag_in_the_temporary_folder(tmp_path, monkeypatch):
    """``/dev/shm`` whose mode allows a file but whose space does not (Docker's 64 MB one,
    full): the flag goes where a file can be made."""
    import tempfile
    from pathlib import Path

    memory = tmp_path / "shm"
    memory.mkdir()
    monkeypatch.setattr(flag_folder, "MEMORY", str(memory))
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    made = tempfile.mkstemp

    def full(*args: Any, dir: Any = None, **kwargs: Any) -> Any:
        if dir is not None and Path(dir).is_relative_to(memory):
            raise OSError(errno.ENOSPC, "No space left on device")
        return made(*args, dir=dir, **kwargs)

    monkeypatch.setattr(tempfile, "mkstemp", full)
    assert Path(StopFlag.planned().folder).parent == tmp_path


def _batch_of_three(tmp_path):
    graph, registry, _ = _counting_graph(tmp_path)
    files = [str(photo(tmp_path / "in" / f"p{k}.png", 40 * k)) for k in range(3)]
    return graph, registry, files


def test_a_file_whose_claim_cannot_be_made_fails_naming_why(tmp_path, monkeypatch):
    """The flag is there but full: each file fails with the reason, none is 'ok' without
    its folder (they were, and the batch exited 0)."""
    import tempfile

    graph, registry, files = _batch_of_three(tmp_path)
    made = tempfile.mkstemp

    def full(*args: Any, prefix: Any = None, **kwargs: Any) -> Any:
        if prefix == ".claim-":
            raise OSError(errno.ENOSPC, "No space left on device")
        return made(*args, prefix=prefix, **kwargs)

    monkeypatch.setattr(tempfile, "mkstemp", full)
    result = gv.run_batch(
        graph, files, input="image", output_dir=tmp_path / "out", registry=registry,
        executor="sync", cache=None,
    )  # fmt: skip
    for item in result.items:
        assert item.status == "failed" and item.output_dir is None  # none made
        folder = tmp_path / "out" / item.file.stem
        assert f"cannot mark {folder} as being written in" in item.error
        assert "No space left on device" in item.error


def test_files_after_their_flag_was_removed_are_interrupted_not_ok(tmp_path, monkeypatch):
    """Someone empties the flag's folder mid-batch (systemd removes a user's /dev/shm files
    at logout): the files after it are 'interrupted' and unwritten, not 'ok'."""
    import shutil

    memory = tmp_path / "shm"  # this batch's alone
    memory.mkdir()
    monkeypatch.setattr(flag_folder, "MEMORY", str(memory))
    graph, registry, files = _batch_of_three(tmp_path)

    def remove_flags(number: int, total: int, item: BatchItem) -> None:
        if number == 1:
            for flag in memory.glob("graphvision-batch-*"):
                shutil.rmtree(flag)

    result = gv.run_batch(
        graph,
        files,
        input="image",
        output_dir=tmp_path / "out",
        registry=registry,
        executor="sync",
        cache=None,
        on_item=remove_flags,
    )
    statuses = [item.status for item in result.items]
    assert statuses[0] == "ok" and statuses[1:] == ["interrupted", "interrupted"]
    assert [item.output_dir for item in result.items] == [tmp_path / "out" / "p0", None, None]


def _bytes_refused_in(folder: Any, monkeypatch: pytest.MonkeyPatch) -> None:
    """A full tmpfs: a file is made in ``folder``, then its first byte refused."""
    import os

    made, names = os.write, {}
    opened = batch_stop.tempfile.mkstemp

    def mkstemp(*args: Any, **kwargs: Any) -> Any:
        fd, name = opened(*args, **kwargs)
        names[fd] = name
        return fd, name

    def write(fd: int, data: bytes) -> int:
        if str(names.get(fd, "")).startswith(str(folder)):
            raise OSError(errno.ENOSPC, "No space left on device")
        return made(fd, data)

    monkeypatch.setattr(batch_stop.tempfile, "mkstemp", mkstemp)
    monkeypatch.setattr(os, "write", write)


def test_a_memory_folder_that_makes_files_but_refuses_bytes_is_not_used(tmp_path, monkeypatch):
    import tempfile
    from pathlib import Path

    memory = tmp_path / "shm"
    memory.mkdir()
    monkeypatch.setattr(flag_folder, "MEMORY", str(memory))
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    _bytes_refused_in(memory, monkeypatch)
    assert Path(StopFlag.planned().folder).parent == tmp_path
    assert list(memory.iterdir()) == []  # its probe removed


def test_a_claim_whose_bytes_are_refused_fails_its_file_naming_why(tmp_path, monkeypatch):
    """/dev/shm filled while the batch runs: the claim's file is made, its bytes refused;
    the file fails with the reason (it was 'interrupted', re-running never helped)."""
    memory = tmp_path / "shm"
    memory.mkdir()
    monkeypatch.setattr(flag_folder, "MEMORY", str(memory))
    graph, registry, files = _batch_of_three(tmp_path)
    _bytes_refused_in(memory / "graphvision-batch-", monkeypatch)  # the flag's, not the probe's
    result = gv.run_batch(
        graph, files, input="image", output_dir=tmp_path / "out", registry=registry,
        executor="sync", cache=None,
    )  # fmt: skip
    for item in result.items:
        assert item.status == "failed" and item.output_dir is None  # none made
        folder = tmp_path / "out" / item.file.stem
        assert f"cannot mark {folder} as being written in" in item.error
        assert "No space left on device" in item.error
