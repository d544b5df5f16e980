"""The Dask executor: same results as threads, a dead worker costs one retry, clear errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import graphvision as gv

distributed = pytest.importorskip(
    "distributed", reason="Dask is an optional extra: graphvision[dask]"
)

from graphvision.execution.dask import DaskExecutor, DaskUnavailableError  # noqa: E402

PIPELINES = Path(__file__).parents[2] / "pipelines"

FLAKY_PLUGIN = '''
import os
from pathlib import Path
from graphvision import Float, node


@node("flaky.die_once")
def die_once(x: Float, *, marker: str = "") -> Float:
    """Kills its worker process the first time it runs; returns x + 1 after.

    Parameters
    ----------
    x : the value
    marker : a file whose existence says the first attempt happened
    """
    if not Path(marker).exists():
        Path(marker).write_text("died once")
        os._exit(1)
    return x + 1.0
'''


@pytest.fixture(scope="module")
def dask_executor():
    executor = DaskExecutor(workers=2, threads_per_worker=1)
    yield executor
    executor.shutdown()


def test_coins_on_dask_equal_coins_on_threads(dask_executor, tmp_path):
    graph = gv.load_pipeline(PIPELINES / "coins.yaml")
    on_dask = gv.run(graph, executor=dask_executor, cache=None).outputs
    on_threads = gv.run(graph, executor="threads", cache=None).outputs
    assert on_dask["count"] == on_threads["count"] == 24
    np.testing.assert_array_equal(on_dask["labels"], on_threads["labels"])


def test_a_worker_that_dies_costs_one_retry_not_the_run(dask_executor, tmp_path):
    plugin = tmp_path / "flaky.py"
    plugin.write_text(FLAKY_PLUGIN)
    registry = gv.discover([plugin])
    graph = gv.Graph("flaky")
    x = graph.input("x", "Float", default=1.0)
    graph.output("y", graph.add("y", "flaky.die_once", x=x, params={"marker": str(tmp_path / "m")}))
    result = gv.run(graph, registry, executor=dask_executor, cache=None)
    assert (tmp_path / "m").exists()  # the first attempt ran, and its worker died
    assert result.outputs["y"] == 2.0


ODD_PLUGIN = '''
from graphvision import Float, node


@node("odd.refuse_odd")
def refuse_odd(x: Float, *, value: int = 0) -> Float:
    """Returns value, or raises for an odd one.

    Parameters
    ----------
    x : the input
    value : the number to return
    """
    if value % 2:
        raise ValueError(f"odd value {value}")
    return float(value)
'''


def test_results_and_failures_finishing_together_each_reach_their_node(dask_executor, tmp_path):
    """Results are fetched many at a time; a failure among them fails only its own node."""
    plugin = tmp_path / "odd.py"
    plugin.write_text(ODD_PLUGIN)
    registry = gv.discover([plugin])
    graph = gv.Graph("fan")
    x = graph.input("x", "Float", default=0.0)
    for value in range(40):
        graph.output(f"o{value}", graph.add(f"n{value}", "odd.refuse_odd", x=x,
                                            params={"value": value}))  # fmt: skip
    with pytest.raises(gv.RunError) as caught:
        gv.run(graph, registry, executor=dask_executor, cache=None, keep_going=True)
    assert sorted(caught.value.failures) == sorted(f"n{v}" for v in range(1, 40, 2))
    assert "odd value 7" in str(caught.value.failures["n7"])
    produced = caught.value.result.outputs
    assert produced == {f"o{v}": float(v) for v in range(0, 40, 2)}


def test_a_worker_that_cannot_import_the_plugin_is_named(dask_executor, tmp_path):
    plugin = tmp_path / "gone.py"
    plugin.write_text(FLAKY_PLUGIN.replace("flaky.die_once", "gone.die_once"))
    registry = gv.discover([plugin])
    plugin.unlink()  # the client has imported it; the workers cannot
    graph = gv.Graph("gone")
    x = graph.input("x", "Float", default=1.0)
    graph.output("y", graph.add("y", "gone.die_once", x=x, params={"marker": str(tmp_path)}))
    with pytest.raises(gv.RunError) as caught:
        gv.run(graph, registry, executor=dask_executor, cache=None)
    message = str(caught.value.failures["y"])
    assert "worker tcp://" in message and "gone.py" in message


def test_an_unreachable_scheduler_is_refused_naming_the_address():
    with pytest.raises(DaskUnavailableError, match=r"cannot reach the Dask scheduler at tcp://127"):
        DaskExecutor(address="tcp://127.0.0.1:9", timeout=1)


DYING_FILE_PLUGIN = '''
import os
from pathlib import Path
from graphvision import Float, Image, node


@node("dying.mean")
def mean(image: Image, *, marker: str = "") -> Float:
    """The image's mean; kills its worker the first time it sees the darkest file.

    Parameters
    ----------
    image : the file's image
    marker : a file whose existence says the worker already died once
    """
    if float(image.mean()) < 0.1 and not Path(marker).exists():
        Path(marker).write_text("died once")
        os._exit(1)
    return float(image.mean())
'''


def test_a_batch_on_dask_survives_a_dying_worker_and_retries_its_file(dask_executor, tmp_path):
    import imageio.v3 as iio

    plugin = tmp_path / "dying.py"
    plugin.write_text(DYING_FILE_PLUGIN)
    registry = gv.discover([plugin])
    graph = gv.Graph("dying")
    image = graph.input("image", "Image")
    graph.output(
        "mean",
        graph.add("mean", "dying.mean", image=image, params={"marker": str(tmp_path / "died")}),
    )
    levels = [200, 10, 120, 60, 240, 30]
    files = []
    for k, level in enumerate(levels):
        files.append(tmp_path / "in" / f"{k}.png")
        files[-1].parent.mkdir(exist_ok=True)
        iio.imwrite(files[-1], np.full((8, 8), level, np.uint8))
    batch = gv.run_batch(
        graph,
        [str(f) for f in files],
        input="image",
        output_dir=tmp_path / "out",
        registry=registry,
        executor=dask_executor,
        cache=None,
        client_files=False,  # file 1 kills its process: a worker's, never the test's
    )
    assert (tmp_path / "died").exists()  # a worker did die, on file 1
    assert [item.status for item in batch.items] == ["ok"] * len(levels), batch.items
    for item, level in zip(batch.items, levels, strict=True):
        assert item.scalars["mean"] == pytest.approx(level / 255.0, abs=1e-6)
    assert (tmp_path / "out" / "batch.csv").is_file()


def test_a_dask_batch_sends_the_shared_values_once_and_never_recomputes_them(
    dask_executor, tmp_path
):
    from .test_batch import _counting_graph, photo

    graph, registry, log = _counting_graph(tmp_path)
    levels = [20, 90, 160, 230]
    files = [photo(tmp_path / "in" / f"{k}.png", level) for k, level in enumerate(levels)]
    batch = gv.run_batch(
        graph,
        [str(f) for f in files],
        input="image",
        output_dir=tmp_path / "out",
        registry=registry,
        executor=dask_executor,
        cache=None,
    )
    assert [item.status for item in batch.items] == ["ok"] * len(levels)
    for item, level in zip(batch.items, levels, strict=True):
        assert item.scalars["score"] == pytest.approx(2.0 * level / 255.0, abs=1e-6)
    assert log.read_text().splitlines().count("model") == 1


STEP_PLUGIN = '''
from graphvision import Float, node


@node("step.add")
def add(x: Float, *, fail: bool = False) -> Float:
    """x + 1, or an error.

    Parameters
    ----------
    x : the value
    fail : raise instead
    """
    if fail:
        raise ValueError("asked to fail")
    return x + 1.0
'''


class Order(gv.RunHooks):
    def __init__(self) -> None:
        self.events: list[str] = []

    def node_started(self, *, name, op):
        self.events.append(f"start {name}")

    def node_finished(self, *, name, op, status, seconds):
        self.events.append(f"{status} {name}")


def step_chain(tmp_path, length, failing=None):
    plugin = tmp_path / "step.py"
    plugin.write_text(STEP_PLUGIN)
    graph = gv.Graph("steps")
    value = graph.input("x", "Float", default=0.0)
    for k in range(length):
        value = graph.add(f"n{k}", "step.add", x=value, params={"fail": k == failing})
    graph.output("last", value)
    return graph, gv.discover([plugin])


def test_a_chain_is_submitted_whole_and_computed_on_the_workers(dask_executor, tmp_path):
    """Each node goes to Dask with its predecessor's task, not after its value came back."""
    graph, registry = step_chain(tmp_path, 12)
    order = Order()
    result = gv.run(graph, registry, executor=dask_executor, cache=None, hooks=[order])
    assert result.outputs["last"] == 12.0
    assert order.events[:12] == [f"start n{k}" for k in range(12)]
    assert order.events[12:] == [f"computed n{k}" for k in range(12)]


