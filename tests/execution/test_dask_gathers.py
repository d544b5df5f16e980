"""Results of a Dask batch's tasks fetched from the workers straight on a ``LocalCluster`` of
this process (``direct_gathers``), through the scheduler elsewhere, as Dask does."""

from __future__ import annotations

import operator

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
