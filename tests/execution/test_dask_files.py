"""Dask batches: several files to a task, each with its own outcome; the executor's own
cluster forked from the client after a batch's first file."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import graphvision as gv

distributed = pytest.importorskip(
    "distributed", reason="Dask is an optional extra: graphvision[dask]"
)

from graphvision.execution.dask import DaskExecutor  # noqa: E402
from graphvision.execution.dask_files import FILES_PER_TASK  # noqa: E402

from .test_dask import DYING_FILE_PLUGIN  # noqa: E402

PICKY_PLUGIN = '''
from graphvision import Float, Image, node


@node("picky.mean")
def mean(image: Image) -> Float:
    """The image's mean; a dark image is refused.

    Parameters
    ----------
    image : the file's image
    """
    if float(image.mean()) < 0.1:
        raise ValueError("too dark to measure")
    return float(image.mean())
'''


def _images(folder: Path, levels: list[int]) -> list[Path]:
    import imageio.v3 as iio

    folder.mkdir(parents=True, exist_ok=True)
    for k, level in enumerate(levels):
        iio.imwrite(folder / f"{k:02d}.png", np.full((8, 8), level, np.uint8))
    return sorted(folder.glob("*.png"))


def _means(tmp_path: Path, source: str, family: str, levels: list[int], executor: Any) -> Any:
    """A batch on ``executor`` of one image per level (``in/NN.png``), each measured by the
    plugin ``source``'s node ``FAMILY.mean``, into ``out/``; the workers run every file."""
    plugin = tmp_path / f"{family}.py"
    plugin.write_text(source)
    graph = gv.Graph(family)
    graph.output("mean", graph.add("mean", f"{family}.mean", image=graph.input("image", "Image")))
    return gv.run_batch(
        graph, [str(f) for f in _images(tmp_path / "in", levels)], input="image",
        output_dir=tmp_path / "out", registry=gv.discover([plugin]), executor=executor,
        cache=None, client_files=False,
    )  # fmt: skip


def test_files_sent_several_to_a_task_keep_their_own_outcomes(tmp_path):
    levels = [200, 120, 60, 240, 180, 10, 90, 150, 220, 30, 70, 250]
    with (
        distributed.LocalCluster(n_workers=1, threads_per_worker=1, dashboard_address=":0") as c,
        distributed.Client(c) as client,
    ):
        executor = DaskExecutor(client)
        assert executor.files_at_once == 2 * FILES_PER_TASK  # one thread, two tasks in flight
        with distributed.get_task_stream(client) as stream:
            batch = _means(tmp_path, PICKY_PLUGIN, "picky", levels, executor)
    statuses = [item.status for item in batch.items]
    assert statuses == ["failed" if level == 10 else "ok" for level in levels]
    assert "too dark to measure" in batch.items[5].error
    for item, level in zip(batch.items, levels, strict=True):
        if level != 10:
            assert item.scalars["mean"] == pytest.approx(level / 255.0, abs=1e-6)
            assert json.loads((item.output_dir / "mean.json").read_text()) == pytest.approx(
                level / 255.0, abs=1e-6
            )
    tasks = [t for t in stream.data if t["key"].startswith("on_worker")]
    assert len(tasks) < len(levels) - 1  # files 1 to 11 went in fewer tasks than files


FORKED = """
import json, multiprocessing, os, sys
from pathlib import Path
import graphvision as gv
from graphvision.execution.dask import DaskExecutor

folder = Path(sys.argv[1])
graph = gv.Graph("dying")
image = graph.input("image", "Image")
marker = str(folder / "died")
graph.output("mean", graph.add("mean", "dying.mean", image=image, params={"marker": marker}))
executor = DaskExecutor(workers=2)
batch = gv.run_batch(
    graph, sorted(str(p) for p in (folder / "in").glob("*.png")), input="image",
    output_dir=folder / "out", registry=gv.discover([folder / "dying.py"]), executor=executor,
    cache=None, client_files=False,
)
names = executor.client.run(lambda: multiprocessing.current_process().name)
executor.shutdown()
print(json.dumps({
    "forked": sum(name.startswith("graphvision-dask-worker") for name in names.values()),
    "means": [item.scalars.get("mean") for item in batch.items],
    "statuses": [item.status for item in batch.items],
}))
"""


