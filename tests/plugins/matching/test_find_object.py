"""Detection by feature constellations (issue 28, item 4): scenes with known
quadrilaterals, Lowe's pose Hough table, verification, scores and pictures.

Every truth here is built by the test: homographies it composes itself, models it pastes
with ``geometry`` warps, polygons whose areas are known by hand.
"""

from __future__ import annotations

import dataclasses
import doctest
import importlib
import math

import numpy as np
import pytest
import scipy.ndimage as ndi
import skimage.data

import graphvision as gv
from graphvision_plugins import geometry, matching, synthetic
from graphvision_plugins.features import sift
from graphvision_plugins.matching import InstanceSet
from graphvision_plugins.matching._model_views import (
    ConstellationParams,
    ModelViews,
    match_to_model,
    model_views,
    simulate_view,
)
from graphvision_plugins.matching._polygons import (
    _inside_convex,
    convex_overlap,
    polygon_area,
    quad_iou,
)
from graphvision_plugins.matching._probability import log_binomial_tail, match_probability
from graphvision_plugins.matching._verify import locate_instances
from graphvision_plugins.matching._votes import pose_votes
from graphvision_plugins.synthetic import ObjectSceneSet
from graphvision_plugins.synthetic._object_pose import object_pose
from graphvision_plugins.synthetic._object_scene_set import model_corners

from ...conftest import PIPELINES

GRAY = (skimage.data.astronaut().mean(axis=2) / 255).astype(np.float32)
MODEL = np.ascontiguousarray(GRAY[270:430, 130:330])  # the pipeline's model, 200 × 160
PARAMS = ConstellationParams()
SQUARE = np.array([[0, 0], [2, 0], [2, 2], [0, 2]], float)


def translate(x: float, y: float) -> np.ndarray:
    return np.array([[1, 0, x], [0, 1, y], [0, 0, 1.0]])


def paste(scene: np.ndarray, model: np.ndarray, h: np.ndarray) -> None:
    """Put ``model`` into ``scene`` through ``h`` (model → scene), in place."""
    warped, inside = geometry.warp(model, h, width=scene.shape[1], height=scene.shape[0])
    scene[inside] = warped[inside]


def background(shape: tuple[int, int]) -> np.ndarray:
    """A crop of the coffee photograph (no astronaut in it), slightly darkened."""
    coffee = skimage.data.coffee().mean(axis=2) / 255
    return np.ascontiguousarray(0.8 * coffee[: shape[0], : shape[1]], dtype=np.float32)


@pytest.fixture(scope="module")
def two_instance_scene():
    """A 400 × 600 scene with two instances placed by poses the test composes."""
    scene = background((400, 600))
    rows, cols = MODEL.shape
    first = translate(150, 200) @ object_pose(
        cols, rows, scale=0.9, tilt=math.radians(40), axis=0.3, roll=0.5, distance=None
    )
    second = translate(430, 190) @ object_pose(
        cols, rows, scale=1.1, tilt=math.radians(50), axis=1.2, roll=-2.0, distance=2.0
    )
    truths = []
    for h in (first, second):
        paste(scene, MODEL, h)
        truths.append(geometry.apply_homography(h, model_corners(cols, rows)))
    return scene, truths


@pytest.fixture(scope="module")
def views() -> ModelViews:
    return model_views(MODEL, [1.414, 2.0], {})


# --------------------------------------------------------------------------- polygons, probability


def test_polygon_area_and_overlap_of_squares_known_by_hand():
    assert polygon_area(SQUARE) == 4.0
    assert polygon_area(SQUARE[::-1]) == -4.0
    assert convex_overlap(SQUARE, SQUARE + 1) == pytest.approx(1.0)
    assert convex_overlap(SQUARE, SQUARE[::-1] + np.array([1, 0])) == pytest.approx(2.0)
    assert convex_overlap(SQUARE, SQUARE + 5) == 0.0
    assert quad_iou(SQUARE, SQUARE + 1) == pytest.approx(1 / 7)  # 1 / (4 + 4 - 1)
    diamond = np.array([[1, -1], [3, 1], [1, 3], [-1, 1]], float)  # area 8, holds the square
    assert quad_iou(SQUARE, diamond) == pytest.approx(4 / 8)


