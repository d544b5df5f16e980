"""A batch's stop under kills and a second Ctrl-C (issue 26 item 1, adversary findings): a
writer killed while it writes is not waited for and its folder is cleared; a folder written
whole whose result never reached the client counts as done; a file whose worker died has a
whole folder or none; a second Ctrl-C during the stop still leaves batch.csv."""

from __future__ import annotations

import csv
import json
import multiprocessing
import os
import signal
import threading
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest

import graphvision as gv
from graphvision.execution import batch_signals, batch_stop, file_task
from graphvision.execution.batch_files import NO_PAGES, BatchItem
from graphvision.execution.batch_run import BatchRun
from graphvision.execution.batch_stop import StopFlag
from graphvision.execution.executors import SyncExecutor, WorkerDiedError
from graphvision.execution.provenance import file_sha256

from .test_batch import _counting_graph, photo

DEADLINE = 60.0


def _one_file_batch(tmp_path: Path, pool: Any = None) -> BatchRun:
    """A batch of one file whose folder holds output ``score``, not started."""
    folder = tmp_path / "out" / "a"
    pool = SyncExecutor() if pool is None else pool
    batch = BatchRun(
        gv.Graph("g"), [tmp_path / "a.png"], [folder], "image", {}, pool, True, NO_PAGES,
        tmp_path / "out",
    )  # fmt: skip
    batch.options = {"outputs": ["score"]}
    batch.stop.create()  # as its files start
    return batch


def _dask() -> Any:
    """A Dask executor, not started (its workers may be on other machines)."""
    pytest.importorskip("distributed", reason="Dask is an optional extra: graphvision[dask]")
    from graphvision.execution.dask import DaskExecutor

    return DaskExecutor()


def _write_half_and_hang(flag: StopFlag, folder: Path, ready: Any) -> None:
    """A worker killed while it writes: it claims the folder, places one output file and its
    staging folder, then hangs until killed."""
    with flag.writing(folder, None) as claim:
        assert claim
        (folder / ".graphvision-writing-x").mkdir(parents=True)
        (folder / "score.json").write_text("1.0")
        ready.set()
        threading.Event().wait(DEADLINE)


@pytest.mark.parametrize("executor", ["processes", "dask"])
def test_a_writer_killed_while_it_writes_is_not_waited_for_and_its_folder_is_cleared(
    tmp_path, executor
):
    """kill -9, or SIGTERM to the process group (a Dask worker forked from the client ends
    on it at once): the staging folder and the outputs it placed are removed."""
    batch = _one_file_batch(tmp_path, _dask() if executor == "dask" else None)
    if executor == "dask":  # on the storage the workers write to, not this machine's /tmp
        assert Path(batch.stop.folder).parent == tmp_path / "out"
    folder = batch.folders[0]
    fork = multiprocessing.get_context("fork")
    ready = fork.Event()
    writer = fork.Process(target=_write_half_and_hang, args=(batch.stop, folder, ready))
    writer.start()
    try:
        assert ready.wait(DEADLINE)
        assert batch.stop.writer_alive(StopFlag.name(folder))  # locked while it lives
        os.kill(writer.pid, signal.SIGKILL)  # kill -9: it never drops its claim itself
        writer.join(DEADLINE)
        stopping = ThreadPoolExecutor(1).submit(batch.stop_writers)
        assert stopping.result(timeout=DEADLINE / 2) == {}  # not waited for: not counted
        assert not folder.exists()  # nothing half-written, no staging folder
    finally:
        writer.kill()
        batch.remove_stop_flag()


def test_a_folder_written_whole_whose_result_never_came_counts_as_done(tmp_path):
    batch = _one_file_batch(tmp_path)
    folder = batch.folders[0]
    written = BatchItem(tmp_path / "a.png", folder, seconds=0.5, scalars={"score": 2.5})
    try:
        with batch_stop.writing(batch.stop, folder, None) as claim:  # as a worker writes it
            assert claim
            folder.mkdir(parents=True)
            (folder / "record.json").write_text("{}")
            claim.written(written)
        # its worker died before sending the result (SIGTERM to the process group)
        assert batch.stop_writers() == {0: written}  # whole, so counted, with its outputs
    finally:
        batch.remove_stop_flag()


class _DyingWorkers:
    """'Workers' whose file tasks travel as to other processes; the task of ``b`` writes
    its folder, then its worker dies; ``c``'s finds no worker that can start; ``d``'s worker
    dies half-way through its folder, twice."""

    encodes_values = True
    name = "dying"
    width = 2

    def __init__(self) -> None:
        self._pool = ThreadPoolExecutor(2)

    def submit(self, fn: Any, /, *args: Any) -> Future:
        name = Path(str(args[1])).name if len(args) > 1 else ""
        if name == "c.png":
            failed: Future = Future()
            failed.set_exception(WorkerDiedError("no worker process could start (EOFError())"))
            return failed
        return self._pool.submit(self._run, name, fn, *args)

    @staticmethod
    def _run(name: str, fn: Any, *args: Any) -> Any:
        if name == "d.png":  # half its folder, then killed: its claim left unlocked, empty
            folder, job = Path(args[2]), args[0]
            (folder / ".graphvision-writing-x").mkdir(parents=True)
            (folder / "score.json").write_text("0.5")
            Path(job.stop.folder, StopFlag.name(args[2])).touch()
            raise WorkerDiedError("died (killed, or out of memory), and again when retried alone")
        outcome = fn(*args)
        if name == "b.png":  # written whole, then killed before its result was sent
            raise WorkerDiedError("died (killed, or out of memory), and again when retried alone")
        return outcome

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        self._pool.shutdown(wait=wait, cancel_futures=cancel_futures)


