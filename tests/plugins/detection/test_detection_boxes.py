"""Box maths (IoU, NMS, box coding, anchors) on hand-made boxes, and selective search with
proposals.yaml against the issue's recall on the coins."""

from __future__ import annotations

import numpy as np
import pytest

import graphvision as gv
from graphvision_plugins import detection
from graphvision_plugins.recognition import non_max_suppression as recognition_nms
from graphvision_plugins.shared import boxes as _boxes

from ...conftest import PIPELINES


def test_iou_of_hand_made_boxes():
    a = np.array([[0.0, 0, 10, 10], [0, 0, 4, 4]])
    b = np.array([[5.0, 0, 15, 10], [20, 20, 30, 30], [0, 0, 10, 10], [1, 1, 3, 3]])
    expected = np.array(
        [
            [50 / 150, 0, 1, 4 / 100],  # half overlap: 50 / (100 + 100 - 50)
            [0, 0, 16 / 100, 4 / 16],
        ]
    )
    np.testing.assert_array_equal(_boxes.iou_matrix(a, b), expected)


def test_nms_keeps_the_best_of_each_overlapping_group():
    boxes = np.array(
        [[0.0, 0, 10, 10], [1, 0, 11, 10], [20, 20, 30, 30], [0, 0, 10, 10.5], [21, 20, 31, 30]]
    )
    scores = np.array([0.9, 0.95, 0.5, 0.3, 0.6])
    # 1 (0.95) suppresses 0 (IoU 9/11) and 3; 4 (0.6) suppresses 2 (IoU 9/11)
    np.testing.assert_array_equal(_boxes.non_max_suppression(boxes, scores, 0.5), [1, 4])
    # at 0.95 only box 3 goes: it overlaps box 0 by 100 / 105 > 0.95 (and 1 by 90 / 115)
    np.testing.assert_array_equal(_boxes.non_max_suppression(boxes, scores, 0.95), [1, 0, 4, 2])
    assert recognition_nms is _boxes.non_max_suppression  # one copy for both families


def test_nms_refuses_nan_scores():
    with pytest.raises(ValueError, match=r"box scores must not be NaN \(row 1 is\)"):
        _boxes.non_max_suppression(np.array([[0.0, 0, 1, 1]] * 2), np.array([1.0, np.nan]), 0.5)


def test_box_coding_of_hand_made_boxes_and_its_inverse():
    proposal = np.array([[10.0, 20, 30, 60]])  # centre (20, 40), size 20 × 40
    target = np.array([[15.0, 10, 55, 50]])  # centre (35, 30), size 40 × 40
    np.testing.assert_allclose(
        _boxes.encode_boxes(proposal, target), [[15 / 20, -10 / 40, np.log(2), 0]], rtol=1e-15
    )
    rng = np.random.default_rng(0)
    corner = rng.uniform(0, 100, (50, 2))
    boxes = np.hstack([corner, corner + rng.uniform(1, 50, (50, 2))])
    others = np.hstack([corner + 3, corner + rng.uniform(5, 80, (50, 2))])
    decoded = _boxes.decode_boxes(boxes, _boxes.encode_boxes(boxes, others))
    assert np.abs(decoded - others).max() < 1e-9


def test_anchors_are_centred_with_the_given_area_and_ratio():
    anchors = _boxes.anchor_boxes(2, 3, 16, (32.0, 64.0), (0.5, 1.0, 2.0))
    assert anchors.shape == (2 * 3 * 2 * 3, 4)
    width, height = anchors[:, 2] - anchors[:, 0], anchors[:, 3] - anchors[:, 1]
    np.testing.assert_allclose(width * height, np.tile(np.repeat([32.0**2, 64.0**2], 3), 6))
    np.testing.assert_allclose(height / width, np.tile([0.5, 1, 2], 12))
    centres = (anchors[:, :2] + anchors[:, 2:]) / 2
    np.testing.assert_allclose(centres[:6], [[8, 8]] * 6)  # cell (0, 0)
    np.testing.assert_allclose(centres[-1], [40, 24])  # cell (row 1, column 2)
    node = detection.anchors(np.zeros((48, 64), np.float32), stride=16, sizes=[32], ratios=[1])
    assert len(node) == 3 * 4


def test_boxes_of_negative_width_are_refused():
    with pytest.raises(ValueError, match=r"box row 1 has width -2 and height 5"):
        _boxes.check_boxes(np.array([[0.0, 0, 1, 1], [5, 0, 3, 5]]))
    found = detection.DetectionSet(
        np.array([[0.0, 0, 4, 4], [6, 1, 2, 9]]), np.ones(2), np.zeros(2, np.int64),
        np.zeros(2, np.int64), 1,
    )  # fmt: skip
    with pytest.raises(gv.PortValueError, match=r"Detections box row 1 has width -4 and height 8"):
        detection.DetectionsPort.validate(found)
    with pytest.raises(ValueError, match=r"box row 0 is not finite"):
        _boxes.check_boxes(np.array([[0.0, np.nan, 1, 1]]))
    bad = gv.BoxSet(np.array([[5.0, 0, 3, 5]]), np.array([1.0]))
    with pytest.raises(gv.PortValueError, match="x0 < x1 and y0 < y1"):
        detection.recall(bad, bad)


def test_nan_scores_are_refused_naming_the_box():
    boxes = gv.BoxSet(np.array([[0.0, 0, 4, 4], [1, 1, 5, 5]]), np.array([1.0, np.nan]))
    with pytest.raises(
        ValueError, match=r"detection\.recall: input 'proposals' box 1 has a NaN score"
    ):
        detection.recall(boxes, boxes)


# --- selective search ----------------------------------------------------------------


def test_selective_search_finds_drawn_squares():
    """Three flat squares on a flat background: each is a Felzenszwalb region whose box is
    proposed exactly."""
    image = np.full((60, 80), 0.2, np.float32)
    truth = np.array([[5.0, 5, 20, 20], [30, 10, 50, 40], [60, 30, 75, 55]])
    for (x0, y0, x1, y1), level in zip(truth.astype(int), (0.9, 0.6, 0.4), strict=True):
        image[y0:y1, x0:x1] = level
    boxes = detection.selective_search(image, scales=[50.0], colour_spaces=["rgb"])
    found = _boxes.iou_matrix(truth, boxes.xyxy).max(axis=1)
    np.testing.assert_array_equal(found, [1, 1, 1])
    assert len(np.unique(boxes.xyxy, axis=0)) == len(boxes)  # de-duplicated


def test_an_empty_scene_gives_no_proposals():
    boxes = detection.selective_search(np.full((40, 40), 0.5, np.float32))
    assert len(boxes) == 0


def test_an_unknown_similarity_is_refused_naming_it():
    with pytest.raises(ValueError, match=r"similarity set 'colour\+shape' names \['shape'\]"):
        detection.selective_search(np.zeros((8, 8), np.float32), similarities=["colour+shape"])


def test_proposals_pipeline_meets_the_issue_recall_on_the_coins():
    out = gv.run(gv.load_pipeline(PIPELINES / "proposals.yaml")).outputs
    truth = out["truth"].xyxy
    assert len(truth) == 24  # the photograph's 24 coins (coins.yaml's segmentation)
    sides = truth[:, 2:] - truth[:, :2]
    assert (sides > 25).all() and (sides < 80).all()  # every box is one coin
    assert out["recall"] >= 0.9 and out["count"] <= 1000
    curve = out["curve"]
    assert (np.diff(curve["recall"]) >= 0).all()  # more proposals never lose a coin
    assert curve["recall"][-1] == out["recall"]
