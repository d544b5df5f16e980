"""A batch on processes runs every file on workers forked from the client, the first one
included (graphvision.execution.batch_forked): a node that kills its process on the
batch's first file fails that file alone, the others complete and batch.csv is written
(issue 26 item 1; the client used to run that file and die with it)."""

from __future__ import annotations

import csv
import json
import multiprocessing
import os
import signal
import threading
import time
from typing import Any

import pytest

from graphvision.execution.file_workers import FileWorkers

from .test_batch import photo
from .test_batch_groups import _scored_on_processes
from .test_batch_workers import _no_parallel_layer

KILLING_PLUGIN = '''
import os
import signal

import numpy as np

from graphvision import Float, Image, node


@node("killing.score")
def score(image: Image) -> Float:
    """The image's mean; a process other than the test's given the image of level 77 ends
    itself as KILL_BY says."""
    mean = float(np.mean(image))
    if round(mean * 255) == 77 and os.getpid() != int(os.environ["CLIENT_PID"]):
        if os.environ["KILL_BY"] == "exit":
            os._exit(3)
        os.kill(os.getpid(), getattr(signal, os.environ["KILL_BY"]))
    return mean
'''


@pytest.fixture
def alone(monkeypatch):
    """No thread but this one (earlier tests of this process may have left some): the
    batch forks its workers from the client (its plugin runs no numba code)."""
    monkeypatch.setattr(threading, "enumerate", lambda: [threading.current_thread()])
    _no_parallel_layer(monkeypatch)


@pytest.mark.parametrize(
    ("kill_by", "said"),
    [
        ("exit", "it exited with status 3"),
        ("SIGKILL", "killed by SIGKILL"),
        ("SIGSEGV", "crashed in native code: SIGSEGV"),
    ],
)
def test_a_node_that_kills_its_process_on_the_first_file_fails_that_file_alone(
    tmp_path, monkeypatch, alone, kill_by, said
):
    monkeypatch.setenv("CLIENT_PID", str(os.getpid()))  # never this process: the test's
    monkeypatch.setenv("KILL_BY", kill_by)
    levels = [77] + [10 + 3 * k for k in range(1, 12)]
    batch = _scored_on_processes(tmp_path, KILLING_PLUGIN, "killing", levels)
    status = [item.status for item in batch.items]
    assert status == ["failed"] + ["ok"] * 11, batch.items
    error = batch.items[0].error
    assert error.startswith("WorkerDiedError: the worker process running this file died")
    assert said in error and "__main__" not in error  # a fork imports no script
    assert "again when retried alone" in error
    assert batch.items[0].seconds > 0  # the retry's, until its worker died (it said 0.0)
    assert not (tmp_path / "out" / "00").exists()  # no half of a folder
    with (tmp_path / "out" / "batch.csv").open() as summary:
        rows = {row["output_dir"]: row["status"] for row in csv.DictReader(summary)}
    assert sorted(rows.values()) == ["failed"] + ["ok"] * 11
    for item, level in zip(batch.items[1:], levels[1:], strict=True):
        assert item.scalars["score"] == pytest.approx(level / 255.0, abs=1e-6)


def test_the_first_file_runs_node_by_node_on_a_worker(tmp_path, monkeypatch, alone):
    """Its record says where it ran; the files after it run in tasks of several files."""
    monkeypatch.setenv("CLIENT_PID", str(os.getpid()))
    monkeypatch.setenv("KILL_BY", "exit")
    batch = _scored_on_processes(tmp_path, KILLING_PLUGIN, "killing", [20, 30, 40, 50])
    records = [json.loads((i.output_dir / "record.json").read_text()) for i in batch.items]
    executors = [record["executor"] for record in records]
    assert executors[0] == "processes, first file on a worker"
    assert set(executors[1:]) == {"processes, up to 8 files a task"}
    assert [item.scalars["score"] for item in batch.items] == pytest.approx(
        [level / 255.0 for level in (20, 30, 40, 50)], abs=1e-6
    )


def _answer(state: Any, payload: Any) -> Any:
    """A worker's task: ``payload`` back with the worker's state, or its exit when asked."""
    if payload == "exit":
        os._exit(5)
    if payload == "raise":
        raise ValueError("no such thing")
    return payload, state


def test_a_dead_workers_task_is_seen_on_its_sentinel_and_the_other_goes_on():
    workers = FileWorkers(multiprocessing.get_context("fork"))
    first, second = workers.start("one"), workers.start("two")
    try:
        workers.send(first, "task a", _answer, "exit")
        workers.send(second, "task b", _answer, 7)
        workers.send(second, "task c", _answer, "raise")
        answers: list[Any] = []
        dead: list[Any] = []
        while len(answers) < 2 or not dead:
            found, ended = workers.answers()
            answers += found
            dead += ended
        assert [(task, answer) for _, task, answer in answers[:1]] == [("task b", (7, "two"))]
        assert answers[1][1] == "task c" and isinstance(answers[1][2], ValueError)
        assert str(answers[1][2]) == "no such thing"
        assert dead == [first] and first.held == ["task a"]  # what it ran, unanswered
        assert first.process.exitcode == 5
        assert workers.workers == [second]  # the other goes on
        workers.send(second, "task d", _answer, 8)
        assert workers.answers()[0][0][1:] == ("task d", (8, "two"))
    finally:
        workers.shutdown()
    assert second.process._closed  # type: ignore[attr-defined]  # joined


