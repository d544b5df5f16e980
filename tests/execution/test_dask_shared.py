"""A value the Dask executor's tasks share is held by every worker, so that Dask spreads the
tasks that read it (a batch's job on one worker sent every file task to that worker)."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest

import graphvision as gv

distributed = pytest.importorskip(
    "distributed", reason="Dask is an optional extra: graphvision[dask]"
)

from graphvision.execution.dask import DaskExecutor  # noqa: E402

SPIN_PLUGIN = '''
import os
import time

from graphvision import Float, Image, node


@node("spin.pid")
def pid(image: Image) -> Float:
    """The id of the process that ran it, after 20 ms of its thread's CPU time.

    Parameters
    ----------
    image : the file's image
    """
    end = time.thread_time() + 0.02
    while time.thread_time() < end:
        pass
    return float(os.getpid())
'''


@pytest.fixture(scope="module")
def client():
    """A cluster of two workers that does not steal work: tasks go where their inputs are."""
    import dask

    with (
        dask.config.set({"distributed.scheduler.work-stealing": False}),
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        client.wait_for_workers(2, timeout=60)
        yield client


def _holders(client, task) -> set[str]:
    return set(client.who_has([task]).get(task.key, ()))


def test_a_shared_value_is_copied_to_every_worker(client):
    executor = DaskExecutor(client)
    value = np.arange(5.0)
    task = executor.share(value).sent()
    deadline, held = time.monotonic() + 30, set()
    while len(held) < 2 and time.monotonic() < deadline:  # Dask may drop a copy no task needs
        held = _holders(client, task)
        time.sleep(0.02)
    assert held == set(client.nthreads())
    np.testing.assert_array_equal(task.result(), [0.0, 1.0, 2.0, 3.0, 4.0])


def test_a_batchs_files_run_on_every_worker(client, tmp_path):
    import imageio.v3 as iio

    plugin = tmp_path / "spin.py"
    plugin.write_text(SPIN_PLUGIN)
    graph = gv.Graph("spin")
    graph.output("pid", graph.add("pid", "spin.pid", image=graph.input("image", "Image")))
    files = []
    for k in range(24):
        files.append(tmp_path / "in" / f"{k:02d}.png")
        files[-1].parent.mkdir(exist_ok=True)
        iio.imwrite(files[-1], np.full((8, 8), 10 * k, np.uint8))
    batch = gv.run_batch(
        graph, [str(f) for f in files], input="image", output_dir=tmp_path / "out",
        registry=gv.discover([plugin]), executor=DaskExecutor(client), cache=None,
        client_files=False,
    )  # fmt: skip
    assert [item.status for item in batch.items] == ["ok"] * len(files)
    workers = {int(pid) for pid in client.run(os.getpid).values()}
    ran = [int(item.scalars["pid"]) for item in batch.items[1:]]  # the first runs in the client
    assert set(ran) == workers  # both workers took files (one of them alone: sync's pace)
