"""Faces in photographs: OpenCV's LBP cascade read from XML and evaluated on graphvision's
integral images against a NumPy evaluation written here, OpenCV's grouping and
detections (recorded with their calls) and scikit-image's detector (called here);
scenes with known faces; the lfw-trained Haar cascade's early rejection against its full
evaluation; face_detect.yaml against the issue's complaints."""

from __future__ import annotations

import re

import numpy as np
import pytest
import skimage.data

import graphvision as gv
from graphvision_plugins import recognition as rec
from graphvision_plugins import synthetic as syn
from graphvision_plugins.recognition._group_rectangles import group_rectangles
from graphvision_plugins.recognition._lbp_scan import lbp_windows, resampled_integral
from graphvision_plugins.recognition._scenes import SceneBoxSet
from graphvision_plugins.recognition._types import SampleSet, recipe_of
from graphvision_plugins.recognition._windows import _haar_cascade_windows, _haar_windows, _score
from graphvision_plugins.synthetic._face_collage import ASTRONAUT_FACE, photograph

from ...conftest import PIPELINES

pytestmark = pytest.mark.heavy  # trains networks: run first (tests/conftest.py)


@pytest.fixture(scope="module")
def cascade():
    return rec.lbp_cascade()


@pytest.fixture(scope="module")
def astronaut_gray():
    return (skimage.data.astronaut().mean(axis=2) / 255).astype(np.float32)


def iou(a, b):
    return float(rec.iou_matrix(np.array([a], float), np.array([b], float))[0, 0])


def xywh_to_xyxy(x, y, w, h):
    return (x, y, x + w, y + h)


# --- reading OpenCV's XML -----------------------------------------------------------------


def test_the_built_in_cascade_is_read_whole(cascade):
    with open(skimage.data.lbp_frontal_face_cascade_filename()) as file:
        text = file.read()
    # counted here on the text itself, not by the parser
    assert len(cascade.stage_threshold) == len(re.findall("<stageThreshold>", text)) == 20
    assert len(cascade.feature) == len(re.findall("<internalNodes>", text)) == 139
    assert len(cascade.rects) == len(re.findall("<rect>", text)) == 136
    assert (cascade.height, cascade.width) == (24, 24)
    first = re.search(r"<internalNodes>\s*([-\d\s]+)</internalNodes>", text).group(1).split()
    assert cascade.feature[0] == int(first[2]) == 46
    assert cascade.subsets[0].tolist() == [int(v) % 2**32 for v in first[3:]]
    assert cascade.leaves[0].tolist() == [-0.6543210148811340, 0.8888888955116272]
    assert cascade.stage_threshold[0] == -0.7520892024040222
    assert np.bincount(cascade.stage)[:3].tolist() == [3, 4, 4]


TINY = """<?xml version="1.0"?>
<opencv_storage><cascade type_id="opencv-cascade-classifier">
  <stageType>BOOST</stageType><featureType>LBP</featureType>
  <height>6</height><width>9</width>
  <stageNum>2</stageNum>
  <stages>
    <_><maxWeakCount>1</maxWeakCount><stageThreshold>0.5</stageThreshold>
      <weakClassifiers><_>
        <internalNodes>0 -1 1 0 0 0 0 -2147483648 0 0 0</internalNodes>
        <leafValues>1.0 -1.0</leafValues></_></weakClassifiers></_>
    <_><maxWeakCount>2</maxWeakCount><stageThreshold>-5</stageThreshold>
      <weakClassifiers>
        <_><internalNodes>0 -1 0 -1 -1 -1 -1 -1 -1 -1 -1</internalNodes>
          <leafValues>0.25 -0.25</leafValues></_>
        <_><internalNodes>0 -1 1 0 0 0 0 1 0 0 0</internalNodes>
          <leafValues>2.0 3.0</leafValues></_></weakClassifiers></_>
  </stages>
  <features><_><rect>0 0 1 1</rect></_><_><rect>0 0 3 2</rect></_></features>
</cascade></opencv_storage>"""