def test_a_batch_forks_the_workers_of_its_own_cluster_and_one_that_dies_costs_a_retry(tmp_path):
    """In a fresh process (no other thread: a fork is safe), the executor's own cluster gets
    its workers as forks of the client; file 1 kills its worker once and is run again."""
    (tmp_path / "dying.py").write_text(DYING_FILE_PLUGIN)
    levels = [200, 10, 120, 60, 240]
    _images(tmp_path / "in", levels)
    done = subprocess.run(
        [sys.executable, "-c", FORKED, str(tmp_path)],
        capture_output=True, text=True, timeout=300, env={**os.environ, "PYTHONWARNINGS": "ignore"},
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    found = json.loads(done.stdout.splitlines()[-1])
    assert (tmp_path / "died").exists()  # a worker did die, on file 1
    assert found["statuses"] == ["ok"] * len(levels)
    assert found["means"] == pytest.approx([level / 255.0 for level in levels], abs=1e-6)
    assert found["forked"] >= 1  # the surviving worker is a fork of the client


ALWAYS_DYING_PLUGIN = '''
import os
from graphvision import Float, Image, node


@node("always.mean")
def mean(image: Image) -> Float:
    """The image's mean; kills its worker on the darkest file, every time.

    Parameters
    ----------
    image : the file's image
    """
    if float(image.mean()) < 0.1:
        os._exit(1)
    return float(image.mean())
'''


def test_a_file_that_kills_every_worker_fails_alone_and_no_file_is_written_twice(tmp_path):
    """Its task of several files failed whole (KilledWorker: Dask gives up on a task whose
    workers died): the healthy files in it failed too, and those it had written were
    written again on each retry (history/ in a new folder). Now each file goes again alone;
    those written whole come back from their claims."""
    import dask

    levels = [200, 120, 60, 240, 180, 90, 10, 150, 220, 30, 70, 250]
    with (
        dask.config.set({"distributed.scheduler.allowed-failures": 2}),
        distributed.LocalCluster(n_workers=1, threads_per_worker=1, dashboard_address=":0") as c,
        distributed.Client(c) as client,
    ):
        batch = _means(tmp_path, ALWAYS_DYING_PLUGIN, "always", levels, DaskExecutor(client))
    statuses = [item.status for item in batch.items]
    assert statuses == ["failed" if level == 10 else "ok" for level in levels]
    for item, level in zip(batch.items, levels, strict=True):
        if level != 10:
            assert item.scalars["mean"] == pytest.approx(level / 255.0, abs=1e-6)
    assert not list((tmp_path / "out").glob("*/history"))  # no folder written twice
    assert not (tmp_path / "out" / "06").exists()  # the file at fault has no folder
    error = batch.items[levels.index(10)].error  # said as the processes executor says it
    assert error.startswith("WorkerDiedError: the Dask worker running this file died each of the 3")
    assert batch.items[levels.index(10)].seconds > 0  # its tries' time (was 0.0; TRY45)


def test_a_node_that_kills_every_worker_in_a_run_is_said_to_have_killed_them(tmp_path):
    """``gv.run`` on Dask said Dask's ``KilledWorker`` ("Attempted to run task
    'on_worker-…'"), not which node died nor in the words of the processes executor."""
    import dask

    plugin = tmp_path / "always.py"
    plugin.write_text(ALWAYS_DYING_PLUGIN)
    graph = gv.Graph("dies")
    graph.output("mean", graph.add("mean", "always.mean", image=graph.input("image", "Image")))
    with (
        dask.config.set({"distributed.scheduler.allowed-failures": 1}),
        distributed.LocalCluster(n_workers=1, threads_per_worker=1, dashboard_address=":0") as c,
        distributed.Client(c) as client,
        pytest.raises(gv.RunError) as raised,
    ):
        gv.run(
            graph, inputs={"image": np.zeros((8, 8), np.float32)}, registry=gv.discover([plugin]),
            executor=DaskExecutor(client), cache=None,
        )  # fmt: skip
    told = str(raised.value)
    assert told.startswith("node 'mean' (op always.mean) failed: WorkerDiedError: the Dask worker")
    assert "died each of the 2 times it was run" in told
    assert "KilledWorker" not in told and "on_worker-" not in told
