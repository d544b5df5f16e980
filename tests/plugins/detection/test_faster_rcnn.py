"""Faster R-CNN: the ROI pooling's argmax, the NMS kernel, anchor labels, the losses'
gradients against finite differences, a small detector trained and measured on held-out
scenes built here, reproducibility, and bad input."""

from __future__ import annotations

import numpy as np
import pytest

import graphvision as gv
from graphvision_plugins import cnn, detection
from graphvision_plugins.detection import DetectionSet
from graphvision_plugins.detection._faster_train import (
    Settings,
    anchor_labels,
    backward_with_input,
    head_gradient,
    rpn_gradient,
    with_input_gradient,
)
from graphvision_plugins.shared.boxes import iou_matrix, non_max_suppression
from graphvision_plugins.synthetic import digit_scenes

from ...conftest import PIPELINES

pytestmark = pytest.mark.heavy  # trains networks: run first (tests/conftest.py)


def test_roi_pooling_with_argmax_equals_roi_pooling_and_points_at_each_maximum():
    from graphvision_plugins.detection._faster_kernels import roi_max_pool_argmax
    from graphvision_plugins.detection._kernels import roi_max_pool

    rng = np.random.default_rng(0)
    features = rng.normal(size=(3, 11, 13))
    rois = np.array([[0, 0, 13, 11], [2, 3, 7, 5], [5, 1, 6, 2]], np.int64)
    pooled, where = roi_max_pool_argmax(features, rois, 3)
    np.testing.assert_array_equal(pooled, roi_max_pool(features, rois, 3))
    np.testing.assert_array_equal(features.ravel()[where], pooled)
    channel = where // (11 * 13)
    np.testing.assert_array_equal(
        channel, np.broadcast_to(np.arange(3)[None, :, None, None], where.shape)
    )


def test_greedy_nms_kernel_keeps_what_the_shared_nms_keeps():
    from graphvision_plugins.detection._faster_kernels import greedy_nms

    rng = np.random.default_rng(1)
    corner = rng.uniform(0, 40, (200, 2))
    boxes = np.hstack([corner, corner + rng.uniform(4, 20, (200, 2))])
    score = rng.uniform(size=200)
    order = np.argsort(-score, kind="stable")
    for iou in (0.3, 0.7):
        expected = order[np.isin(order, non_max_suppression(boxes, score, iou))]
        np.testing.assert_array_equal(order[greedy_nms(boxes[order], iou, 1000)], expected)
        np.testing.assert_array_equal(order[greedy_nms(boxes[order], iou, 5)], expected[:5])
    # by hand: the second box overlaps the first by 0.6 and goes; the third is disjoint
    hand = np.array([[0.0, 0, 10, 10], [0, 0, 10, 6], [20, 20, 30, 30]])
    np.testing.assert_array_equal(greedy_nms(hand, 0.5, 10), [0, 2])


def test_anchor_labels_follow_the_papers_rule():
    truth = np.array([[10.0, 10, 30, 30], [50, 50, 56, 70]])
    anchors = np.array(
        [
            [10.0, 10, 30, 30],  # the first true box: object
            [60, 0, 80, 20],  # far from both: background
            [14, 10, 34, 30],  # IoU 16/24 = 0.67: neither
            [48, 48, 64, 64],  # the second box's best anchor (IoU 0.2): object
        ]
    )
    label, match = anchor_labels(anchors, truth, Settings(positive_iou=0.7, negative_iou=0.3))
    assert iou_matrix(anchors[3:], truth[1:])[0, 0] < 0.3
    np.testing.assert_array_equal(label, [1, 0, -1, 1])
    np.testing.assert_array_equal(match[[0, 3]], [0, 1])


def _numeric_gradient(loss, x, step=1e-6):
    grad = np.zeros_like(x)
    for index in np.ndindex(x.shape):
        up, down = x.copy(), x.copy()
        up[index] += step
        down[index] -= step
        grad[index] = (loss(up) - loss(down)) / (2 * step)
    return grad


def test_rpn_and_head_losses_have_the_gradients_of_their_formulas():
    rng = np.random.default_rng(2)
    out = rng.normal(size=(10, 3, 2))  # 2 anchor shapes on a 3 × 2 map
    index = np.array([0, 3, 5, 8])
    label = np.array([1, 0, 1, 0])
    target = rng.normal(size=(4, 4)) * 2
    loss = lambda o: rpn_gradient(o, 2, index, label, target)[0]  # noqa: E731
    np.testing.assert_allclose(rpn_gradient(out, 2, index, label, target)[1],
                               _numeric_gradient(loss, out), atol=1e-6)  # fmt: skip
    scores = rng.normal(size=(5, 5 * 3 + 1))  # 3 classes
    classes = np.array([0, 2, 3, 0, 1])
    deltas = rng.normal(size=(5, 4)) * 2
    loss = lambda s: head_gradient(s, classes, deltas, 3)[0]  # noqa: E731
    np.testing.assert_allclose(head_gradient(scores, classes, deltas, 3)[1],
                               _numeric_gradient(loss, scores), atol=1e-6)  # fmt: skip


def test_backward_with_input_gives_the_inputs_gradient():
    architecture = with_input_gradient(
        cnn.build_architecture((2, 5, 5), ["conv 3x3", "relu", "dense 2"])
    )
    rng = np.random.default_rng(3)
    weights = rng.normal(size=architecture.size)
    x = rng.normal(size=(1, 2, 5, 5))
    probe = rng.normal(size=(1, 2))
    _, saved = architecture.forward(weights, x, keep=True)
    d_x, d_w = backward_with_input(architecture, weights, probe, saved)
    numeric = _numeric_gradient(
        lambda v: float((architecture.forward(weights, v)[0] * probe).sum()), x
    )
    np.testing.assert_allclose(d_x, numeric, atol=1e-6)
    np.testing.assert_allclose(d_w, architecture.backward(weights, probe, saved))