def test_a_small_cascade_is_read_field_by_field():
    model = rec.parse_opencv_cascade(TINY, "tiny")
    assert model.rects.tolist() == [[0, 0, 1, 1], [0, 0, 3, 2]]
    assert model.feature.tolist() == [1, 0, 1] and model.stage.tolist() == [0, 1, 1]
    # −2³¹ is bit 31 of word 4 (code 159); −1 is all 32 bits
    assert model.subsets[0].tolist() == [0, 0, 0, 0, 2**31, 0, 0, 0]
    assert model.subsets[1].tolist() == [2**32 - 1] * 8
    assert model.leaves.tolist() == [[1.0, -1.0], [0.25, -0.25], [2.0, 3.0]]
    assert model.stage_threshold.tolist() == [0.5, -5.0]
    assert model.stage_end.tolist() == [1, 3]


@pytest.mark.parametrize(
    "change, message",
    [(("<featureType>LBP", "<featureType>HAAR"), "is a HAAR cascade; graphvision reads LBP"),
     (("0 -1 1 0 0 0 0 1 0 0 0", "1 -1 1 0 0 0 0 1 0 0 0 7"), "expected a stump"),
     (("<rect>0 0 3 2</rect>", "<rect>0 0 4 2</rect>"), r"feature 1 .* must lie inside the 9×6"),
     (("<leafValues>2.0 3.0", "<leafValues>2.0 x"), "expected float values, got '2.0 x'"),
     (("<stageThreshold>0.5</stageThreshold>", ""), "stage 0 has no <stageThreshold>"),
     (("</opencv_storage>", ""), "is not XML")],
)  # fmt: skip
def test_a_broken_cascade_file_is_refused_with_what_is_wrong(change, message):
    with pytest.raises(ValueError, match=message):
        rec.parse_opencv_cascade(TINY.replace(*change), "tiny.xml")


def test_a_cascade_round_trips_through_the_array_encoding(cascade, tmp_path):
    arrays, meta = rec.LBPCascadePort.encode(cascade)
    assert all(not a.dtype.hasobject for a in arrays.values())
    back = rec.LBPCascadePort.validate(rec.LBPCascadePort.decode(arrays, meta))
    for name in arrays:
        np.testing.assert_array_equal(getattr(back, name), getattr(cascade, name))
    path = tmp_path / "cascade.xml"
    path.write_text(TINY)
    assert rec.read_opencv_cascade(path).source == str(path)
    with pytest.raises(FileNotFoundError, match="no such cascade file"):
        rec.read_opencv_cascade(tmp_path / "missing.xml")


def tiny_cascade(code: int) -> rec.LBPCascadeModel:
    """One stage, one weak classifier on the 3 × 3 blocks of 3 × 2 pixels filling a 9 × 6
    window: the window passes when its MB-LBP code is ``code``."""
    subsets = np.zeros((1, 8), np.uint32)
    subsets[0, code >> 5] = np.uint32(1 << (code & 31))
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


@pytest.mark.parametrize(
    "block, bit",
    [((0, 0), 128), ((0, 1), 64), ((0, 2), 32), ((1, 2), 16), ((2, 2), 8), ((2, 1), 4),
     ((2, 0), 2), ((1, 0), 1)],
)  # fmt: skip
def test_mb_lbp_bits_go_clockwise_from_the_top_left_block(block, bit):
    image = np.full((6, 9), 0.2, np.float32)
    image[2:4, 3:6] = 0.5  # the centre block is brighter than all but one neighbour
    r, c = block
    image[2 * r : 2 * r + 2, 3 * c : 3 * c + 3] = 0.9
    boxes, _, _ = lbp_windows(image, tiny_cascade(bit), min_size=9, max_size=9)
    assert boxes.tolist() == [[0.0, 0.0, 9.0, 6.0]]
    others = [rec.lbp_detect(image, tiny_cascade(code), min_size=9, max_size=9,
                             min_neighbours=0) for code in (0, 255, bit ^ 255)]  # fmt: skip
    assert [len(found) for found in others] == [0, 0, 0]


