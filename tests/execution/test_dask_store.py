"""On Dask, a batch's values stay on the workers: they write them into the store the
cluster shares (S3 here, through a server the test starts), the client gets keys and
small metadata; a worker killed while it writes costs a retry, and nothing half-written
is ever read."""

from __future__ import annotations

import json
import uuid
import warnings
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

import graphvision as gv

distributed = pytest.importorskip("distributed", reason="Dask is an optional extra")

from ..conftest import PIPELINES  # noqa: E402


def _coins_files(folder: Path, count: int) -> list[str]:
    """Seeded variations of the coins picture: flipped, gamma, a little noise."""
    from graphvision_plugins.io import read_sample

    folder.mkdir(parents=True)
    rng, coins, files = np.random.default_rng(7), read_sample("coins"), []
    for k in range(count):
        image = coins[:, ::-1] if k % 2 else coins
        image = np.clip(image ** rng.uniform(0.9, 1.1) + rng.normal(0, 0.01, image.shape), 0, 1)
        files.append(str(folder / f"c{k}.png"))
        iio.imwrite(files[-1], np.round(image * 255).astype(np.uint8))
    return files


@pytest.fixture(scope="module")
def cluster_client():
    """Two worker processes; they share nothing with the client but the store (values) and
    this machine's folders (the input files and the output folders)."""
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        yield client


def _run(files, out, cache, client):
    return gv.run_batch(
        gv.load_pipeline(PIPELINES / "coins.yaml"),
        files,
        input="image",
        output_dir=out,
        executor=gv.DaskExecutor(client, retries=2),
        cache=cache,
    )


def test_workers_write_the_values_to_the_shared_store_and_send_back_keys(
    cluster_client, tmp_path, s3_options
):
    files = _coins_files(tmp_path / "in", 3)
    url = f"s3://gv-tests/{uuid.uuid4().hex}"
    batch = _run(files, tmp_path / "out", gv.Cache.at(url, **s3_options), cluster_client)
    assert [item.status for item in batch.items] == ["ok"] * 3, batch.items
    assert all(item.scalars["count"] == 24 for item in batch.items)
    store = gv.FsspecStore(url, storage_options=s3_options)
    for item in batch.items[1:]:  # files done by a worker: every computed value is in S3
        record = json.loads((item.output_dir / "record.json").read_text())
        assert record["executor"] == "dask, up to 16 files a task"
        assert (item.output_dir / "overlay.png").is_file() and (item.output_dir / "report.html")
        for node in record["nodes"]:
            if node["status"] == "computed":
                assert all(store.get(key) is not None for key in node["keys"].values()), node
    assert 0 < batch.client_bytes <= 0.01 * batch.value_bytes
    again = _run(files, tmp_path / "out", gv.Cache.at(url, **s3_options), cluster_client)
    later = json.loads((again.items[-1].output_dir / "record.json").read_text())
    assert {node["status"] for node in later["nodes"]} - {"unneeded"} == {"cached"}  # from S3


def test_a_worker_killed_mid_write_costs_a_retry_and_leaves_nothing_half_written(
    cluster_client, tmp_path, s3_options
):
    import cloudpickle

    from . import killing_store

    cloudpickle.register_pickle_by_value(killing_store)
    url = f"s3://gv-tests/{uuid.uuid4().hex}"
    marker = tmp_path / "killed"
    store = killing_store.KillingStore(url, 2**30, s3_options, str(marker))
    files = _coins_files(tmp_path / "in", 3)
    batch = _run(files, tmp_path / "out", gv.Cache(gv.MemoryStore(), store), cluster_client)
    assert marker.is_file()  # a worker died while it wrote this key
    assert [item.status for item in batch.items] == ["ok"] * 3, batch.items
    assert all(item.scalars["count"] == 24 for item in batch.items)
    reader = gv.FsspecStore(url, storage_options=s3_options)
    leftovers = [p for p in reader.fs.find(reader.root) if "/.tmp-" in p]
    assert len(leftovers) == 1  # the dead writer's half entry, under its temporary name
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # every entry published is whole: none is dropped
        entries = [
            p for p in reader.fs.find(reader.root) if p.endswith(".gvc") and "/.tmp-" not in p
        ]
        for path in entries:
            assert reader.get(path.rsplit("/", 1)[-1][: -len(".gvc")]) is not None
    assert reader.get(marker.read_text()) is not None  # the retry published it whole