# --- a small detector trained here -----------------------------------------------------


def small_backbone(scenes, epochs=3, learning_rate=0.05):
    """A backbone trained on crops of seeded random boxes of the scenes (no selective
    search: fast), labelled by their overlap with the true boxes."""
    rng = np.random.default_rng(0)
    corner = rng.uniform(0, 30, (len(scenes) * 20, 2))
    boxes = np.hstack([corner, corner + rng.uniform(10, 18, corner.shape)])
    owner = np.repeat(np.arange(len(scenes)), 20)
    proposals = DetectionSet(
        boxes, np.zeros(len(boxes)), np.full(len(boxes), -1), owner, len(scenes)
    )
    crops = detection.roi_samples(scenes, proposals, size=12, jitter=2, seed=0)
    outputs = f"dense {len(np.unique(crops.labels))}"
    return cnn.train(
        crops, layers=["conv 8x3", "relu", "maxpool 2", "conv 8x3", "relu", outputs],
        epochs=epochs, batch_size=32, learning_rate=learning_rate, seed=0,
    )  # fmt: skip


@pytest.fixture(scope="module")
def small_model():
    scenes = digit_scenes(count=40, size=48, min_scale=14, max_scale=20, classes=[0, 1], seed=5)
    backbone = small_backbone(scenes)
    train = dict(feature_layers=5, frozen_layers=3, sizes=[14.0, 20.0], ratios=[1.0, 1.6],
                 hidden=["dense 32", "relu"], epochs=6, learning_rate=0.02, seed=0)  # fmt: skip
    return backbone, scenes, train, detection.train_faster_rcnn(backbone, scenes, **train)


def test_a_small_faster_rcnn_finds_held_out_digits(small_model):
    """Trained on 40 scenes of zeros and ones, measured on 20 held-out scenes made here."""
    _, _, _, model = small_model
    held_out = digit_scenes(split="test", count=20, size=48, min_scale=14, max_scale=20,
                            classes=[0, 1], seed=77)  # fmt: skip
    found = detection.faster_rcnn(model, held_out, proposals=50)
    assert detection.scene_recall(found.proposals, held_out, count=50) >= 0.9
    assert detection.mean_average_precision(detection.nms(found.detections), held_out) >= 0.7
    assert model.history[-1] < 0.6 * model.history[0]


def test_training_is_reproducible_and_the_model_round_trips(small_model):
    backbone, scenes, train, model = small_model
    again = detection.train_faster_rcnn(backbone, scenes, **{**train, "epochs": 1})
    twice = detection.train_faster_rcnn(backbone, scenes, **{**train, "epochs": 1})
    np.testing.assert_array_equal(again.head_weights, twice.head_weights)
    frozen = sum(int(np.prod(s)) for p in backbone.parsed().parameter_shapes[:3] for s in p)
    np.testing.assert_array_equal(model.feature_weights[:frozen], backbone.weights[:frozen])
    assert not np.array_equal(
        model.feature_weights[frozen:], backbone.weights[frozen : model.feature_weights.size]
    )
    port = detection.FasterRcnnPort
    back = port.decode(*port.encode(port.validate(model)))
    np.testing.assert_array_equal(back.rpn_weights, model.rpn_weights)
    broken = detection.FasterRcnnModel(
        **{**model.__dict__, "head_weights": model.head_weights[:-1]}
    )
    with pytest.raises(gv.PortValueError, match=r"FasterRcnn weights .* do not match its layers"):
        port.validate(broken)


def test_bad_settings_are_refused_naming_them(small_model):
    backbone, scenes, train, model = small_model
    with pytest.raises(ValueError, match=r"frozen_layers \(5\) must be below feature_layers \(5\)"):
        detection.train_faster_rcnn(backbone, scenes, **{**train, "frozen_layers": 5})
    with pytest.raises(ValueError, match=r"anchor size 90 with ratio 1 is a 90×90 box, larger"):
        detection.train_faster_rcnn(backbone, scenes, **{**train, "sizes": [90.0]})
    three = digit_scenes(count=3, size=48, min_scale=14, max_scale=20, classes=[0, 1], seed=8)
    two = digit_scenes(count=2, size=48, min_scale=14, max_scale=20, classes=[0, 1], seed=8)
    with pytest.raises(ValueError, match=r"the proposals cover 3 scenes but 2 scenes are given"):
        detection.draw_proposals(two, detection.faster_rcnn(model, three).proposals)
    graph = gv.load_pipeline(PIPELINES / "faster_rcnn.yaml").with_overrides({"found.proposals": 0})
    with pytest.raises(
        gv.PipelineError, match=r"--set found\.proposals=0: .*greater than or equal to 1"
    ):
        gv.compile_graph(graph, gv.discover())


def test_drawings_and_loss_curve(small_model):
    _, _, _, model = small_model
    scenes = digit_scenes(count=4, size=48, min_scale=14, max_scale=20, classes=[0, 1], seed=8)
    found = detection.faster_rcnn(model, scenes, proposals=10)
    picture = detection.draw_proposals(scenes, found.proposals, count=4, columns=2, per_scene=3)
    assert picture.shape == (2 * 50, 2 * 50, 3)
    red = (picture[..., 0] > 0.9) & (picture[..., 1] < 0.2)
    assert red.any()
    curve = detection.faster_rcnn_loss(model)
    np.testing.assert_array_equal(curve["epoch"], np.arange(1, 7))
