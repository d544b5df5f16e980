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