def test_a_flat_window_sets_every_bit_as_opencv_does_on_ties():
    flat = np.full((6, 9), 0.37, np.float32)  # equal sums: s_i >= s_c everywhere
    assert len(rec.lbp_detect(flat, tiny_cascade(255), min_neighbours=0, min_size=9)) == 1


def reference_windows(image, model, step=1):
    """Every window of a gray image at scale 1 that passes the cascade, evaluated with
    plain NumPy block sums (no integral image), and its last stage's margin."""
    found = {}
    height, width = image.shape
    order = [(0, 0), (0, 1), (0, 2), (1, 2), (2, 2), (2, 1), (2, 0), (1, 0)]
    for top in range(0, height - model.height + 1, step):
        for left in range(0, width - model.width + 1, step):
            margin = 0.0
            for s, threshold in enumerate(model.stage_threshold):
                total = 0.0
                for k in np.flatnonzero(model.stage == s):
                    x, y, w, h = model.rects[model.feature[k]]
                    block = image[top + y : top + y + 3 * h, left + x : left + x + 3 * w]
                    sums = block.reshape(3, h, 3, w).sum(axis=(1, 3), dtype=np.float64)
                    code = sum(
                        1 << (7 - i) for i, (r, c) in enumerate(order)
                        if sums[r, c] >= sums[1, 1] - 1e-9
                    )  # fmt: skip
                    word = int(model.subsets[k, code >> 5])
                    total += model.leaves[k, 0 if (word >> (code & 31)) & 1 else 1]
                margin = total - threshold
                if margin < 0:
                    break
            if margin >= 0:
                found[(left, top)] = margin
    return found


def test_the_integral_image_cascade_equals_block_sums_window_by_window(cascade, astronaut_gray):
    small = astronaut_gray.reshape(128, 4, 128, 4).mean(axis=(1, 3))  # her face is ~24 px
    crop = small[:60, 30:100]
    expected = reference_windows(crop, cascade)
    boxes, margins, evaluated = lbp_windows(crop, cascade, min_size=24, max_size=24)
    got = {(int(b[0]), int(b[1])): m for b, m in zip(boxes, margins, strict=True)}
    assert len(expected) >= 3 and got.keys() == expected.keys()
    np.testing.assert_allclose([got[k] for k in expected], list(expected.values()), atol=1e-9)
    # early rejection: far fewer weak classifiers than windows × 139
    windows = (60 - 23) * (70 - 23)
    assert evaluated < 0.2 * windows * len(cascade.feature)


@pytest.mark.parametrize("scale, factor", [(2.0, 1), (1.5, 2), (2.5, 2)])
def test_a_scale_level_is_the_integral_image_of_the_area_reduced_image(scale, factor):
    rng = np.random.default_rng(0)
    image = rng.random((31, 47))
    # the image's pixels split into factor × factor equal parts, then summed over
    # squares of scale × factor parts: exact area sums on the reduced grid
    fine = np.kron(image, np.ones((factor, factor))) / factor**2
    side = int(scale * factor)
    rows, cols = fine.shape[0] // side, fine.shape[1] // side
    reduced = fine[: rows * side, : cols * side].reshape(rows, side, cols, side).sum(axis=(1, 3))
    padded = np.zeros((image.shape[0] + 1, image.shape[1] + 1))
    padded[1:, 1:] = image.cumsum(0).cumsum(1)
    level = resampled_integral(padded, scale)
    np.testing.assert_allclose(level[1 : rows + 1, 1 : cols + 1],
                               reduced.cumsum(0).cumsum(1), atol=1e-9)  # fmt: skip


