"""What the studio's viewers receive beside a value: the values drawn with it (matches'
image pair and inliers, epipolar points, a cloud's colours, a mask's image, a classifier's
samples), a float map's units, a classifier's confusion matrix, a network's curves."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("starlette")

import graphvision as gv
from graphvision.compiler.compile import compile_graph
from graphvision.studio import payload
from graphvision.values.ports import PortType
from graphvision.values.records import MatchesPort, MatchSet
from graphvision.values.scalars import TablePort
from graphvision_plugins.stereo._ports import DepthPort

PIPELINES = Path(__file__).parents[2] / "pipelines"


def describe_value(*args):
    """The payload, checked to be what the server can send (JSON, no NumPy scalars)."""
    found = payload.describe_value(*args)
    json.dumps(found)  # raises on a NumPy scalar
    return found


def _compiled(name: str):
    graph = gv.load_pipeline(PIPELINES / name)
    return compile_graph(graph, gv.discover(graph.plugins))


def test_matches_name_their_pair_and_the_fit_that_kept_the_inliers():
    compiled = _compiled("homography.yaml")
    matches = MatchSet(np.array([[0, 1], [2, 3]], np.int64), np.array([0.1, 0.2]))
    found = describe_value(MatchesPort, matches, compiled, "matches", "out")
    assert found["view"] == "matches"
    assert found["pair"]["inliers"] == ["fit", "inliers"]
    assert found["pair"]["a"] == {"keypoints": ["f0", "keypoints"], "image": ["gray", "out"]}
    assert found["pair"]["b"] == {"keypoints": ["f1", "keypoints"], "image": ["warp", "image"]}
    assert found["columns"]["a"] == [0, 2] and found["columns"]["b"] == [1, 3]


def test_a_fundamental_matrix_names_its_points_and_their_images():
    compiled = _compiled("fundamental.yaml")
    kind = compiled.steps["fit"].outputs["F"]
    found = describe_value(kind, np.eye(3), compiled, "fit", "F")
    assert found["view"] == "fundamental" and len(found["value"]) == 9
    assert found["pair"]["a"] == {"points": ["fit", "inliers_a"], "image": ["gray_l", "out"]}
    assert found["pair"]["b"] == {"points": ["fit", "inliers_b"], "image": ["gray_r", "out"]}


def test_a_cloud_names_its_colours_and_its_sampling_step():
    compiled = _compiled("stereo.yaml")
    points = np.random.default_rng(0).uniform(1, 2, (50_001, 3))
    kind = compiled.steps["cloud"].outputs["points"]
    found = describe_value(kind, points, compiled, "cloud", "points")
    assert found["colours"] == ["cloud", "colours"]
    assert found["step"] == 3 and len(found["points"]) == 16_667  # ceil(50 001 / 20 000)


def test_a_float_map_carries_its_units_for_the_colour_bar():
    compiled = _compiled("stereo.yaml")
    depth = np.full((16, 16), 2.0, np.float32)
    found = describe_value(DepthPort, depth, compiled, "depth", "out")
    assert found["view"] == "floatmap" and found["units"] == "depth, in the unit of the baseline"


def test_a_mask_is_tinted_over_the_image_behind_it():
    compiled = _compiled("coins.yaml")
    kind = compiled.steps["closed"].outputs["out"]
    found = describe_value(kind, np.zeros((8, 8), bool), compiled, "closed", "out")
    assert found["view"] == "mask" and found["over"] == ["gray", "out"]  # closed ← binary ← gray


def test_a_classifier_gets_its_confusion_matrix_rows_right_and_wrong_and_samples():
    compiled = _compiled("cnn_digits.yaml")
    labels = np.array([0, 0, 1, 1, 2, 2, 2], np.int64)
    predicted = np.array([0, 1, 1, 1, 2, 0, 2], np.int64)
    table = {"label": labels, "predicted": predicted, "probability": np.ones(7)}
    found = describe_value(TablePort, table, compiled, "predicted", "out")
    assert found["confusion"] == {"classes": [0, 1, 2], "counts": [[1, 1, 0], [0, 2, 0], [1, 0, 2]]}
    assert found["right"] == [[0, 0, 0], [2, 1, 1], [3, 1, 1], [4, 2, 2], [6, 2, 2]]
    assert found["wrong"] == [[1, 0, 1], [5, 2, 0]]
    assert found["samples"] == ["split", "test"]
    plain = describe_value(TablePort, {"x": np.arange(3.0)}, compiled, "predicted", "out")
    assert "confusion" not in plain


def test_samples_send_their_pixels_when_small():
    compiled = _compiled("cnn_digits.yaml")
    kind = compiled.steps["split"].outputs["test"]
    images = np.linspace(0, 1, 5 * 8 * 8, dtype=np.float32).reshape(5, 8, 8)
    samples = kind.validate(kind.value_class(images, np.arange(5, dtype=np.int64)))
    found = describe_value(kind, samples, compiled, "split", "test")
    assert found["view"] == "samples" and found["side"] == [8, 8]
    assert found["labels"] == [0, 1, 2, 3, 4] and len(found["pixels"]) == 5 * 64
    assert found["pixels"][-1] == 1.0


def test_a_trained_network_sends_its_training_curves():
    compiled = _compiled("cnn_digits.yaml")
    kind = PortType  # any value with a per-epoch history (the cnn, segmentation, detection models)
    model = SimpleNamespace(
        history=np.array([2.0, 1.0, 0.5]),
        accuracy=np.array([0.2, 0.6, 0.9]),
        held_out_accuracy=np.array([0.3, 0.5, 0.7]),
    )
    found = describe_value(kind, model, compiled, "cnn", "out")
    assert found["curves"] == {
        "loss": [2.0, 1.0, 0.5],
        "accuracy": {"training": [0.2, 0.6, 0.9], "held out": [0.3, 0.5, 0.7]},
    }  # the held-out curve too (the studio sent the training accuracy alone)
    no_accuracy = SimpleNamespace(history=np.array([1.0]), accuracy=None)
    assert describe_value(kind, no_accuracy, compiled, "cnn", "out")["curves"] == {"loss": [1.0]}
