"""On the process pool a batch's lanes send several files as one task
(graphvision.execution.batch_lanes): tasks shrink to one file as the batch ends, every
file runs once, and a node that kills its worker fails its own file alone."""

from __future__ import annotations

import csv
import json
import threading
from pathlib import Path
from typing import Any

import pytest

import graphvision as gv
from graphvision.execution.batch_files import BatchItem
from graphvision.execution.batch_lanes import FileLanes

from .test_batch import _counting_graph, photo

CRASHING_PLUGIN = '''
import os

import numpy as np

from graphvision import Float, Image, node


@node("crashy.score")
def score(image: Image) -> Float:
    """The image's mean; a worker process given the image of level 77 dies."""
    mean = float(np.mean(image))
    if round(mean * 255) == 77 and os.getpid() != int(os.environ["CLIENT_PID"]):
        os._exit(3)
    return mean
'''


def test_lanes_take_up_to_per_task_files_and_one_at_a_time_at_the_end():
    ready = threading.Event()
    ready.set()
    taken: list[list[int]] = []
    lock = threading.Lock()

    def lane(indices: list[int]) -> list[tuple[int, BatchItem]]:
        with lock:
            taken.append(indices)
        return [(k, BatchItem(f"{k}.png", f"out/{k}")) for k in indices]  # type: ignore[arg-type]

    lanes = FileLanes(201, 4, ready, lambda: False, per_task=8)
    done = sorted(index for index, _ in lanes.stream(lane, None))
    assert done == list(range(1, 201))  # every file once
    assert sorted(k for indices in taken for k in indices) == done
    sizes = sorted((len(indices) for indices in taken), reverse=True)
    assert sizes[0] == 8 and sizes[-4:] == [1, 1, 1, 1]  # the last files alone
    assert len(taken) < 60  # against 200 tasks of one file
    for indices in taken:  # consecutive files in a task
        assert indices == list(range(indices[0], indices[0] + len(indices)))


def _scored_on_processes(tmp_path: Path, source: str, family: str, levels: list[int]) -> Any:
    """A batch on 2 worker processes of one image per level (``in/NN.png``), each scored by
    the plugin ``source``'s node ``FAMILY.score``, into ``out/``; the workers run every file."""
    plugin = tmp_path / f"{family}.py"
    plugin.write_text(source)
    graph = gv.Graph(family)
    image = graph.input("image", "Image")
    graph.output("score", graph.add("score", f"{family}.score", image=image))
    files = [photo(tmp_path / "in" / f"{k:02d}.png", level) for k, level in enumerate(levels)]
    return gv.run_batch(
        graph,
        [str(f) for f in files],
        input="image",
        output_dir=tmp_path / "out",
        registry=gv.discover([plugin]),
        cache=None,
        executor="processes",
        workers=2,
        client_files=False,
    )


def test_a_node_that_kills_its_worker_in_a_task_of_several_files_fails_that_file_alone(
    tmp_path, monkeypatch
):
    monkeypatch.setenv("CLIENT_PID", str(__import__("os").getpid()))
    levels = [10 + 3 * k for k in range(30)]
    levels[3] = 77  # in the batch's first task of several files
    batch = _scored_on_processes(tmp_path, CRASHING_PLUGIN, "crashy", levels)
    status = [item.status for item in batch.items]
    assert status == ["ok"] * 3 + ["failed"] + ["ok"] * 26, batch.items
    assert "again when retried alone" in batch.items[3].error
    assert not (tmp_path / "out" / "03").exists()  # no half of a folder
    for written in ("01", "02"):  # whole before the worker died in their task: not run again
        assert not (tmp_path / "out" / written / "history").exists()
    for item, level in zip(batch.items, levels, strict=True):
        if item.status == "ok":
            assert item.scalars["score"] == pytest.approx(level / 255.0, abs=1e-6)
            record = json.loads((item.output_dir / "record.json").read_text())
            assert record["outputs"]["score"].startswith("Float")
    later = json.loads((batch.items[-1].output_dir / "record.json").read_text())
    assert later["executor"] == "processes, up to 8 files a task"


def test_ctrl_c_in_a_batch_of_tasks_of_several_files_leaves_each_folder_whole_or_absent(
    tmp_path,
):
    graph, registry, _ = _counting_graph(tmp_path)
    files = [photo(tmp_path / "in" / f"{k:02d}.png", 5 * k) for k in range(40)]

    def stop_at_tenth(number: int, total: int, item: Any) -> None:
        if number == 10:  # tasks of several files on both workers: Ctrl-C
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        gv.run_batch(
            graph,
            [str(f) for f in files],
            input="image",
            output_dir=tmp_path / "out",
            registry=registry,
            cache=None,
            executor="processes",
            workers=2,
            client_files=False,
            on_item=stop_at_tenth,
        )
    with (tmp_path / "out" / "batch.csv").open() as summary:
        rows = {Path(r["file"]).stem: r["status"] for r in csv.DictReader(summary)}
    assert sorted(rows) == [f"{k:02d}" for k in range(40)]  # every file, done or not
    assert sum(status == "ok" for status in rows.values()) >= 10
    for name, status in rows.items():
        folder = tmp_path / "out" / name
        if status == "ok":
            record = json.loads((folder / "record.json").read_text())
            # the first file runs node by node: on a worker forked from the client, or in
            # the client when another thread runs in it (an earlier test's)
            first = ("first file on a worker", "first file in this process")
            assert record["executor"].endswith(first if name == "00" else ("a task",))
        else:
            assert status in ("interrupted", "not run") and not folder.exists()


INTERRUPTING_PLUGIN = '''
import numpy as np

from graphvision import Float, Image, node


@node("interrupting.score")
def score(image: Image) -> Float:
    """The image's mean; the image of level 77 raises KeyboardInterrupt, as a node may."""
    mean = float(np.mean(image))
    if round(mean * 255) == 77:
        raise KeyboardInterrupt
    return mean
'''


def test_a_node_raising_keyboard_interrupt_on_a_worker_fails_its_file_alone(tmp_path):
    levels = [10 + 3 * k for k in range(20)]
    levels[5] = 77  # not the first file: the client runs that one (its Ctrl-C stops the batch)
    batch = _scored_on_processes(tmp_path, INTERRUPTING_PLUGIN, "interrupting", levels)
    status = [item.status for item in batch.items]
    assert status == ["ok"] * 5 + ["failed"] + ["ok"] * 14, batch.items
    plugin = (tmp_path / "interrupting.py").resolve()  # the node's error, as any other's
    said = f"node 'score' (op interrupting.score) failed: KeyboardInterrupt ({plugin}:12)"
    assert batch.items[5].error == said