# --- grouping --------------------------------------------------------------------------

RECTS = [
    [100, 100, 50, 50], [102, 98, 52, 49], [99, 101, 50, 52], [101, 100, 48, 50],
    [103, 102, 50, 50],  # five alike
    [300, 300, 40, 40], [302, 301, 41, 40],  # two alike
    [110, 110, 20, 20], [111, 110, 20, 21], [110, 111, 21, 20],  # three inside the five
    [400, 50, 60, 60], [402, 52, 60, 60], [401, 49, 61, 61], [399, 51, 60, 59],  # four
]  # fmt: skip


@pytest.mark.parametrize(
    "threshold, rects, weights",
    # OpenCV 4.10: cv2.groupRectangles(RECTS, threshold, 0.2) -> (rects, weights)
    [(1, [[101, 100, 50, 50], [301, 300, 40, 40], [400, 50, 60, 60]], [5, 2, 4]),
     (2, [[101, 100, 50, 50], [400, 50, 60, 60]], [5, 4]),
     (3, [[101, 100, 50, 50], [400, 50, 60, 60]], [5, 4])],
)  # fmt: skip
def test_grouping_matches_opencv_group_rectangles(threshold, rects, weights):
    xyxy = np.array([xywh_to_xyxy(*r) for r in RECTS], np.float64)
    boxes, members = group_rectangles(xyxy, threshold, 0.2)
    order = np.lexsort((boxes[:, 1], boxes[:, 0]))
    got = np.column_stack([boxes[:, :2], boxes[:, 2:] - boxes[:, :2]])[order]
    np.testing.assert_array_equal(np.round(got), rects)  # OpenCV rounds the means
    assert members[order].tolist() == weights


# --- against the reference detectors ----------------------------------------------------

# OpenCV 4.10 (and 5.0 contrib): cv2.CascadeClassifier(path).detectMultiScale(
#     cv2.cvtColor(astronaut, cv2.COLOR_RGB2GRAY), 1.1, 3) on scikit-image's file with its
# "featuhreParams" tag corrected (OpenCV refuses the file as shipped), (x, y, w, h);
# the mirror image is np.ascontiguousarray(gray[:, ::-1]).
OPENCV_ASTRONAUT = (171, 64, 104, 104)
OPENCV_MIRRORED = (243, 67, 94, 94)


def test_the_astronaut_and_her_mirror_image_are_found_where_opencv_and_skimage_find_her(
    cascade, astronaut_gray
):
    from skimage.feature import Cascade

    reference = Cascade(skimage.data.lbp_frontal_face_cascade_filename())
    for image, opencv in ((astronaut_gray, OPENCV_ASTRONAUT),
                          (astronaut_gray[:, ::-1], OPENCV_MIRRORED)):  # fmt: skip
        found = rec.lbp_detect(np.ascontiguousarray(image), cascade)
        assert len(found) == 1 if image is astronaut_gray else len(found) <= 2
        ours = found.xyxy[0]
        (theirs,) = reference.detect_multi_scale(
            image, scale_factor=1.2, step_ratio=1, min_size=(60, 60), max_size=(123, 123)
        )
        skimage_box = xywh_to_xyxy(theirs["c"], theirs["r"], theirs["width"], theirs["height"])
        assert iou(ours, xywh_to_xyxy(*opencv)) > 0.8
        assert iou(ours, skimage_box) > 0.75