def test_binomial_tail_equals_the_sum_of_its_terms():
    for k, n, p in [(3, 10, 0.2), (1, 5, 0.5), (7, 40, 0.01), (10, 10, 0.9)]:
        exact = sum(math.comb(n, j) * p**j * (1 - p) ** (n - j) for j in range(k, n + 1))
        assert math.exp(log_binomial_tail(k, n, p)) == pytest.approx(exact, rel=1e-9)
    assert log_binomial_tail(0, 5, 0.3) == 0.0
    assert log_binomial_tail(6, 5, 0.3) == -math.inf
    # far below the smallest float: 300 successes in 300 at p = 1e-3
    assert log_binomial_tail(300, 300, 1e-3) == pytest.approx(300 * math.log(1e-3))


def test_match_probability_follows_bayes_rule_and_grows_with_the_inliers():
    # 6 inliers beyond a 4-match sample among 100 candidates, p = 0.05
    chance = sum(math.comb(96, j) * 0.05**j * 0.95 ** (96 - j) for j in range(6, 97))
    assert match_probability(10, 100, 0.05, 0.01) == pytest.approx(0.01 / (0.01 + chance * 0.99))
    values = [match_probability(k, 200, 0.01, 0.01) for k in range(4, 16)]
    assert values[0] == 0.01 and np.all(np.diff(values) > 0) and values[-1] > 0.98


@pytest.mark.parametrize("name", ["_model_views", "_polygons", "_probability"])
def test_doctests_of_the_modules_hold(name):
    module = importlib.import_module(f"graphvision_plugins.matching.{name}")
    result = doctest.testmod(module)
    assert result.attempted > 0 and result.failed == 0


# --------------------------------------------------------------------------- scenes


def test_object_pose_of_a_tilt_foreshortens_across_its_axis():
    # affine, tilt 60° about the x axis: x lengths kept (times the scale), y halved
    h = object_pose(201, 101, scale=1.5, tilt=math.radians(60), axis=0.0, roll=0.0, distance=None)
    quad = geometry.apply_homography(h, model_corners(201, 101))
    np.testing.assert_allclose(quad[1] - quad[0], [1.5 * 200, 0], atol=1e-9)
    np.testing.assert_allclose(quad[3] - quad[0], [0, 1.5 * 100 * 0.5], atol=1e-9)
    np.testing.assert_allclose(quad.mean(axis=0), [0, 0], atol=1e-9)
    # perspective: the centre maps to the origin with the same local scale; the far edge is
    # shorter than the near one
    h = object_pose(201, 101, scale=1.5, tilt=math.radians(60), axis=0.0, roll=0.0, distance=2.0)
    step = geometry.apply_homography(h, np.array([[100.0, 50.0], [100.5, 50.0], [100.0, 50.5]]))
    np.testing.assert_allclose(step[0], [0, 0], atol=1e-9)
    np.testing.assert_allclose(step[1] - step[0], [0.75, 0], atol=1e-3)
    np.testing.assert_allclose(step[2] - step[0], [0, 0.375], atol=1e-3)
    # the top edge (q_y = -50) is sin 60° · 50 nearer than the centre, at distance D = 2
    # diagonals; the bottom edge as much farther: their lengths go as 1 / depth
    quad = geometry.apply_homography(h, model_corners(201, 101))
    top, bottom = quad[1, 0] - quad[0, 0], quad[2, 0] - quad[3, 0]
    depth, lift = 2 * math.hypot(201, 101), 50 * math.sin(math.radians(60))
    assert bottom / top == pytest.approx((depth - lift) / (depth + lift), rel=1e-9)


