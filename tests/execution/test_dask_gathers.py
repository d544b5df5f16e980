"""Results of a Dask batch's tasks fetched from the workers straight on a ``LocalCluster`` of
this process (``direct_gathers``), through the scheduler elsewhere, as Dask does."""

from __future__ import annotations

import operator
import threading

import pytest

distributed = pytest.importorskip(
    "distributed", reason="Dask is an optional extra: graphvision[dask]"
)

from graphvision.execution.dask import DaskExecutor  # noqa: E402
from graphvision.execution.dask_fork import direct_gathers  # noqa: E402


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=":0"
    ) as running:
        yield running


def _gathers_through_the_scheduler(client) -> int:
    return sum(event.get("action") == "gather" for _, event in client.get_events("all"))


def test_a_local_clusters_results_skip_the_scheduler_and_arrive_whole(cluster):
    with distributed.Client(cluster) as client:
        assert direct_gathers(client) is True
        executor = DaskExecutor(client)
        alone = executor.submit(operator.add, 2, 3).result()  # fetched by Dask's callback
        together = [executor.submit(operator.mul, k, 7) for k in range(6)]  # by the loop
        assert alone == 5
        assert [future.result() for future in together] == [0, 7, 14, 21, 28, 35]
        assert _gathers_through_the_scheduler(client) == 0


def test_a_clients_own_setting_is_kept_and_its_results_arrive_whole(cluster):
    with distributed.Client(cluster, direct_to_workers=False) as client:
        assert direct_gathers(client) is None  # Dask reads the client's own setting
        executor = DaskExecutor(client)
        assert executor.submit(operator.add, 2, 3).result() == 5
        assert _gathers_through_the_scheduler(client) >= 1


def test_no_client_yet_leaves_it_to_the_client_the_executor_makes():
    assert direct_gathers(None) is None


def _fails(path: str) -> None:
    raise ValueError(f"{path} is unreadable")


def test_a_tasks_result_or_error_is_handed_on_by_the_clients_event_loop(cluster):
    with distributed.Client(cluster) as client:
        executor = DaskExecutor(client)
        landed: list[tuple[object, object, str]] = []
        done = threading.Event()

        def record(value: object, error: BaseException | None) -> None:
            landed.append((value, error, threading.current_thread().name))
            if len(landed) == 2:
                done.set()

        executor.when_done(client.submit(operator.mul, 6, 7, pure=False), record, "file")
        executor.when_done(client.submit(_fails, "a.png", pure=False), record, "file")
        assert done.wait(30)
        results = sorted(landed, key=lambda found: found[1] is not None)
        assert results[0][:2] == (42, None)
        assert results[1][0] is None
        assert type(results[1][1]) is ValueError and str(results[1][1]) == "a.png is unreadable"
        on_loop: list[str] = []  # the name of the thread the client's event loop runs in
        client.loop.add_callback(lambda: on_loop.append(threading.current_thread().name))
        client.submit(operator.add, 1, 1, pure=False).result()
        assert on_loop and on_loop[0] != threading.current_thread().name
        assert {name for *_, name in landed} == {on_loop[0]}
