"""Small report pages of coins.yaml and cnn_digits.yaml with values made here (the graphs
compiled, nothing run): a label map and the image it was found in, a classifier's results
with its samples, a network with its training curves."""

from __future__ import annotations

import base64
import functools
import json
import re
import zlib
from pathlib import Path
from typing import Any

import numpy as np

import graphvision as gv
from graphvision.compiler.compile import compile_graph
from graphvision.execution.record import RunRecord
from graphvision.views.html import html_report

PIPELINES = Path(__file__).parents[2] / "pipelines"
GRAY = 0.5  # the image the labels are tinted over: one gray


@functools.cache
def compiled(name: str) -> Any:
    graph = gv.load_pipeline(PIPELINES / name)
    return compile_graph(graph, gv.discover(graph.plugins))


def labels_map() -> np.ndarray:
    """24×32, label 1 a block in the middle (its centre pixel among them), 2 a corner block."""
    labels = np.zeros((24, 32), np.int32)
    labels[8:16, 10:22] = 1
    labels[0:4, 0:4] = 2
    return labels


def coins_page(with_image: bool = True) -> str:
    """coins.yaml's report: its labels output, and (``with_image``) the gray image kept
    as an intermediate (the image the labels were found in)."""
    graph = compiled("coins.yaml")
    gray = np.full((24, 32), GRAY, np.float32)
    outputs = {"count": 2, "regions": {"area": np.array([96.0, 16.0])}, "labels": labels_map(),
               "overlay": np.zeros((24, 32, 3), np.float32)}  # fmt: skip
    kept = {"gray": (graph.steps["gray"].outputs["out"], gray)} if with_image else None
    return html_report(graph, outputs, RunRecord("coins", "threads"), intermediates=kept)


def classifier_values() -> tuple[Any, dict[str, np.ndarray], Any]:
    """A network with curves, 30 predictions (every third wrong), their 30 samples."""
    from graphvision_plugins import cnn
    from graphvision_plugins.recognition._types import SampleSet

    rng = np.random.default_rng(0)
    labels = np.arange(30, dtype=np.int64) % 3
    predicted = labels.copy()
    predicted[::3] = (labels[::3] + 1) % 3
    samples = SampleSet(rng.uniform(0, 1, (30, 4, 4)).astype(np.float32), labels)
    spec = json.dumps({"input": [1, 4, 4], "layers": ["dense 3"]})
    network = cnn.NetworkModel(
        spec, rng.normal(0, 0.1, 51), np.arange(3, dtype=np.int64),
        np.array([1.2, 0.7, 0.4, 0.3]), np.array([0.4, 0.7, 0.8, 0.9]),
        np.array([0.3, 0.6, 0.7, 0.75]),
    )  # fmt: skip
    table = {"label": labels, "predicted": predicted, "probability": np.full(30, 0.5)}
    return network, table, samples


def cnn_page() -> str:
    """cnn_digits.yaml's report with the classifier values and split.test kept."""
    graph = compiled("cnn_digits.yaml")
    network, table, samples = classifier_values()
    outputs = {"accuracy": 0.7, "linear_accuracy": 0.6, "network": network,
               "predictions": table, "examples": np.zeros((8, 8, 3), np.float32)}  # fmt: skip
    kept = {"split.test": (graph.steps["split"].outputs["test"], samples)}
    return html_report(graph, outputs, RunRecord("cnn_digits", "threads"), intermediates=kept)


def page_data(page: str) -> dict[str, Any]:
    """The JSON the page's script draws its values from."""
    found = re.search(r'<script type="application/json" data-values="1">(.*?)</script>', page)
    assert found, "the page holds no values for its viewers"
    return json.loads(found.group(1))


def cloud_points() -> np.ndarray:
    """21 000 points on a tilted plane: more than the 3-D view takes (every second one)."""
    rng = np.random.default_rng(1)
    xy = rng.uniform(-1, 1, (21_000, 2))
    return np.column_stack([xy, 5 + 0.5 * xy[:, 0]])