def test_a_worker_ignores_ctrl_c_and_ends_on_sigterm():
    workers = FileWorkers(multiprocessing.get_context("fork"))
    worker = workers.start()
    try:
        workers.send(worker, "ready", _answer, 1)
        assert workers.answers()[0][0][1] == "ready"  # set up: its signal handlers too
        os.kill(worker.process.pid, signal.SIGINT)
        workers.send(worker, "after Ctrl-C", _answer, 2)
        assert workers.answers()[0][0][1:] == ("after Ctrl-C", (2, None))
        os.kill(worker.process.pid, signal.SIGTERM)
        found, dead = workers.answers()
        assert (found, dead) == ([], [worker]) and worker.process.exitcode == -signal.SIGTERM
    finally:
        workers.shutdown()


STOPPING_PLUGIN = '''
import os
import signal
import time

import numpy as np

from graphvision import Float, Image, node


@node("stopping.score")
def score(image: Image) -> Float:
    """The image's mean; the worker given the image of level 77 sends Ctrl-C to the client,
    then takes a second more."""
    mean = float(np.mean(image))
    if round(mean * 255) == 77 and os.getpid() != int(os.environ["CLIENT_PID"]):
        os.kill(int(os.environ["CLIENT_PID"]), signal.SIGINT)
        time.sleep(1.0)
    return mean
'''


def test_files_waiting_in_a_workers_pipe_when_the_batch_stops_are_not_run(
    tmp_path, monkeypatch, alone
):
    """One worker, stopped by its first task after the first file (files 1-8) while the
    next task waits in its pipe: that task's files never started (they were listed
    interrupted); the files of the task it ran wrote nothing."""
    import graphvision as gv

    monkeypatch.setenv("CLIENT_PID", str(os.getpid()))
    plugin = tmp_path / "stopping.py"
    plugin.write_text(STOPPING_PLUGIN)
    graph = gv.Graph("stopping")
    graph.output("score", graph.add("score", "stopping.score", image=graph.input("image", "Image")))
    levels = [10 + 3 * k for k in range(40)]
    levels[1] = 77
    files = [str(photo(tmp_path / "in" / f"{k:02d}.png", level)) for k, level in enumerate(levels)]
    before = signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a terminal
    try:
        with pytest.raises(KeyboardInterrupt):
            gv.run_batch(
                graph, files, input="image", output_dir=tmp_path / "out",
                registry=gv.discover([plugin]), executor="processes", workers=1,
            )  # fmt: skip
    finally:
        signal.signal(signal.SIGINT, before)
    with (tmp_path / "out" / "batch.csv").open() as summary:
        status = [row["status"] for row in csv.DictReader(summary)]
    for k, said in enumerate(status[1:], start=1):  # each folder absent, as batch.csv says
        assert not (tmp_path / "out" / f"{k:02d}").exists() and said != "ok", (k, status)
    assert status[1:9] == ["interrupted"] * 8  # the task it ran
    assert status[9:] == ["not run"] * 31, status  # the next one waited in its pipe


def test_an_executor_given_to_several_batches_keeps_only_the_workers_still_running(tmp_path, alone):
    """Its list of batches' workers (joined at its shutdown) used to grow by one a batch."""
    import graphvision as gv

    plugin = tmp_path / "stopping.py"
    plugin.write_text(STOPPING_PLUGIN)
    graph = gv.Graph("stopping")
    graph.output("score", graph.add("score", "stopping.score", image=graph.input("image", "Image")))
    files = [str(photo(tmp_path / "in" / f"{k}.png", 20 + k)) for k in range(4)]
    executor = gv.make_executor("processes", 2)
    try:
        for run in range(3):
            batch = gv.run_batch(
                graph, files, input="image", output_dir=tmp_path / f"out{run}",
                registry=gv.discover([plugin]), executor=executor,
            )  # fmt: skip
            assert [item.status for item in batch.items] == ["ok"] * 4
            assert len(executor.file_workers) == 1  # the batch before had ended: joined
            for process in [p for workers in executor.file_workers for p in workers.ended]:
                process.join(timeout=30)  # each exits once told to
    finally:
        executor.shutdown()


def test_the_first_files_whole_folder_counts_when_the_batch_stops_before_its_answer(
    tmp_path, monkeypatch, alone
):
    """The first file's worker has written its folder whole and the client stops (Ctrl-C)
    before the worker's answer reaches it: the file is ``ok``, as its folder is. The worker
    dropped the file's claim as it finished, so the client knew nothing of it: listed
    ``interrupted`` beside its whole folder."""
    from graphvision.execution.batch_run import BatchRun

    client = os.getpid()
    run_first = BatchRun.run_first

    def then_stopped(batch: BatchRun) -> Any:  # in the first file's worker (a fork)
        item = run_first(batch)
        os.kill(client, signal.SIGINT)
        time.sleep(1.0)  # the client stops meanwhile: the answer comes too late
        return item

    monkeypatch.setattr(BatchRun, "run_first", then_stopped)
    monkeypatch.setenv("CLIENT_PID", str(client))
    monkeypatch.setenv("KILL_BY", "exit")
    before = signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a terminal
    try:
        with pytest.raises(KeyboardInterrupt):
            _scored_on_processes(tmp_path, KILLING_PLUGIN, "killing", [20, 30, 40, 50])
    finally:
        signal.signal(signal.SIGINT, before)
    with (tmp_path / "out" / "batch.csv").open() as summary:
        rows = list(csv.DictReader(summary))
    assert [row["status"] for row in rows] == ["ok", "not run", "not run", "not run"], rows
    assert float(rows[0]["score"]) == pytest.approx(20 / 255.0, abs=1e-6)
    record = json.loads((tmp_path / "out" / "00" / "record.json").read_text())
    assert record["executor"] == "processes, first file on a worker"
    assert [p.name for p in (tmp_path / "out").iterdir() if p.is_dir()] == ["00"]
