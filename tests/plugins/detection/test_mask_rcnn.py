"""Mask R-CNN: RoIAlign on a plane, mask targets and pasting on rectangles, COCO's AP on a
hand-computed case, mask AP of true and of spoilt masks, a small mask branch trained and
measured on held-out instance scenes built here, and bad input."""

from __future__ import annotations

import numpy as np
import pytest

from graphvision_plugins import detection
from graphvision_plugins.detection import DetectionSet
from graphvision_plugins.shared.boxes import iou_matrix
from graphvision_plugins.synthetic import instance_scenes

from .test_faster_rcnn import small_backbone

pytestmark = pytest.mark.heavy  # trains networks: run first (tests/conftest.py)


def test_roi_align_samples_a_plane_exactly_at_the_bin_centres():
    rows, cols = np.mgrid[0:12, 0:16].astype(np.float64)
    plane = np.stack([2 * cols + 3 * rows + 1, -cols])  # f(x, y) on cell centres
    boxes = np.array([[4.0, 4.0, 20.0, 12.0], [7.3, 5.1, 18.9, 20.5]])
    out = detection.roi_align(plane, boxes, 2, 4)  # stride 2
    steps = (np.arange(4) + 0.5) / 4
    for box, pooled in zip(boxes, out, strict=True):
        x = (box[0] + steps * (box[2] - box[0])) / 2 - 0.5  # bin centres in cell units
        y = (box[1] + steps * (box[3] - box[1])) / 2 - 0.5
        expected = 2 * x[None, :] + 3 * y[:, None] + 1
        np.testing.assert_allclose(pooled[0], expected, atol=1e-5)
        np.testing.assert_allclose(pooled[1], np.broadcast_to(-x[None, :], (4, 4)), atol=1e-5)


def test_mask_targets_and_pasting_of_a_rectangle():
    mask = np.zeros((20, 20), bool)
    mask[4:12, 6:10] = True  # x 6..10, y 4..12
    box = np.array([[6.0, 4.0, 10.0, 12.0]])
    np.testing.assert_array_equal(detection.mask_targets(mask[None], box, 7), np.ones((1, 7, 7)))
    wide = np.array([[2.0, 4.0, 14.0, 12.0]])  # the mask fills the middle third in x
    target = detection.mask_targets(mask[None], wide, 6)[0]
    np.testing.assert_array_equal(target, np.tile([0, 0, 1, 1, 0, 0], (6, 1)))
    pasted = detection.paste_mask(np.ones((14, 14)), box[0], (20, 20))
    np.testing.assert_array_equal(pasted, mask)
    half = np.zeros((14, 14))
    half[:, :7] = 1  # the left half of the box: x 6..8
    expected = np.zeros((20, 20), bool)
    expected[4:12, 6:8] = True
    np.testing.assert_array_equal(detection.paste_mask(half, box[0], (20, 20)), expected)


def test_coco_average_precision_of_a_hand_computed_ranking():
    # hits 1, 0, 1 of 2 instances: precision 1, 1/2, 2/3 at recall 1/2, 1/2, 1; the
    # envelope is 1 for recall thresholds 0..0.50 (51 of them), 2/3 for 0.51..1 (50)
    ap = detection.coco_average_precision(np.array([True, False, True]), 2)
    assert ap == pytest.approx((51 * 1 + 50 * 2 / 3) / 101)
    # a missed instance: recall stops at 1/2, thresholds above read 0
    assert detection.coco_average_precision(np.array([True]), 2) == pytest.approx(51 / 101)


@pytest.fixture(scope="module")
def instances():
    return instance_scenes(count=12, size=48, min_scale=14, max_scale=20, touching=0.7, seed=4)


def _as_detections(scenes, scores=None):
    score = np.ones(len(scenes.xyxy)) if scores is None else scores
    return DetectionSet(scenes.xyxy, score, scenes.label, scenes.owner, len(scenes))


def test_mask_ap_of_the_true_masks_is_one_and_of_spoilt_masks_lower(instances):
    scenes, masks = instances
    found = _as_detections(scenes)
    assert detection.mask_average_precision(found, masks, scenes, masks) == 1.0
    shifted = np.roll(masks, 6, axis=2)  # moved 6 px: thin digit strokes overlap little
    iou = np.diag(detection.mask_iou(shifted, masks))
    expected = np.mean(
        [
            detection.coco_average_precision(
                iou[scenes.label == c] >= 0.5, int(np.sum(scenes.label == c))
            )
            for c in np.unique(scenes.label)
        ]
    )  # one detection per instance: each class's hits are its instances' own
    assert detection.mask_average_precision(found, shifted, scenes, masks) == pytest.approx(
        expected
    )
    assert expected < 1.0
    empty = np.zeros_like(masks)
    assert detection.mask_average_precision(found, empty, scenes, masks) == 0.0


