"""A batch's shared values reach a worker frozen, as the client holds them (file_task)."""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np

import graphvision as gv
from graphvision.execution.file_task import FileJob, _prepared
from graphvision.values.ports import is_frozen


def test_a_shared_value_is_frozen_on_the_worker_as_in_the_client():
    graph = gv.Graph("seeded")
    graph.output("out", graph.input("image", "GrayImage"))
    shared = np.linspace(0, 1, 48, dtype=np.float32).reshape(6, 8)
    job = FileJob(
        token="seeded-job",
        graph=graph,
        plugin_paths=(),
        input="image",
        inputs={},
        outputs=None,
        keep_going=False,
        seeds=[("key", "GrayImage", {"data": shared}, {})],
        pages=(),
        store=None,
        executor="processes, one task per file",
        out_dir=Path("out"),
    )
    sent = pickle.loads(pickle.dumps(job))  # as a worker gets it: arrays writable again
    assert sent.seeds[0][2]["data"].flags.writeable
    ((key, value, nbytes),) = _prepared(sent).seeds
    assert key == "key" and nbytes == shared.nbytes
    assert not value.flags.writeable and is_frozen(value)
    np.testing.assert_array_equal(value, shared)


def test_a_file_a_worker_takes_after_the_stop_is_not_run(tmp_path):
    """Such a file never started: it was listed 'interrupted' ('the batch stopped while this
    file ran'; found by TRY45 on Dask, where a task's files after the stop are skipped)."""
    from graphvision.execution.batch_stop import StopFlag
    from graphvision.execution.file_task import run_file_task

    stop = StopFlag.make(tmp_path)
    stop.raise_()
    graph = gv.Graph("stopped")
    graph.output("out", graph.input("image", "GrayImage"))
    job = FileJob(
        token="stopped-job", graph=graph, plugin_paths=(), input="image", inputs={},
        outputs=None, keep_going=False, seeds=[], pages=(), store=None, executor="dask",
        out_dir=tmp_path / "out", stop=stop,
    )  # fmt: skip
    item = run_file_task(job, str(tmp_path / "a.png"), str(tmp_path / "out" / "a")).item
    assert (item.status, item.error) == ("not run", "the batch stopped before this file started")
    assert not (tmp_path / "out").exists()
    stop.remove()