def test_a_file_whose_worker_died_has_a_whole_folder_or_none(tmp_path):
    graph, registry, _ = _counting_graph(tmp_path)
    files = [photo(tmp_path / "in" / f"{name}.png", 50) for name in "abcd"]
    batch = gv.run_batch(
        graph,
        [str(f) for f in files],
        input="image",
        output_dir=tmp_path / "out",
        registry=registry,
        executor=_DyingWorkers(),
        client_files=False,
    )
    status = {item.file.name: item.status for item in batch.items}
    assert status == {"a.png": "ok", "b.png": "ok", "c.png": "ok", "d.png": "failed"}
    for name in "abc":  # b: whole before its worker died; c: run again in the client
        assert (tmp_path / "out" / name / "record.json").is_file()
    assert not (tmp_path / "out" / "d").exists()  # failed: no folder, not half of one
    record = json.loads((tmp_path / "out" / "c" / "record.json").read_text())
    assert record["executor"] == "dying, in the client: no worker could start"


class _HeldWorkers(_DyingWorkers):
    """'Workers' whose file ``c`` stays in the middle of writing its folder until released."""

    def submit(self, fn: Any, /, *args: Any) -> Future:
        return self._pool.submit(fn, *args)


def test_a_second_ctrl_c_during_the_stop_still_leaves_batch_csv(tmp_path, monkeypatch):
    graph, registry, _ = _counting_graph(tmp_path)
    files = [photo(tmp_path / "in" / f"{name}.png", 50) for name in "abc"]
    writing_c, raised, handled, release = (threading.Event() for _ in range(4))
    finish = file_task.finish_item

    def slow_finish(item: BatchItem, *args: Any) -> BatchItem:
        if item.file.name == "c.png":  # c is being written when the batch stops
            writing_c.set()
            assert release.wait(DEADLINE)
        return finish(item, *args)

    def second_ctrl_c() -> None:
        assert raised.wait(DEADLINE)
        os.kill(os.getpid(), signal.SIGINT)  # while the client waits for c's writer
        handled.wait(DEADLINE)
        release.set()

    def stop_at_second(number: int, total: int, item: Any) -> None:
        if number == 2:  # a and b done, c being written: Ctrl-C
            assert writing_c.wait(DEADLINE)
            threading.Thread(target=second_ctrl_c).start()
            raise KeyboardInterrupt

    raise_ = StopFlag.raise_
    monkeypatch.setattr(file_task, "finish_item", slow_finish)
    monkeypatch.setattr(StopFlag, "raise_", lambda flag: (raise_(flag), raised.set()))
    monkeypatch.setattr(batch_signals, "_ignored", lambda *_: handled.set())
    before = signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a terminal
    try:
        with pytest.raises(KeyboardInterrupt):
            gv.run_batch(
                graph,
                [str(f) for f in files],
                input="image",
                output_dir=tmp_path / "out",
                registry=registry,
                executor=_HeldWorkers(),
                client_files=False,
                files_at_once=2,
                on_item=stop_at_second,
            )
    finally:
        release.set()
        signal.signal(signal.SIGINT, before)
    rows = {r["file"]: r["status"] for r in csv.DictReader((tmp_path / "out" / "batch.csv").open())}
    assert rows == {str(f): "ok" for f in files}  # c, being written, finished and counted


def test_a_write_cut_short_in_the_client_leaves_its_claim_for_the_stop_to_clear(tmp_path):
    batch = _one_file_batch(tmp_path)
    assert batch.stop is not None
    folder = batch.folders[0]
    # Ctrl-C while the main thread writes the folder
    with pytest.raises(KeyboardInterrupt), batch.stop.writing(folder, None) as claim:
        assert claim
        folder.mkdir(parents=True)
        (folder / "score.json").write_text("1.0")
        raise KeyboardInterrupt
    try:
        assert batch.stop.left() == {StopFlag.name(folder): None}  # half-written, no writer
        assert batch.stop_writers() == {}
        assert not folder.exists()
    finally:
        batch.remove_stop_flag()


def test_a_writer_killed_just_after_placing_its_record_leaves_no_folder(tmp_path):
    """Its folder is whole, but its claim never got the file's item (SIGTERM to the process
    group, between the record's move into place and the claim's update): the run there is
    the writer's, not a previous one to keep, so it goes and the file is listed not done."""
    batch = _one_file_batch(tmp_path)
    folder = batch.folders[0]
    with pytest.raises(KeyboardInterrupt), batch.stop.writing(folder, None) as claim:
        assert claim
        folder.mkdir(parents=True)
        (folder / "score.json").write_text("1.0")
        digest = file_sha256(folder / "score.json")
        record = {"files": {"score": ["score.json"]}, "file_sha256": {"score.json": digest}}
        (folder / "record.json").write_text(json.dumps(record))  # moved in last: whole
        raise KeyboardInterrupt  # killed before claim.written
    try:
        assert batch.stop_writers() == {}
        assert not folder.exists()
    finally:
        batch.remove_stop_flag()