def stereo_page() -> str:
    """stereo.yaml's report with its cloud and the cloud's colours (all red)."""
    graph = compiled("stereo.yaml")
    points = cloud_points()
    colours = np.tile(np.array([1.0, 0.0, 0.0], np.float32), (len(points), 1))
    outputs = {"cloud": points, "cloud_colours": colours}
    return html_report(graph, outputs, RunRecord("stereo", "threads"))


def homography_page() -> str:
    """homography.yaml's report: 3 matches, 2 of them the fit's inliers, with both
    keypoint sets and both images kept as intermediates."""
    from graphvision.values.records import KeypointSet, MatchSet

    graph = compiled("homography.yaml")

    def keypoints(xy: list[list[float]]) -> KeypointSet:
        n = len(xy)
        return KeypointSet(np.array(xy, np.float64), np.ones(n), np.zeros(n), np.ones(n),
                           np.tile(np.eye(2), (n, 1, 1)))  # fmt: skip

    whole = MatchSet(np.array([[0, 2], [1, 1], [2, 0]], np.int64), np.zeros(3))
    values = {"f0.keypoints": keypoints([[1, 2], [3, 4], [5, 6]]),
              "f1.keypoints": keypoints([[10, 20], [30, 40], [50, 60]]),
              "gray": np.zeros((70, 40), np.float32), "warp.image": np.ones((80, 60), np.float32),
              "matches": whole, "fit.inliers": whole.take(np.array([0, 2]))}  # fmt: skip
    kept = {}
    for where, value in values.items():
        node, _, port = where.partition(".")
        step = graph.steps[node]
        kept[where] = (step.outputs[port or next(iter(step.outputs))], value)
    return html_report(graph, {}, RunRecord("homography", "threads"), intermediates=kept)


def decoded(raw: dict[str, Any]) -> np.ndarray:
    """An array of the page's JSON as its script decodes it (views/scripted.py ``_raw``)."""
    data = np.frombuffer(zlib.decompress(base64.b64decode(raw["deflate"])), np.uint8)
    if raw.get("planes"):  # the bytes plane by plane: every value's first byte, then...
        data = np.ascontiguousarray(data.reshape(raw["planes"], -1).T)
    values = data.view(np.dtype(raw["dtype"]).newbyteorder("<")).reshape(raw["shape"])
    if not raw.get("scale"):
        return values
    real = raw.get("offset", 0) + values.astype(np.float64) / raw["scale"]
    if "nan" in raw:
        real[values == raw["nan"]] = np.nan
    return real.astype(np.float32)


def stereo_maps() -> dict[str, np.ndarray]:
    """stereo.yaml's maps: a 30×40 disparity in quarter pixels (each value printed exactly
    at 4 digits) with one invalid pixel, a 60×80 depth of whole numbers, a 12×16 RGB
    picture in eighths (not 8-bit levels) and a 12×16 one of 8-bit levels."""
    rng = np.random.default_rng(7)
    disparity = (rng.integers(4, 256, (30, 40)) / 4).astype(np.float32)
    disparity[0, 0] = np.nan
    depth = rng.integers(1000, 9000, (60, 80)).astype(np.float32)
    eighths = (rng.integers(0, 9, (12, 16, 3)) / 8).astype(np.float32)
    levels = rng.integers(0, 256, (12, 16, 3)).astype(np.float32) / np.float32(255)
    return {"disparity": disparity, "depth": depth, "disparity_picture": eighths,
            "cloud_picture": levels}  # fmt: skip


def stereo_maps_page() -> str:
    """stereo.yaml's report of :func:`stereo_maps` (with ``scripted.MAX_VALUES`` as set)."""
    graph = compiled("stereo.yaml")
    return html_report(graph, stereo_maps(), RunRecord("stereo", "threads"))