@pytest.fixture(scope="module")
def small_scenes():
    return synthetic.object_scenes(
        GRAY, box=[150, 290, 290, 400], count=6, height=240, width=320, seed=5
    )


def test_object_scenes_truth_matches_what_was_drawn():
    """The scene, sampled where the true homography puts the model's pixels, reproduces the
    model up to the instance's gain and offset (correlation > 0.9, against the model blurred
    as much as the smallest instance's); 8 model pixels off, it does not."""
    model, scenes = synthetic.object_scenes(
        GRAY, box=[150, 290, 290, 400], count=3, height=240, width=320, min_instances=1,
        occlusion=0.0, clutter=0, seed=8,
    )  # fmt: skip
    rows, cols = model.shape
    ys, xs = np.mgrid[10 : rows - 10 : 3, 10 : cols - 10 : 3]
    points = np.column_stack([xs.ravel(), ys.ravel()]).astype(float)
    smooth = ndi.gaussian_filter(model, 2.0)[ys.ravel(), xs.ravel()]
    assert len(scenes.owner) >= 3
    for m, image in enumerate(scenes.images[scenes.owner]):
        mapped = geometry.apply_homography(scenes.homographies[m], points)
        seen = ndi.map_coordinates(image, [mapped[:, 1], mapped[:, 0]], order=1)
        off = geometry.apply_homography(scenes.homographies[m], points + 8.0)
        moved = ndi.map_coordinates(image, [off[:, 1], off[:, 0]], order=1)
        assert np.corrcoef(seen, smooth)[0, 1] > 0.9
        assert np.corrcoef(moved, smooth)[0, 1] < 0.7


def test_object_scenes_keep_their_promises(small_scenes):
    model, scenes = small_scenes
    rows, cols = model.shape
    counts = np.bincount(scenes.owner, minlength=len(scenes))
    assert counts.max() <= 3 and len(scenes.owner) >= 4
    np.testing.assert_allclose(
        scenes.quads,
        [geometry.apply_homography(h, model_corners(cols, rows)) for h in scenes.homographies],
    )
    assert (scenes.quads >= 0).all() and (scenes.quads[..., 0] < 320).all()
    assert (scenes.quads[..., 1] < 240).all()
    assert (scenes.tilt <= 60).all() and ((scenes.scale >= 0.5) & (scenes.scale <= 2)).all()
    assert ((scenes.visible > 0.5) & (scenes.visible <= 1)).all()
    for scene in range(len(scenes)):  # instances never overlap one another
        quads = scenes.quads_of(scene)
        for i in range(len(quads)):
            for j in range(i):
                assert convex_overlap(quads[i], quads[j]) == 0.0
    again = synthetic.object_scenes(
        GRAY, box=[150, 290, 290, 400], count=6, height=240, width=320, seed=5
    ).scenes
    np.testing.assert_array_equal(again.images, scenes.images)
    other = synthetic.object_scenes(
        GRAY, box=[150, 290, 290, 400], count=6, height=240, width=320, seed=6
    ).scenes
    assert not np.array_equal(other.images, scenes.images)


def test_object_scenes_refuse_bad_boxes_and_ranges():
    with pytest.raises(ValueError, match=r"box \[0, 0, 600, 50\] is not a crop"):
        synthetic.object_scenes(GRAY, box=[0, 0, 600, 50], count=1)
    with pytest.raises(ValueError, match="at least 16×16"):
        synthetic.object_scenes(GRAY, box=[0, 0, 10, 50], count=1)
    with pytest.raises(gv.ParameterError, match="min_instances"):
        synthetic.object_scenes(GRAY, min_instances=3, max_instances=1)
    with pytest.raises(gv.ParameterError, match="max_tilt"):
        synthetic.object_scenes(GRAY, max_tilt=85.0)


# --------------------------------------------------------------------------- voting