def test_nodes_submitted_ahead_of_a_failure_are_skipped_not_failed(dask_executor, tmp_path):
    graph, registry = step_chain(tmp_path, 6, failing=2)
    cache = gv.Cache.at(tmp_path / "cache")
    order = Order()
    with pytest.raises(gv.RunError) as caught:
        gv.run(graph, registry, executor=dask_executor, cache=cache, hooks=[order])
    started = sorted(e.split()[1] for e in order.events if e.startswith("start"))
    finished = sorted(e.split()[1] for e in order.events if not e.startswith("start"))
    assert started == finished == [f"n{k}" for k in range(6)]  # each start has its end
    assert [e for e in order.events if e.startswith("skipped")] == [
        "skipped n3",
        "skipped n4",
        "skipped n5",
    ]
    assert list(caught.value.failures) == ["n2"]
    assert "asked to fail" in str(caught.value.failures["n2"])
    statuses = {node.name: node.status for node in caught.value.record.nodes}
    assert statuses == {
        "n0": "computed", "n1": "computed", "n2": "failed",
        "n3": "skipped", "n4": "skipped", "n5": "skipped",
    }  # fmt: skip
    fixed = step_chain(tmp_path, 6)[0]  # the same first two nodes, then no failure
    again = gv.run(fixed, registry, executor=dask_executor, cache=cache)
    assert again.outputs["last"] == 6.0
    statuses = {node.name: node.status for node in again.record.nodes}
    assert statuses == {  # n1's value was stored, so n0 is not even looked at (nor run)
        "n0": "unneeded", "n1": "cached", "n2": "computed", "n3": "computed", "n4": "computed",
        "n5": "computed",
    }  # fmt: skip


