"""The LBP cascade scanned as OpenCV scans (``step`` 0): the positions of OpenCV's rule
counted by hand on a cascade that passes every window, the astronaut's face against
OpenCV's box and window count (recorded with their call), and recall on a few seeds of
scenes with known faces."""

from __future__ import annotations

import numpy as np
import pytest
import skimage.data

from graphvision import ParameterError
from graphvision_plugins import recognition as rec
from graphvision_plugins import synthetic as syn
from graphvision_plugins.recognition._lbp_scan import lbp_windows, scan_step


def everything_cascade() -> rec.LBPCascadeModel:
    """One stage whose one weak classifier passes every window of 9 × 6 pixels (a flat
    image's code is 255, every neighbour's sum reaching the centre's)."""
    subsets = np.zeros((1, 8), np.uint32)
    subsets[0, 7] = np.uint32(1 << 31)  # code 255
    return rec.LBPCascadeModel(
        rects=np.array([[0, 0, 3, 2]], np.int64),
        feature=np.array([0], np.int64),
        subsets=subsets,
        leaves=np.array([[1.0, -1.0]]),
        stage=np.array([0], np.int64),
        stage_threshold=np.array([0.5]),
        height=6,
        width=9,
    )


def test_opencvs_rule_steps_two_reduced_pixels_up_to_scale_2_then_one():
    # OpenCV's cascadedetect.cpp: yStep = factor > 2. ? 1 : 2 (for LBP and Haar)
    assert [scan_step(s, 0) for s in (1.0, 1.9487, 2.0, 2.0001, 4.5)] == [2, 2, 2, 1, 1]
    assert [scan_step(s, 3) for s in (1.0, 2.5)] == [3, 3]


def test_step_0_visits_the_positions_of_opencvs_rule():
    flat = np.full((40, 40), 0.5, np.float32)
    boxes, _, _ = lbp_windows(flat, everything_cascade(), scale_factor=2.0, min_size=9, step=0)
    widths = np.round(boxes[:, 2] - boxes[:, 0]).astype(int)
    # a 9 × 6 window at scale s on the 40 × 40 image reduced to ⌊40 / s⌋ pixels a side:
    # s = 1: 35 rows × 32 columns of positions, every second: 18 × 16;
    # s = 2: 20 pixels, 15 × 12 positions, every second: 8 × 6;
    # s = 4: 10 pixels, 5 × 2 positions, every one (s > 2); s = 8 does not fit
    assert {w: int((widths == w).sum()) for w in (9, 18, 36)} == {9: 288, 18: 48, 36: 10}
    assert len(boxes) == 346
    at_2 = boxes[widths == 18]
    assert set(np.unique(at_2[:, :2] % 4).tolist()) == {0.0}  # 2 reduced pixels = 4 px
    every, _, _ = lbp_windows(flat, everything_cascade(), scale_factor=2.0, min_size=9, step=1)
    assert len(every) == 35 * 32 + 15 * 12 + 5 * 2


def test_a_negative_step_is_refused():
    flat = np.full((40, 40), 0.5, np.float32)
    with pytest.raises(ParameterError, match=r"'step'.*greater than or equal to 0"):
        rec.lbp_detect(flat, everything_cascade(), step=-1)


# OpenCV 5.0.0 (opencv-contrib-python-headless): cv2.CascadeClassifier(path).detectMultiScale2(
#     np.round(skimage.data.astronaut().mean(axis=2) / 255 * 255).astype(np.uint8), 1.1, 3)
# on scikit-image's lbpcascade_frontalface.xml with its "featuhreParams" tag corrected:
# one face (x, y, w, h) = (171, 64, 104, 104), grouped from 17 windows.
OPENCV_FACE = (171, 64, 275, 168)
OPENCV_WINDOWS = 17


def test_the_astronaut_scanned_as_opencv_scans_is_found_where_opencv_finds_her():
    gray = (skimage.data.astronaut().mean(axis=2) / 255).astype(np.float32)
    found = rec.lbp_detect(gray, rec.lbp_cascade(), scale_factor=1.1, step=0, min_neighbours=3)
    best = found.xyxy[0]
    iou = rec.iou_matrix(best[None], np.array([OPENCV_FACE], float))[0, 0]
    assert iou > 0.8
    # as many windows as OpenCV's (step 1 gathers about four times as many)
    assert abs(found.score[0] - OPENCV_WINDOWS) <= 4
    assert len(found) <= 2


def test_step_0_finds_the_faces_of_scenes_it_was_not_tuned_on():
    cascade = rec.lbp_cascade()
    hits = faces = false = scenes = 0
    for seed in (100, 101):
        made = syn.face_scenes(photos=("coffee", "rocket"), seed=seed, side=256, max_side=100)
        found = rec.lbp_detect_scenes(made.images, cascade, step=0, min_neighbours=3)
        scores = rec.face_scores(found, made.faces)
        hits += round(scores.recall * len(made.faces))
        faces += len(made.faces)
        false += round(scores.false_positives * made.faces.scenes)
        scenes += made.faces.scenes
    assert faces >= 6
    assert hits / faces >= 0.9 and false / scenes <= 0.5  # face_detect.yaml's aim
