"""A one-task-per-file batch's client runs files itself while its workers start
(graphvision.execution.batch_lanes), and leaves the batch's last files to the workers."""

from __future__ import annotations

import json
import threading
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any

import pytest

import graphvision as gv

from .test_batch import _counting_graph, photo


class _SlowToStart:
    """An executor whose workers (threads of this process) start only once ``released``: its
    tasks are files that travel as to other processes (``encodes_values``)."""

    encodes_values = True
    name = "slow-start"
    width = 1

    def __init__(self) -> None:
        self.released = threading.Event()
        self._pool = ThreadPoolExecutor(1)

    def submit(self, fn: Any, /, *args: Any) -> Future:
        def started() -> Any:
            if not self.released.wait(timeout=60):
                raise TimeoutError("never released")
            return fn(*args)

        return self._pool.submit(started)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        self.released.set()
        self._pool.shutdown(wait=wait, cancel_futures=cancel_futures)


def _run(graph, registry, files, tmp_path, pool: _SlowToStart, **options: Any) -> Any:
    """The batch of ``files`` on ``pool``, two files at once, then the pool shut down."""
    batch = gv.run_batch(
        graph,
        [str(f) for f in files],
        input="image",
        output_dir=tmp_path / "out",
        registry=registry,
        cache=None,
        executor=pool,
        files_at_once=2,
        **options,
    )
    pool.shutdown()
    return batch


def _executors(batch: Any) -> list[str]:
    return [
        json.loads((item.output_dir / "record.json").read_text())["executor"]
        for item in batch.items
    ]


def test_the_client_runs_files_until_a_worker_is_ready_and_leaves_the_last_to_workers(
    tmp_path,
):
    graph, registry, log = _counting_graph(tmp_path)
    levels = [10, 60, 110, 160, 210]
    files = [photo(tmp_path / "in" / f"{k}.png", level) for k, level in enumerate(levels)]
    pool = _SlowToStart()
    batch = _run(
        graph, registry, files, tmp_path, pool, client_files=True,
        on_item=lambda number, total, item: number == 2 and pool.released.set(),
    )  # fmt: skip
    assert [item.status for item in batch.items] == ["ok"] * len(files), batch.items
    for item, level in zip(batch.items, levels, strict=True):
        assert item.scalars["score"] == pytest.approx(2.0 * level / 255.0, abs=1e-6)
    assert log.read_text().splitlines().count("model") == 1  # seeded in the client's files too
    executors = _executors(batch)
    assert executors[1] == "slow-start, in the client while the workers started"
    assert executors[3:] == ["slow-start, one task per file"] * 2  # the last files: workers'
    assert batch.client_bytes > 0  # what the workers' files sent; the client's send nothing


def test_a_first_file_that_cannot_be_read_does_not_fail_the_others(tmp_path):
    graph, registry, _ = _counting_graph(tmp_path)
    (tmp_path / "in").mkdir()
    bad = tmp_path / "in" / "0.png"
    bad.write_text("not an image")
    files = [bad, photo(tmp_path / "in" / "1.png", 60), photo(tmp_path / "in" / "2.png", 110)]
    pool = _SlowToStart()
    pool.released.set()
    batch = _run(graph, registry, files, tmp_path, pool)
    assert [item.status for item in batch.items] == ["failed", "ok", "ok"], batch.items
    assert "is not a readable image" in batch.items[0].error
    assert batch.items[2].scalars["score"] == pytest.approx(2.0 * 110 / 255.0, abs=1e-6)


def test_without_client_files_every_further_file_waits_for_the_workers(tmp_path):
    graph, registry, _ = _counting_graph(tmp_path)
    files = [photo(tmp_path / "in" / f"{k}.png", 40 * k) for k in range(5)]
    pool = _SlowToStart()
    batch = _run(
        graph, registry, files, tmp_path, pool,
        on_item=lambda number, total, item: number == 1 and pool.released.set(),
    )  # fmt: skip
    assert [item.status for item in batch.items] == ["ok"] * len(files), batch.items
    assert _executors(batch)[1:] == ["slow-start, one task per file"] * 4