def test_a_node_workers_cannot_import_fails_alone_and_its_readers_are_skipped(
    dask_executor, tmp_path
):
    """A node defined in __main__ is refused before it is sent; nothing is sent ahead of it."""
    import types

    def twice(x: gv.Float) -> gv.Float:
        """2 x.

        Parameters
        ----------
        x : the value
        """
        return 2.0 * x

    twice.__module__ = "__main__"
    module = types.ModuleType("in_a_notebook")
    module.twice = gv.node("notebook.twice")(twice)  # type: ignore[attr-defined]
    plugin = tmp_path / "step.py"
    plugin.write_text(STEP_PLUGIN)
    registry = gv.discover([plugin])
    registry.add_plugin(module, "in_a_notebook")
    graph = gv.Graph("notebook")
    x = graph.input("x", "Float", default=1.0)
    graph.output("y", graph.add("b", "step.add", x=graph.add("a", "notebook.twice", x=x)))
    with pytest.raises(gv.RunError) as caught:
        gv.run(graph, registry, executor=dask_executor, cache=None)
    assert list(caught.value.failures) == ["a"]
    assert "defined in __main__" in str(caught.value.failures["a"])
    assert [(n.name, n.status) for n in caught.value.record.nodes] == [
        ("a", "failed"),
        ("b", "skipped"),
    ]