def test_the_astronauts_face_box_is_the_mean_of_opencvs_haar_cascades():
    # cv2.CascadeClassifier(cv2.data.haarcascades + name).detectMultiScale(
    #     cv2.cvtColor(astronaut, cv2.COLOR_RGB2GRAY), 1.1, 3), OpenCV 4.10, (x, y, w, h)
    haar = {
        "haarcascade_frontalface_default.xml": (177, 66, 95, 95),
        "haarcascade_frontalface_alt.xml": (176, 65, 98, 98),  # and (265, 323, 72, 72)
        "haarcascade_frontalface_alt2.xml": (177, 66, 97, 97),
        "haarcascade_frontalface_alt_tree.xml": (175, 64, 102, 102),
    }
    mean = np.mean([xywh_to_xyxy(*box) for box in haar.values()], axis=0)
    np.testing.assert_allclose(ASTRONAUT_FACE, mean)
    _, mirrored = photograph("astronaut_mirrored")
    np.testing.assert_allclose(mirrored[0], [512 - mean[2], mean[1], 512 - mean[0], mean[3]])


# --- scenes with known faces ----------------------------------------------------------------


def test_a_collage_pastes_gray_faces_exactly_at_its_boxes():
    photo, _ = photograph("coffee")
    collage = syn.face_collage(photo="coffee", faces=3, seed=4)
    boxes = collage.faces.xyxy.astype(int)
    assert len(boxes) == 3 and collage.image.shape == photo.shape
    inside = np.zeros(photo.shape[:2], bool)
    for x0, y0, x1, y1 in boxes:
        assert 40 <= x1 - x0 == y1 - y0 <= 120  # squares of 40–120 px
        patch = collage.image[y0:y1, x0:x1]
        assert np.array_equal(patch[..., 0], patch[..., 1])  # gray: R = G = B
        assert not np.array_equal(patch, photo[y0:y1, x0:x1])
        inside[y0:y1, x0:x1] = True
    np.testing.assert_array_equal(collage.image[~inside], photo[~inside])  # nothing else
    overlap = rec.iou_matrix(collage.faces.xyxy, collage.faces.xyxy)
    assert (overlap[~np.eye(3, dtype=bool)] == 0).all()
    again = syn.face_collage(photo="coffee", faces=3, seed=4)
    np.testing.assert_array_equal(again.image, collage.image)
    other = syn.face_collage(photo="coffee", faces=3, seed=5)
    assert not np.array_equal(other.faces.xyxy, collage.faces.xyxy)


def test_pasted_faces_are_the_ones_lfw_faces_holds_out():
    from skimage.transform import resize

    split = rec.lfw_faces()
    held_out = split.test.images[split.test.labels == 1].reshape(25, -1)
    trained = split.train.images[split.train.labels == 1].reshape(75, -1)
    faces = np.concatenate([held_out, trained])  # rows 0–24 held out, 25–99 trained on
    for lfw, pool in (("test", range(25)), ("train", range(25, 100))):
        collage = syn.face_collage(photo="rocket", faces=4, lfw=lfw, seed=2)
        for x0, y0, x1, y1 in collage.faces.xyxy.astype(int):
            patch = resize(collage.image[y0:y1, x0:x1, 0], (25, 25), anti_aliasing=True)
            distance = np.abs(faces - patch.reshape(1, -1)).mean(axis=1)
            nearest = int(np.argmin(distance))  # a shrunk copy of one of them
            assert nearest in pool and distance[nearest] < 0.05
            assert np.sort(distance)[1] > 2 * distance[nearest]


def test_face_scenes_keep_the_astronaut_and_scale_the_others_before_pasting():
    from skimage.transform import resize

    scenes = syn.face_scenes(photos=("astronaut", "astronaut_mirrored", "chelsea"), seed=3)
    assert scenes.images.shape == (3, 512, 512) and scenes.faces.scenes == 3
    np.testing.assert_allclose(scenes.faces.boxes_of(0)[0], [ASTRONAUT_FACE])
    astronaut = skimage.data.astronaut().mean(axis=2) / 255
    np.testing.assert_allclose(scenes.images[0], astronaut, atol=1e-6)
    np.testing.assert_allclose(scenes.images[1], astronaut[:, ::-1], atol=1e-6)
    # chelsea (300 × 451) covers 512 × 770, centre-cropped to columns 129–640
    cat = skimage.data.chelsea().mean(axis=2) / 255
    expected = resize(cat, (512, 770), order=1, anti_aliasing=False)[:, 129:641]
    faces = scenes.faces.boxes_of(2)[0]
    assert 1 <= len(faces) <= 3 and ((faces[:, 2:] - faces[:, :2]) >= 40).all()
    outside = np.ones((512, 512), bool)
    for x0, y0, x1, y1 in faces.astype(int):  # pasted after the scaling, at their sides
        outside[y0:y1, x0:x1] = False
    np.testing.assert_allclose(scenes.images[2][outside], expected[outside], atol=1e-5)