def test_matches_of_one_similarity_vote_into_one_bin():
    """Keypoints moved by a known similarity (scale 1.5, turn 40°, shift): every match
    predicts the same pose, so one bin holds all of them, at scale bin 0 (1 ≤ 1.5 < 2) and
    orientation bin 1 (30° ≤ 40° < 60°)."""
    rng = np.random.default_rng(0)
    xy = rng.uniform(0, 100, (30, 2))
    scale = rng.uniform(1.5, 4, 30)
    theta = rng.uniform(-math.pi, math.pi, 30)
    turn = math.radians(40)
    rotation = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
    model = gv.KeypointSet(xy, scale, theta, np.ones(30))
    scene = gv.KeypointSet(
        1.5 * xy @ rotation.T + [300, 200], 1.5 * scale, theta + turn, np.ones(30)
    )
    views = ModelViews(
        model,
        np.zeros((30, 128), np.float32),
        xy,
        np.tile(np.eye(2), (30, 1, 1)),
        np.zeros(30, np.int64),
        np.array([[49.5, 49.5]]),
        (100, 100),
    )
    pairs = np.column_stack([np.arange(30), np.arange(30)])
    votes = pose_votes(views, scene, pairs, ConstellationParams())
    assert votes.counts.sum() == 16 * 30  # two bins per dimension
    # each match votes the bin holding its prediction and the nearest other one in each
    # dimension: the same 16 bins for all
    full = np.flatnonzero(votes.counts == 30)
    assert len(full) == 16 and votes.counts.max() == 30
    assert set(votes.keys[full, 1]) == {0, 1} and set(votes.keys[full, 2]) == {0, 1}
    for b in full:
        members = votes.members[votes.starts[b] : votes.starts[b + 1]]
        np.testing.assert_array_equal(np.sort(members), np.arange(30))
    centre = 1.5 * np.array([49.5, 49.5]) @ rotation.T + np.array([300, 200])
    holding = [
        b
        for b in full
        if votes.keys[b, 1] == 0  # 1 <= 1.5 < 2
        and votes.keys[b, 2] == 1  # 30° <= 40° < 60°
        and 0 <= centre[0] - votes.keys[b, 3] * votes.widths[b] < votes.widths[b]
        and 0 <= centre[1] - votes.keys[b, 4] * votes.widths[b] < votes.widths[b]
    ]
    assert len(holding) == 1


def test_simulated_view_puts_a_dot_where_its_affine_map_says():
    model = np.zeros((60, 80), np.float32)
    model[20:23, 50:53] = 1.0  # a dot centred at (51, 21)
    view, affine = simulate_view(model, 2.0, math.radians(30))
    expected = affine[:2, :2] @ [51.0, 21.0] + affine[:2, 2]
    peak = np.unravel_index(np.argmax(view), view.shape)
    assert np.hypot(peak[1] - expected[0], peak[0] - expected[1]) <= 1.0
    assert view.shape[1] < view.shape[0] * 1.2  # shrunk across by the tilt


def test_scene_features_match_every_instance(two_instance_scene, views):
    """Scene → model with the ratio test keeps many matches on each instance; model → scene
    with a symmetric check (the single-object recipe) keeps at most the one instance a
    model feature prefers."""
    scene, truths = two_instance_scene
    found = sift(scene)
    pairs = match_to_model(found.descriptors, views, 0.8, 3.0)
    on = [_inside_convex(quad, found.keypoints.xy[pairs[:, 0]]).sum() for quad in truths]
    assert min(on) >= 20
    one_way = matching.match(views.descriptors, found.descriptors, ratio=0.8, symmetric=True)
    kept = [_inside_convex(quad, found.keypoints.xy[one_way.pairs[:, 1]]).sum() for quad in truths]
    assert sum(kept) < sum(on)


# --------------------------------------------------------------------------- finding