def test_a_batch_runs_files_in_the_client_while_the_workers_are_not_ready(dask_executor, tmp_path):
    """Each worker is held busy until the fourth file is done: the client runs files 1 to 3
    itself (the last ``files_at_once`` = 4 are always the workers'), then the workers the
    rest."""
    from .test_batch import _counting_graph, photo

    client, name = dask_executor.client, f"hold-{tmp_path.name}"
    client.wait_for_workers(2, timeout=60)  # a worker an earlier test killed is back: held too

    def hold(event_name: str) -> bool:
        return distributed.Event(event_name).wait(timeout=30)

    for address in client.scheduler_info()["workers"]:  # queued before the batch's warm-up
        client.submit(hold, name, workers=[address], pure=False)

    def release(done: int, total: int, item: object) -> None:
        if done == 4:
            distributed.Event(name, client=client).set()

    graph, registry, _ = _counting_graph(tmp_path)
    levels = [10, 40, 70, 100, 130, 160, 190, 220]
    files = [photo(tmp_path / "in" / f"{k}.png", level) for k, level in enumerate(levels)]
    batch = gv.run_batch(
        graph,
        [str(f) for f in files],
        input="image",
        output_dir=tmp_path / "out",
        registry=registry,
        executor=dask_executor,
        cache=None,
        on_item=release,
        files_at_once=4,  # one file a task, as many as the workers run and queue
    )
    assert [item.scalars["score"] for item in batch.items] == pytest.approx(
        [2.0 * level / 255.0 for level in levels], abs=1e-6
    )
    where = [json.loads((item.output_dir / "record.json").read_text())["executor"]
             for item in batch.items]  # fmt: skip
    assert where == [
        "dask, first file in this process",
        *["dask, in the client while the workers started"] * 3,
        *["dask, up to 16 files a task"] * 4,
    ]


class _Borrowed:
    """The module's cluster's client, which the executor under test may not close."""

    def __init__(self, client: object) -> None:
        self._client = client

    def __getattr__(self, name: str) -> object:
        return getattr(self._client, name)

    def close(self) -> None:
        pass


def test_a_local_cluster_starts_in_the_background_and_shared_values_wait_for_it(
    dask_executor, monkeypatch
):
    import operator
    import threading

    from graphvision.execution import dask as dask_module

    go = threading.Event()

    def slow_start(workers: int, threads_per_worker: int) -> tuple[object, object]:
        assert go.wait(timeout=60)
        return None, _Borrowed(dask_executor.client)

    monkeypatch.setattr(dask_module, "start_local_cluster", slow_start)
    executor = DaskExecutor(workers=3)
    assert executor.width == 3  # known before the cluster has started
    shared = executor.share(41.0)  # held until the cluster is there
    go.set()
    first = executor.submit(operator.add, shared, 1.0)
    second = executor.submit(operator.sub, shared, 1.0)
    assert (first.result(timeout=60), second.result(timeout=60)) == (42.0, 40.0)
    assert first.task.client is dask_executor.client
    executor.shutdown()
    with pytest.raises(DaskUnavailableError, match="this Dask executor has been shut down"):
        executor.submit(operator.add, 1.0, 1.0)


def test_a_local_cluster_that_cannot_start_is_named_where_it_is_first_needed(monkeypatch):
    import operator

    from graphvision.execution import dask as dask_module

    def no_start(workers: int, threads_per_worker: int) -> tuple[object, object]:
        raise OSError("no free port")

    monkeypatch.setattr(dask_module, "start_local_cluster", no_start)
    executor = DaskExecutor()
    with pytest.raises(
        DaskUnavailableError,
        match=r"the local Dask cluster did not start \(OSError: no free port\)",
    ):
        executor.submit(operator.add, 1.0, 1.0)
    executor.shutdown()


def test_a_dask_executor_is_shut_down_at_the_end_of_a_with_block(monkeypatch):
    closed = []
    monkeypatch.setattr(gv.DaskExecutor, "shutdown", lambda self, *a, **k: closed.append(self))
    with gv.DaskExecutor() as pool:  # no cluster yet: it starts on first need
        assert isinstance(pool, gv.DaskExecutor) and not closed
    assert closed == [pool]