def test_face_scene_parameters_are_checked_before_anything_runs():
    with pytest.raises(gv.ParameterError, match=r"min_side \(100\) must be at most max_side"):
        syn.face_collage(min_side=100, max_side=50)
    with pytest.raises(gv.ParameterError, match=r"max_side \(300\) must be at most side \(256\)"):
        syn.face_scenes(max_side=300, side=256)
    with pytest.raises(gv.ParameterError, match="photo"):
        syn.face_collage(photo="camera")  # the cameraman's face has no known box


# --- scoring ---------------------------------------------------------------------------


def known_faces():
    faces = np.array([[10, 10, 30, 30], [50, 50, 70, 70], [5, 5, 25, 25]], np.float64)
    return SceneBoxSet(faces, np.ones(3), np.array([0, 0, 1], np.int64), 3)


def test_face_scores_count_hits_duplicates_and_misses_by_hand():
    found = SceneBoxSet(
        np.array([[10, 10, 30, 30],  # scene 0 face 0 exactly: IoU 1
                  [12, 10, 32, 30],  # the same face again: a false positive
                  [50, 55, 70, 75],  # face 1 shifted by 5 of 20: IoU 15·20/(2·400−300) = 0.6
                  [60, 0, 79, 9],    # nothing there
                  [40, 40, 60, 60]], np.float64),  # scene 1: misses its face
        np.array([9.0, 8.0, 7.0, 6.0, 5.0]),
        np.array([0, 0, 0, 0, 1], np.int64),
        3,
    )  # fmt: skip
    scores = rec.face_scores(found, known_faces())
    assert scores.recall == pytest.approx(2 / 3)
    assert scores.false_positives == pytest.approx(3 / 3)  # three false boxes, three scenes
    assert scores.face_iou == pytest.approx((1.0 + 0.6) / 2)
    assert scores.table["found"].tolist() == [2, 0, 0]
    assert scores.table["false_positives"].tolist() == [2, 1, 0]
    assert scores.table["faces"].tolist() == [2, 1, 0]


def test_the_better_scored_box_claims_a_face_first():
    found = SceneBoxSet(np.array([[12, 10, 32, 30], [10, 10, 30, 30]], np.float64),
                        np.array([1.0, 2.0]), np.array([0, 0], np.int64), 3)  # fmt: skip
    scores = rec.face_scores(found, known_faces())
    assert scores.face_iou == pytest.approx(1.0) and scores.false_positives == pytest.approx(1 / 3)


def test_scores_of_other_scenes_are_refused_with_what_differs():
    found = SceneBoxSet(np.zeros((0, 4)), np.zeros(0), np.zeros(0, np.int64), 2)
    with pytest.raises(ValueError, match="found in 2 scenes but the truth covers 3 scenes"):
        rec.face_scores(found, known_faces())
    with pytest.raises(gv.PortValueError, match="'owner' must index the 2 scenes"):
        rec.SceneBoxesPort.validate(
            SceneBoxSet(np.array([[0, 0, 1, 1.0]]), np.ones(1), np.array([2]), 2)
        )


