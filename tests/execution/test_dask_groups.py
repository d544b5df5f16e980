"""How a Dask batch's files are grouped into tasks (:class:`FileGroups`), on a fake cluster:
one file a task until files have come back, then as many as take about 0.1 s, and a task
of fewer files only for a worker thread that would wait otherwise."""

from __future__ import annotations

import pickle
from concurrent.futures import Future
from pathlib import Path
from typing import Any

from graphvision.execution.batch_files import BatchItem
from graphvision.execution.dask_files import FileGroups
from graphvision.execution.file_group import run_files
from graphvision.execution.file_task import FileOutcome


class _Cluster:
    """A client whose tasks wait until the test lands them (``land``), a file taking ``seconds``
    of CPU time each."""

    def __init__(self, seconds: float) -> None:
        self.seconds = seconds
        self.tasks: list[tuple[list[tuple[str, str]], Future]] = []

    def submit(
        self, _on_worker: Any, _run_files: Any, _task: Any, _job: Any, files: list, **_: Any
    ):
        future: Future = Future()
        self.tasks.append((files, future))
        return future

    def land(self, k: int) -> None:
        files, future = self.tasks[k]
        outcomes = [FileOutcome(BatchItem(Path(p), Path(f))) for p, f in files]
        future.set_result((outcomes, self.seconds * len(files)))  # as run_files returns


class _Executor:
    def __init__(self, cluster: _Cluster, width: int) -> None:
        self.client, self.width, self.retries = cluster, width, 1

    def _sent(self, job: Any) -> Any:
        return job

    def result(self, task: Future, running: str = "node") -> Any:
        return task.result()

    def when_done(self, task: Future, landed: Any, running: str = "node") -> None:
        task.add_done_callback(lambda done: landed(done.result(), None))


def _sizes(cluster: _Cluster) -> list[int]:
    return [len(files) for files, _ in cluster.tasks]


def test_tasks_fill_up_once_files_have_come_back_and_a_short_one_waits_for_an_idle_thread():
    cluster = _Cluster(seconds=0.02)  # 5 files make 0.1 s
    groups = FileGroups(_Executor(cluster, width=2))
    job = object()
    futures = [groups.submit(object(), job, f"{k}.png", f"out/{k}") for k in range(12)]
    # nothing measured: one file a task, one running on each thread and one queued behind it
    assert _sizes(cluster) == [1, 1, 1, 1]
    cluster.land(0)  # 0.02 s a file: five a task
    assert _sizes(cluster) == [1, 1, 1, 1, 5]
    cluster.land(1)  # three files left: a task of three would only queue, so it waits
    cluster.land(2)
    assert _sizes(cluster) == [1, 1, 1, 1, 5]
    cluster.land(3)  # one task in flight on two threads: a thread would wait, they leave
    assert _sizes(cluster) == [1, 1, 1, 1, 5, 3]
    cluster.land(4)
    cluster.land(5)
    found = [future.result().item for future in futures]
    assert [item.file for item in found] == [Path(f"{k}.png") for k in range(12)]
    assert [item.output_dir for item in found] == [Path(f"out/{k}") for k in range(12)]


def test_another_batchs_files_are_measured_afresh():
    cluster = _Cluster(seconds=0.05)  # 2 files make 0.1 s
    groups = FileGroups(_Executor(cluster, width=1))
    first, second = object(), object()
    groups.submit(object(), first, "a.png", "out/a")
    cluster.land(0)
    for k in range(4):
        groups.submit(object(), first, f"{k}.png", f"out/{k}")
    assert _sizes(cluster) == [1, 1, 2]  # a lone file for the idle thread, then two a task
    cluster.land(1)
    cluster.land(2)  # the thread would wait: file 3 leaves alone
    assert _sizes(cluster) == [1, 1, 2, 1]
    cluster.land(3)
    groups.submit(object(), second, "b.png", "out/b")
    groups.submit(object(), second, "c.png", "out/c")
    assert _sizes(cluster) == [1, 1, 2, 1, 1, 1]  # another job: one a task until measured


def _busy(job: Any, path: str, folder: str) -> str:
    if path == "bad.png":
        raise ValueError(f"{path} is unreadable")
    total = 0
    for k in range(200_000):  # some CPU time in this thread
        total += k
    return f"{job}:{path}->{folder}:{total}"


def test_a_task_of_files_reports_each_outcome_and_the_cpu_time_they_took():
    found, seconds = run_files(_busy, "job", [("a.png", "out/a"), ("bad.png", "out/bad")])
    assert found[0] == "job:a.png->out/a:19999900000"
    back = pickle.loads(pickle.dumps(found[1]))  # as the task's result reaches the client
    assert isinstance(back, ValueError) and str(back) == "bad.png is unreadable"
    assert 0.0 < seconds < 60.0
