"""ROI pooling against crop-and-pool, mAP on hand-made detections, the synthetic scenes,
bad input, and rcnn.yaml against the issue's truths."""

from __future__ import annotations

import numpy as np
import pytest

import graphvision as gv
from graphvision_plugins import cnn, detection
from graphvision_plugins.shared.boxes import iou_matrix
from graphvision_plugins.synthetic import SceneSet, digit_scenes

from ...conftest import PIPELINES

pytestmark = pytest.mark.heavy  # trains networks: run first (tests/conftest.py)

# --- ROI pooling -----------------------------------------------------------------------


def test_roi_pooling_equals_crop_and_pool_on_integer_boxes():
    rng = np.random.default_rng(0)
    features = rng.normal(size=(3, 20, 24))
    stride, size = 2, 3
    boxes = np.array([[0.0, 0, 12, 12], [6, 4, 42, 40], [12, 2, 48, 20]])  # sides 6·k cells
    pooled = detection.pool_rois(features, boxes, stride, size)
    for box, out in zip(boxes.astype(int) // stride, pooled, strict=True):
        crop = features[:, box[1] : box[3], box[0] : box[2]]
        c, h, w = crop.shape
        direct = crop.reshape(c, size, h // size, size, w // size).max(axis=(2, 4))
        np.testing.assert_array_equal(out, direct)


def test_roi_pooling_cells_follow_the_documented_rounding():
    features = np.arange(25, dtype=np.float64).reshape(1, 5, 5)
    pooled = detection.pool_rois(features, np.array([[0.0, 0, 5, 5]]), 1, 2)[0, 0]
    # 5 rows in 2 cells: rows [0, 3) and [2, 5) (floor start, ceil end), the same in x
    np.testing.assert_array_equal(pooled, [[12, 14], [22, 24]])
    # a box of 2.6 × 1.4 pixels at stride 1 rounds half up to cells x 1..4, y 1..2
    tiny = detection.pool_rois(features, np.array([[0.6, 0.6, 3.2, 2.0]]), 1, 1)
    assert tiny[0, 0, 0, 0] == features[0, 1:2, 1:3].max()


def test_roi_pool_node_on_an_image():
    image = np.zeros((16, 16), np.float32)
    image[5, 9] = 1.0
    boxes = gv.BoxSet(np.array([[8.0, 4, 12, 8], [0, 0, 4, 4]]), np.zeros(2))
    pooled = detection.roi_pool(image, boxes, size=2)
    assert pooled.shape == (2, 1, 2, 2)
    np.testing.assert_array_equal(pooled[0, 0], [[1, 0], [0, 0]])
    assert pooled[1].max() == 0


def test_a_roi_outside_the_feature_map_is_refused_naming_it():
    boxes = gv.BoxSet(np.array([[0.0, 0, 4, 4], [10, 2, 30, 6]]), np.zeros(2))
    with pytest.raises(ValueError, match=r"ROI 1 \[10.0, 2.0, 30.0, 6.0\] lies outside the 8×8"):
        detection.roi_pool(np.zeros((8, 8), np.float32), boxes, stride=2)


def test_cell_features_gather_the_3_by_3_neighbourhood():
    maps = np.arange(2 * 3 * 4, dtype=np.float64).reshape(2, 3, 4)
    features = detection.cell_features(maps)
    assert features.shape == (12, 18)
    # cell (row 1, column 2): channel 0 then channel 1, each its 3×3 block row by row
    np.testing.assert_array_equal(features[6, :9], maps[0, 0:3, 1:4].ravel())
    np.testing.assert_array_equal(features[6, 9:], maps[1, 0:3, 1:4].ravel())
    # a corner cell sees zeros beyond the border
    np.testing.assert_array_equal(features[0, :9], [0, 0, 0, 0, 0, 1, 0, 4, 5])


def test_scene_recall_counts_boxes_found_by_the_first_proposals():
    scenes = _scenes([[0, 0, 10, 10], [20, 20, 30, 30], [5, 5, 15, 15]], [1, 1, 2], [0, 0, 1], 2)
    proposals = _found(
        [[20, 20, 30, 30], [0, 0, 10, 10], [5, 5, 15, 16]], [0.9, 0.8, 0.7], [-1] * 3, [0, 0, 1], 2
    )
    assert detection.scene_recall(proposals, scenes) == 1.0
    assert detection.scene_recall(proposals, scenes, count=1) == 2 / 3  # scene 0 loses one


# --- scoring ---------------------------------------------------------------------------


def _scenes(boxes: list[list[float]], labels: list[int], owner: list[int], count: int):
    return SceneSet(
        np.zeros((count, 40, 40), np.float32),
        np.array(boxes, np.float64).reshape(-1, 4),
        np.array(labels, np.int64),
        np.array(owner, np.int64),
    )


def _found(boxes, scores, labels, owner, count):
    return detection.DetectionSet(
        np.array(boxes, np.float64).reshape(-1, 4),
        np.array(scores, np.float64),
        np.array(labels, np.int64),
        np.array(owner, np.int64),
        count,
    )


def test_average_precision_of_hand_made_detections():
    scenes = _scenes([[0, 0, 10, 10], [20, 20, 30, 30], [5, 5, 15, 15]], [1, 1, 2], [0, 0, 1], 2)
    perfect = _found(scenes.xyxy, [0.9, 0.8, 0.7], [1, 1, 2], [0, 0, 1], 2)
    assert detection.mean_average_precision(perfect, scenes) == 1.0
    assert detection.true_positive_iou(perfect, scenes) == 1.0
    # class 1: a false positive ranked first, then both boxes: precision 1/2, 2/3 at recall
    # 1/2, 1 -> AP = 0.5 · 2/3 + 0.5 · 2/3 = 2/3; class 2: a duplicate after the hit -> 1
    mixed = _found(
        [[30, 0, 40, 10], [0, 0, 10, 10], [20, 20, 30, 30], [5, 5, 15, 15], [5, 5, 15, 15]],
        [0.95, 0.9, 0.8, 0.7, 0.6],
        [1, 1, 1, 2, 2],
        [0, 0, 0, 1, 1],
        2,
    )
    assert detection.mean_average_precision(mixed, scenes) == pytest.approx((2 / 3 + 1) / 2)
    # a box of the right place but the wrong class is no true positive
    wrong = _found([[0, 0, 10, 10]], [0.9], [2], [0], 2)
    assert detection.mean_average_precision(wrong, scenes) == 0.0


def test_regression_targets_shift_a_box_onto_its_truth_in_the_iou():
    scenes = _scenes([[0, 0, 10, 10]], [1], [0], 1)
    shifted = _found([[2, 0, 12, 10]], [0.9], [1], [0], 1)  # IoU 80 / 120
    assert detection.true_positive_iou(shifted, scenes) == pytest.approx(80 / 120)


def test_nms_works_within_each_scene_and_class():
    found = _found(
        [[0, 0, 10, 10], [1, 0, 11, 10], [0, 0, 10, 10], [0, 0, 10, 10]],
        [0.8, 0.9, 0.7, 0.6],
        [1, 1, 2, 1],
        [0, 0, 0, 1],
        2,
    )
    kept = detection.nms(found, iou=0.3)
    # scene 0: box 1 (0.9) drops box 0 of its class, box 2 is another class; scene 1 alone
    np.testing.assert_array_equal(kept.score, [0.9, 0.7, 0.6])
    np.testing.assert_array_equal(kept.label, [1, 2, 1])
    np.testing.assert_array_equal(kept.owner, [0, 0, 1])


# --- scenes ----------------------------------------------------------------------------


def test_digit_scenes_hold_their_digits_in_disjoint_boxes():
    scenes = digit_scenes(count=12, size=64, seed=3)
    assert len(scenes) == 12 and scenes.images.shape[1:] == (64, 64)
    for scene in range(12):
        boxes, _ = scenes.boxes_of(scene)
        assert 1 <= len(boxes) <= 3
        for x0, y0, x1, y1 in boxes.astype(int):
            inside = scenes.images[scene, y0:y1, x0:x1]
            assert inside.max() > 0.9  # the white ink: backgrounds stay below 0.45
        np.testing.assert_array_equal(iou_matrix(boxes, boxes), np.eye(len(boxes)))
    again = digit_scenes(count=12, size=64, seed=3)
    np.testing.assert_array_equal(again.images, scenes.images)


def test_digit_scenes_refuse_impossible_settings():
    with pytest.raises(
        ValueError, match=r"max_scale \(28\) must be at most the scene's size \(20\)"
    ):
        digit_scenes(size=20, min_scale=16, max_scale=28)
    with pytest.raises(ValueError, match=r"min_objects \(3\) must be at most max_objects \(2\)"):
        digit_scenes(min_objects=3, max_objects=2)


# --- a small trained detector for bad input -----------------------------------------


@pytest.fixture(scope="module")
def small_detector():
    scenes = digit_scenes(count=10, size=48, min_scale=14, max_scale=20, seed=5)
    proposals = detection.scene_proposals(scenes)
    crops = detection.roi_samples(scenes, proposals, size=12, jitter=1)
    outputs = f"dense {len(np.unique(crops.labels))}"  # the classes drawn and background
    backbone = cnn.train(
        crops, layers=["conv 4x3", "relu", "maxpool 2", outputs], epochs=1, batch_size=64
    )
    return detection.train_head(backbone, scenes, proposals, feature_layers=2, epochs=1)


def test_an_empty_scene_gives_no_proposals_and_no_detections(small_detector):
    empty = _scenes([], [], [], 2)
    proposals = detection.scene_proposals(empty)
    assert len(proposals) == 0
    found = detection.detect(small_detector, empty, proposals)
    assert len(found) == 0 and found.scenes == 2


def test_detector_round_trips_and_refuses_mismatched_parts(small_detector):
    port = detection.DetectorPort
    back = port.decode(*port.encode(port.validate(small_detector)))
    np.testing.assert_array_equal(back.regression, small_detector.regression)
    broken = detection.DetectorModel(
        **{**small_detector.__dict__, "regression": small_detector.regression[:3]}
    )
    with pytest.raises(gv.PortValueError, match=r"regressors for \d+ classes plus background"):
        port.validate(broken)


def test_a_fully_connected_feature_layer_is_refused_naming_it(small_detector):
    scenes = digit_scenes(count=2, size=48, min_scale=14, max_scale=20, seed=6)
    proposals = detection.scene_proposals(scenes)
    crops = detection.roi_samples(scenes, proposals, size=12, jitter=0)
    outputs = f"dense {len(np.unique(crops.labels))}"
    backbone = cnn.train(crops, layers=["dense 8", "relu", outputs], epochs=1)
    with pytest.raises(ValueError, match=r"feature layer 0 'dense 8' is fully connected"):
        detection.train_head(backbone, scenes, proposals, feature_layers=2)


def test_detections_port_refuses_nan_scores():
    bad = _found([[0, 0, 4, 4]], [np.nan], [1], [0], 1)
    with pytest.raises(gv.PortValueError, match="scores must not be NaN"):
        detection.DetectionsPort.validate(bad)


# --- the issue's pipeline --------------------------------------------------------------


def test_rcnn_pipeline_meets_the_issue_truths():
    """mAP@0.5 ≥ 0.8 on held-out synthetic scenes, and box regression raises the mean IoU
    of the true positives."""
    out = gv.run(gv.load_pipeline(PIPELINES / "rcnn.yaml")).outputs
    assert out["map50"] >= 0.8
    assert out["tp_iou"] > out["tp_iou_without_regression"]
    assert out["drawing"].shape == (2 * 82, 4 * 82, 3)
    # the region proposal network's first 10 boxes per scene find more digits than
    # selective search's (measured 0.92 against 0.79; 0.52 before selective search
    # ranked its proposals by persistence, issue 24)
    assert out["rpn_recall_10"] >= 0.9
    assert out["rpn_recall_10"] > out["selective_search_recall_10"] >= 0.7


def test_box_regression_ridge_in_the_dual_equals_the_primal_and_pool_is_bounded():
    """More features than regions: the ridge is solved through the N × N system; the
    answer is the primal one with the bias unpenalised (the normal equations written out)."""
    from graphvision_plugins.detection._rcnn import _ridge

    rng = np.random.default_rng(0)
    for count, width in ((200, 30), (40, 300)):
        features, targets = rng.normal(size=(count, width)), rng.normal(size=(count, 4))
        design = np.hstack([features, np.ones((count, 1))])
        penalty = np.eye(width + 1) * 10.0
        penalty[-1, -1] = 0.0
        primal = np.linalg.solve(design.T @ design + penalty, design.T @ targets)
        np.testing.assert_allclose(_ridge(features, targets, 10.0), primal, atol=1e-10)
    graph = gv.load_pipeline(PIPELINES / "rcnn.yaml").with_overrides({"detector.pool": 40})
    refused = r"--set detector\.pool=40: .*less than or equal to 16"
    with pytest.raises(gv.PipelineError, match=refused):
        gv.compile_graph(graph, gv.discover())  # refused before anything runs


@pytest.mark.parametrize("node_id", ["crops", "detector", "rpn"])
def test_negative_iou_above_positive_iou_is_refused_before_the_run(node_id):
    graph = gv.load_pipeline(PIPELINES / "rcnn.yaml")
    overrides = {f"{node_id}.negative_iou": 0.6, f"{node_id}.positive_iou": 0.5}
    refused = rf"--set {node_id}\..*: detection\.\w+: negative_iou 0.6 must not exceed positive"
    with pytest.raises(gv.PipelineError, match=refused):
        gv.compile_graph(graph.with_overrides(overrides), gv.discover())