def test_both_instances_found_within_a_pixel(two_instance_scene):
    scene, truths = two_instance_scene
    found = matching.find_instances(MODEL, scene)
    assert len(found.instances) == 2
    errors = sorted(
        min(np.linalg.norm(quad - truth, axis=1).mean() for quad in found.instances.quads)
        for truth in truths
    )
    assert errors[-1] < 1.0
    assert (found.instances.probability >= 0.98).all()
    assert (found.instances.inliers >= 8).all()
    assert found.votes.shape == (100, 150) and found.votes.max() >= 3


def test_nothing_found_in_clutter_or_in_shuffled_matches(two_instance_scene, views):
    """Scenes of clutter alone give no instance; nor do the two-instance scene's matches
    with their model features shuffled, though their chance clusters are verified."""
    _, scenes = synthetic.object_scenes(
        GRAY, count=2, height=240, width=320, min_instances=0, max_instances=0, clutter=12,
        seed=4,
    )  # fmt: skip
    for image in scenes.images:
        features = sift(image)
        pairs = match_to_model(features.descriptors, views, 0.8, 3.0)
        assert len(locate_instances(views, features.keypoints, pairs, image.shape, PARAMS)[0]) == 0
    scene, _ = two_instance_scene
    features = sift(scene)
    pairs = match_to_model(features.descriptors, views, 0.8, 3.0)
    shuffled = pairs.copy()
    shuffled[:, 1] = np.random.default_rng(0).permutation(pairs[:, 1])
    instances, votes = locate_instances(views, features.keypoints, shuffled, scene.shape, PARAMS)
    assert len(instances) == 0 and votes.counts.max() >= 3


def test_acceptance_needs_the_inliers_and_the_probability(two_instance_scene, views):
    scene, _ = two_instance_scene
    features = sift(scene)
    pairs = match_to_model(features.descriptors, views, 0.8, 3.0)

    def count(**changes) -> int:
        params = dataclasses.replace(PARAMS, **changes)
        return len(locate_instances(views, features.keypoints, pairs, scene.shape, params)[0])

    assert count() == 2
    assert count(min_inliers=10_000) == 0
    assert count(min_votes=10_000) == 0  # no bin verified
    # a vote must agree in orientation: with 1° bins and tolerance, too few do
    assert count(orientation_bin=1.0, orientation_tolerance=0.5) == 0


# --------------------------------------------------------------------------- scores and pictures


def hand_made_scenes() -> ObjectSceneSet:
    """Two 50 × 60 scenes: scene 0 holds quads A and B, scene 1 holds C."""
    a = np.array([[5, 5], [25, 5], [25, 20], [5, 20]], float)
    b = a + np.array([30, 20])
    c = a + np.array([10, 10])
    quads = np.stack([a, b, c])
    return ObjectSceneSet(
        np.zeros((2, 50, 60), np.float32),
        quads,
        np.tile(np.eye(3), (3, 1, 1)),
        np.array([0, 0, 1], np.int64),
        np.ones(3),
        np.zeros(3),
        np.ones(3),
    )


def found_set(quads: list[np.ndarray], owner: list[int], inliers: list[int]) -> InstanceSet:
    return InstanceSet(
        np.asarray(quads, float).reshape(-1, 4, 2),
        np.tile(np.eye(3), (len(quads), 1, 1)),
        np.asarray(inliers, np.int64),
        np.ones(len(quads)),
        np.asarray(owner, np.int64),
        2,
    )