def test_instance_scenes_hold_disjoint_visible_masks_whose_extent_is_the_box(instances):
    scenes, masks = instances
    assert masks.shape == (len(scenes.xyxy), 48, 48) and masks.dtype == bool
    for scene in range(len(scenes)):
        mine = masks[scenes.owner == scene]
        assert mine.sum(axis=0).max(initial=0) <= 1  # each pixel shows one instance
    for mask, box in zip(masks, scenes.xyxy, strict=True):
        rows, cols = np.nonzero(mask)
        np.testing.assert_array_equal(box, [cols.min(), rows.min(), cols.max() + 1, rows.max() + 1])
    # the ink is the bright part of a scene: a mask's pixels outshine the background
    bright = [scenes.images[o][m].mean() for o, m in zip(scenes.owner, masks, strict=True)]
    assert min(bright) > 0.5
    touching = 0
    for scene in range(len(scenes)):
        boxes = scenes.xyxy[scenes.owner == scene]
        touching += int((np.triu(iou_matrix(boxes, boxes), 1) > 0).sum())
    assert touching >= 3  # touching=0.7: boxes overlap in several scenes


def test_instance_scenes_refuse_impossible_settings():
    with pytest.raises(
        ValueError, match=r"max_scale \(60\) must be at most the scene's size \(48\)"
    ):
        instance_scenes(size=48, min_scale=16, max_scale=60)


def test_a_small_mask_branch_segments_held_out_instances(instances):
    """The branch, trained on a small Faster R-CNN's features, segments the true boxes of
    held-out scenes (the detector's own quality is tested in test_faster_rcnn.py)."""
    scenes, masks = instances
    backbone = small_backbone(scenes, epochs=8, learning_rate=0.02)
    model = detection.train_faster_rcnn(
        backbone,
        scenes,
        sizes=[14.0, 20.0],
        ratios=[1.0, 1.6],
        hidden=["dense 16", "relu"],
        epochs=1,
    )
    head = detection.train_mask_head(
        model,
        scenes,
        masks,
        resolution=14,
        layers=["conv 8x3", "relu"],
        jitter=2,
        epochs=10,
        batch_size=8,
    )
    assert head.history[-1] < 0.7 * head.history[0]
    held_out = instance_scenes(split="test", count=6, size=48, min_scale=14, max_scale=20, seed=9)
    known = np.isin(held_out.scenes.label, model.classes)
    truth = held_out.scenes.__class__(
        held_out.scenes.images, held_out.scenes.xyxy[known], held_out.scenes.label[known],
        held_out.scenes.owner[known],
    )  # fmt: skip
    found = _as_detections(truth)
    predicted = detection.predict_masks(model, head, truth, found)
    iou = np.diag(detection.mask_iou(predicted, held_out.masks[known]))
    assert np.median(iou) >= 0.5
    picture = detection.draw_instances(truth, found, predicted, count=4, columns=2)
    assert picture.shape == (2 * 50, 2 * 50, 3)
    with pytest.raises(ValueError, match=r"masks must hold one 48×48 mask per true box"):
        detection.train_mask_head(model, scenes, masks[:-1])
    with pytest.raises(ValueError, match=r"keep the size \(no pooling"):
        detection.train_mask_head(model, scenes, masks, layers=["conv 4x3 pad 0"], epochs=1)


def test_true_instances_are_drawn_in_colour_over_their_masks(instances):
    scenes, masks = instances
    picture = detection.draw_true_instances(scenes, masks, count=1, columns=1)
    assert picture.shape == (50, 50, 3)  # the scene and a 2-pixel margin
    coloured = np.ptp(picture[:48, :48], axis=2) > 0.01  # gray scene pixels have R = G = B
    inside = masks[scenes.owner == 0].any(axis=0)
    assert coloured[inside].all()
    with pytest.raises(ValueError, match=r"masks must hold one 48×48 mask per true box"):
        detection.draw_true_instances(scenes, masks[1:])