def test_the_scenes_picture_marks_true_faces_green_and_found_ones_red():
    found = SceneBoxSet(np.array([[50.0, 50.0, 70.0, 70.0]]), np.ones(1),
                        np.array([0], np.int64), 3)  # fmt: skip
    images = np.zeros((3, 80, 80), np.float32)
    picture = rec.draw_scenes(images, known_faces(), found, count=3, columns=2, size=80)
    assert picture.shape == (80 + 4 + 80, 80 + 4 + 80, 3)
    assert picture[10, 20].tolist() == pytest.approx([0.1, 0.9, 0.1])  # face 0's top side
    assert picture[50, 60].tolist() == pytest.approx([0.95, 0.15, 0.1])  # found over face 1
    assert picture[5, 84 + 15].tolist() == pytest.approx([0.1, 0.9, 0.1])  # scene 1's face


# --- the lfw-trained Haar cascade ----------------------------------------------------------


@pytest.fixture(scope="module")
def small_cascades():
    split = rec.lfw_faces()
    train = rec.combine(rec.augment(split.train, copies=1), rec.negative_patches(count=200))
    return {
        normalise: rec.cascade(
            rec.haar(train, count=300, normalise=normalise), max_stages=4, max_stumps=10
        )
        for normalise in (False, True)
    }


@pytest.mark.parametrize("normalise", [False, True])
def test_early_rejection_gives_the_full_evaluations_decisions(small_cascades, normalise):
    model = small_cascades[normalise]
    image = (skimage.data.astronaut().mean(axis=2) / 255)[40:150, 150:300].astype(np.float32)
    recipe = recipe_of(model.recipe)
    boxes, decision = _haar_cascade_windows(image, model, recipe, 3)
    full = [(w.boxes, _score(model, w.features)) for w in _haar_windows(image, recipe, 3)]
    np.testing.assert_array_equal(boxes, np.concatenate([b for b, _ in full]))
    np.testing.assert_allclose(decision, np.concatenate([s for _, s in full]), atol=1e-9)
    assert (decision > 0).any() and (decision < 0).any()


def test_normalised_haar_features_ignore_brightness_and_contrast():
    images = rec.lfw_faces().test.images[:10]
    dimmer = 0.2 + 0.5 * images  # another brightness and contrast, still in [0, 1]
    labels = np.zeros(10, np.int64)
    plain, changed = (
        rec.haar(SampleSet(x.astype(np.float32), labels), count=200, normalise=True).features
        for x in (images, dimmer)
    )
    np.testing.assert_allclose(changed, plain, atol=1e-4)
    raw = rec.haar(SampleSet(dimmer.astype(np.float32), labels), count=200)
    assert np.abs(raw.features - plain).max() > 1


# --- the pipelines --------------------------------------------------------------------------


def test_face_detect_measures_against_true_boxes_not_a_box_in_the_pipeline():
    graph = gv.load_pipeline(PIPELINES / "face_detect.yaml")
    assert not any("truth" in (decl.params or {}) for decl in graph.nodes.values())
    out = gv.run(graph, outputs=["recall", "false_positives", "face_iou", "per_scene"]).outputs
    assert out["recall"] >= 0.9 and out["false_positives"] <= 0.5  # the aim
    assert 0.6 < out["face_iou"] <= 1
    assert out["per_scene"]["faces"].sum() >= 8


def test_face_detect_finds_the_mirrored_astronaut_and_nothing_on_cat_and_coffee():
    graph = gv.load_pipeline(PIPELINES / "face_detect.yaml")
    mirrored = np.ascontiguousarray(skimage.data.astronaut()[:, ::-1])
    out = gv.run(graph, inputs={"image": mirrored}, outputs=["boxes"]).outputs
    x0, y0, x1, y1 = ASTRONAUT_FACE
    assert iou(out["boxes"].xyxy[0], (512 - x1, y0, 512 - x0, y1)) > 0.7  # best first
    for name in ("cat", "coffee"):  # sample:cat is chelsea
        out = gv.run(graph, inputs={"image": f"sample:{name}"}, outputs=["count"]).outputs
        assert out["count"] == 0
