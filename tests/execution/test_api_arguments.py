"""The Python API takes what people pass and names what it cannot take."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import graphvision as gv

from ..conftest import PIPELINES

COINS = PIPELINES / "coins.yaml"


def test_a_pipeline_files_path_runs_as_its_graph():
    by_path = gv.run(str(COINS), outputs="count", cache=None).outputs
    by_pathlib = gv.run(COINS, outputs=["count"], cache=None).outputs
    assert by_path == by_pathlib == {"count": 24}


def test_a_pathlib_input_reads_like_the_same_path_as_text(tmp_path):
    import imageio.v3 as iio
    from skimage import data

    image = tmp_path / "coins.png"
    iio.imwrite(image, data.coins())
    as_path = gv.run(COINS, inputs={"image": image}, outputs="count", cache=None)
    as_text = gv.run(COINS, inputs={"image": str(image)}, outputs="count", cache=None)
    assert as_path.outputs == as_text.outputs == {"count": 24}


@pytest.mark.parametrize(
    ("arguments", "error", "message"),
    [
        ({"graph": 3}, TypeError, "graph must be a gv.Graph, a compiled graph or a pipeline"),
        ({"outputs": 5}, TypeError, "outputs must be a name or a list of names, got 5"),
        ({"overrides": ["a.b=1"]}, TypeError, "overrides must be a dict from names"),
        ({"inputs": ["x.png"]}, TypeError, "inputs must be a dict from names"),
        ({"cache": "some/folder"}, TypeError, r"for a folder: gv.Cache.at\(path\)"),
        ({"executor": 3}, TypeError, "executor must be one of sync, threads, processes, dask"),
        ({"executor": "gpu"}, ValueError, "executor must be one of .*got 'gpu'"),
        ({"workers": 0}, ValueError, "workers must be at least 1"),
        ({"workers": "2"}, TypeError, "workers must be a whole number"),
    ],
)
def test_arguments_of_the_wrong_kind_are_named(arguments, error, message):
    graph = arguments.pop("graph", COINS)
    with pytest.raises(error, match=message):
        gv.run(graph, **arguments)


def test_batch_and_sweep_check_their_arguments_the_same_way(tmp_path):
    with pytest.raises(TypeError, match="output_dir must be a folder's path, got None"):
        gv.run_batch(COINS, "*.png", input="image", output_dir=None)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"cache must be a gv\.Cache"):
        gv.sweep(COINS, {"disk.size": [3, 5]}, cache=str(tmp_path))  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="grid must be a dict"):
        gv.sweep(COINS, [("disk.size", [3])])  # type: ignore[arg-type]
    result = gv.sweep(str(COINS), {"disk.size": [3, 5]}, outputs="count", executor="sync")
    assert [row["count"] for row in result.rows] == [24, 24]
    assert np.all([row["status"] == "ok" for row in result.rows])


def test_a_graph_built_in_python_is_taken_as_before():
    graph = gv.Graph("g")
    x = graph.input("x", "Float", default=1.0)
    graph.output("y", x)
    assert gv.run(graph, cache=None).outputs == {"y": 1.0}
    assert Path(COINS).is_file()


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (("some/folder",), r"takes a store, got str: .*Cache\.at\(folder\)"),
        ((None, "some/folder"), r"takes a store, got str"),
        (("disk",), r"takes a MemoryStore, got DiskStore: a disk store goes second"),
    ],
)
def test_a_cache_made_from_the_wrong_parts_is_refused_when_made(tmp_path, arguments, message):
    made = tuple(gv.DiskStore(tmp_path / "store") if a == "disk" else a for a in arguments)
    with pytest.raises(TypeError, match=message):
        gv.Cache(*made)