def test_scores_count_true_and_false_instances_by_hand():
    scenes = hand_made_scenes()
    a, _b, c = scenes.quads
    found = found_set(
        # A found twice, a stray, C turned by 90°
        [a + np.array([1, 0]), a + np.array([0, 2]), c + np.array([40, 20]), c[[1, 2, 3, 0]]],
        [0, 0, 1, 1],
        [30, 20, 10, 12],
    )
    scores = matching.score_instances(found, scenes)
    # TP: A (the 30-inlier copy, error 1), C turned by 90° (IoU 1, corner error large);
    # FP: A's second copy, the stray; missed: B
    assert (scores.found, scores.false_positives, scores.missed) == (2, 2, 1)
    assert scores.recall == pytest.approx(2 / 3)
    assert scores.precision == pytest.approx(2 / 4)
    turned = np.linalg.norm(c[[1, 2, 3, 0]] - c, axis=1).mean()
    assert scores.corner_error == pytest.approx(np.median([1.0, turned]))
    empty = matching.score_instances(InstanceSet.empty(2), scenes)
    assert (empty.recall, empty.precision, empty.corner_error) == (0.0, 1.0, math.inf)


def test_scores_refuse_instances_of_other_scenes():
    with pytest.raises(ValueError, match="found in 1 scenes but 2 scenes"):
        matching.score_instances(InstanceSet.empty(1), hand_made_scenes())


def test_drawing_outlines_truth_in_green_and_finds_in_red():
    scenes = hand_made_scenes()
    a = scenes.quads[0]
    found = found_set([a + np.array([0, 12])], [0], [9])
    votes = np.zeros((2, 13, 15), np.float32)
    votes[0, 2:4, 3:5] = 5
    pictures = matching.draw_object_scenes(scenes, found, votes, count=2, columns=2)
    assert pictures.outlines.shape == (50, 124, 3) and pictures.vote_space.shape == (50, 124, 3)
    green = (0.1, 0.9, 0.1)
    red = (0.95, 0.15, 0.1)
    np.testing.assert_allclose(pictures.outlines[5, 15], green, atol=1e-6)  # A's top edge
    np.testing.assert_allclose(pictures.outlines[17, 15], red, atol=1e-6)  # found top edge
    np.testing.assert_allclose(pictures.outlines[25, 60:64], 1.0)  # the gap between scenes
    assert pictures.vote_space[9, 13].min() > 0.9  # 5 votes = the peak: white
    assert pictures.vote_space[40, 40].max() == 0.0  # no vote, black scene: black
    with pytest.raises(ValueError, match="one picture per scene"):
        matching.draw_object_scenes(scenes, found, votes[:1])


# --------------------------------------------------------------------------- direct calls


def test_direct_calls_check_inputs_and_parameters():
    with pytest.raises(gv.PortValueError, match=r"^matching\.find_instances.*input 'model'"):
        matching.find_instances((MODEL * 255).astype(np.int32), MODEL)  # uint8 would be taken
    with pytest.raises(gv.ParameterError, match="ratio"):
        matching.find_instances(MODEL, MODEL, ratio=2.0)
    with pytest.raises(gv.ParameterError, match="tilts"):
        matching.find_instances(MODEL, MODEL, tilts=[0.5])
    with pytest.raises(ValueError, match="at least 16×16"):
        matching.find_instances(MODEL[:10, :10], MODEL)
    bad = InstanceSet(np.zeros((1, 4, 2)), np.zeros((1, 3, 3)), np.zeros(1), np.zeros(1),
                      np.zeros(1, np.int64), 1)  # fmt: skip
    with pytest.raises(gv.PortValueError, match="'inliers' must be int64"):
        matching.score_instances(bad, hand_made_scenes())


# --------------------------------------------------------------------------- the pipeline


def test_find_object_pipeline_meets_its_aims_on_scenes_of_another_seed():
    """Four scenes of a seed used for no tuning (the pipeline's default is another)."""
    graph = gv.load_pipeline(PIPELINES / "find_object.yaml")
    result = gv.run(
        graph,
        overrides={"scenes.count": 4, "scenes.seed": 31},
        outputs=["recall", "precision", "corner_error", "found", "outlines"],
    )
    out = result.outputs
    assert out["found"] >= 4
    assert out["recall"] >= 0.9 and out["precision"] >= 0.9
    assert out["corner_error"] <= 2.0
    assert out["outlines"].shape == (964, 1928, 3)
