"""Bad parameters of the built-in plugins are refused by name, before they exhaust memory,
never finish, or turn into a NaN reported as a figure: sizes and iteration counts have
maxima, lists that must name something are not empty, bounds given as two parameters
are in order, robust fits need inliers, degenerate inputs are refused naming what is
wrong."""

from __future__ import annotations

import typing

import annotated_types
import numpy as np
import pydantic
import pytest

import graphvision as gv
from graphvision_plugins import cnn
from graphvision_plugins.cnn._network import MAX_SAMPLE_VALUES, MAX_WEIGHTS
from graphvision_plugins.detection._rpn import check_anchors_fit
from graphvision_plugins.epipolar import pose_error
from graphvision_plugins.fitting import ransac_iterations
from graphvision_plugins.recognition._data import stratified_split
from graphvision_plugins.shared.params import MAX_EPOCHS, MAX_ITERATIONS

from ...conftest import PIPELINES

REGISTRY = gv.discover()
SPECS = [spec for specs in REGISTRY.families().values() for spec in specs]


def _refused(pipeline: str, overrides: dict, match: str) -> None:
    """The pipeline is refused before anything runs (a PipelineError names the --set)."""
    graph = gv.load_pipeline(PIPELINES / pipeline)
    with pytest.raises(gv.PipelineError, match=match):
        gv.run(graph, overrides=overrides, cache=None)


def _upper_bound(field: pydantic.fields.FieldInfo) -> float | None:
    for item in field.metadata:
        if isinstance(item, annotated_types.Le):
            return float(item.le)  # type: ignore[arg-type]
        if isinstance(item, annotated_types.Lt):
            return float(item.lt)  # type: ignore[arg-type]
    return None


# --- 1. sizes and iteration counts have maxima ------------------------------------------


@pytest.mark.parametrize(
    ("pipeline", "overrides", "message"),
    [
        ("cnn_digits.yaml", {"linear.layers": ["conv 100000x3", "dense 10"]},
         r"layers\[0\]: 'conv 100000x3': filters 100000 exceeds the maximum 4096"),
        ("cnn_digits.yaml", {"linear.layers": ["dense 100000000"]},
         r"layers\[0\]: 'dense 100000000': units 100000000 exceeds the maximum 4096"),
        ("cnn_digits.yaml", {"cnn.layers": ["conv 8x99", "dense 10"]},
         r"layers\[0\]: 'conv 8x99': kernel size 99 exceeds the maximum 31"),
        ("cnn_digits.yaml", {"cnn.layers": ["conv 8x3 pad 40", "dense 10"]},
         r"'conv 8x3 pad 40': padding 40 exceeds the maximum 30"),
        ("cnn_digits.yaml", {"cnn.layers": ["maxpool 64", "dense 10"]},
         r"'maxpool 64': pooling size 64 exceeds the maximum 32"),
        ("rcnn.yaml", {"detector.hidden": ["dense 100000000"]},
         r"detection.train_head: hidden\[0\]: 'dense 100000000': units 100000000 exceeds"),
        ("rcnn.yaml", {"detector.epochs": 100_000_000},
         r"'epochs' of detection.train_head: Input should be less than or equal to 1000"),
        ("rcnn.yaml", {"rpn.epochs": 100_000_000},
         r"'epochs' of detection.train_rpn: Input should be less than or equal to 1000"),
        ("rcnn.yaml", {"crops.size": 100_000},
         r"'size' of detection.roi_samples: Input should be less than or equal to 64"),
        ("two_view.yaml", {"F.max_iterations": 10**9},
         r"'max_iterations' of epipolar.fundamental: Input should be less than or equal"),
        ("homography.yaml", {"fit.max_iterations": 10**9},
         r"'max_iterations' of geometry.homography_ransac: Input should be less than"),
    ],
)  # fmt: skip
def test_a_size_or_count_beyond_its_maximum_is_refused_before_the_run(pipeline, overrides, message):
    _refused(pipeline, overrides, message)


ITERATIVE = ("epochs", "iterations", "max_iterations", "rounds", "max_stages", "max_stumps")


def test_every_epochs_and_iterations_parameter_has_a_maximum():
    found = []
    for spec in SPECS:
        for name, field in spec.params_model.model_fields.items():
            if name in ITERATIVE and field.annotation is int:
                found.append(f"{spec.id}.{name}")
                bound = _upper_bound(field)
                assert bound is not None, f"{spec.id}.{name} has no maximum"
                most = MAX_EPOCHS if name == "epochs" else MAX_ITERATIONS
                assert bound <= most, f"{spec.id}.{name} allows {bound:g}"
    expected = {
        "cnn.train.epochs",
        "detection.train_head.epochs",
        "epipolar.fundamental.max_iterations",
    }
    assert expected <= set(found)


def test_a_network_too_large_for_its_input_is_refused_naming_its_largest_layer():
    layers = ["conv 4096x9", "conv 4096x3", "dense 10"]
    message = (
        r"would hold 153,956,362 weights .* at most 10,000,000; layer 1 'conv "
        r"4096x3' alone holds 150,999,040"
    )
    with pytest.raises(ValueError, match=message):
        cnn.build_architecture((1, 8, 8), layers)
    assert MAX_WEIGHTS == 10_000_000
    # 256 filters over a 512×512 input: 256·512·512 = 67,108,864 values for one input
    with pytest.raises(ValueError, match=r"layer 0 'conv 256x9' would make 67,108,864 values"):
        cnn.build_architecture((1, 512, 512), ["conv 256x9", "maxpool 32", "dense 10"])
    assert MAX_SAMPLE_VALUES < 256 * 512 * 512
    # the same network on a small input is built
    assert cnn.build_architecture((1, 16, 16), ["conv 256x9", "maxpool 16", "dense 10"]).size


def test_a_training_batch_too_large_for_memory_is_refused_naming_batch_size():
    architecture = cnn.build_architecture((1, 64, 64), ["conv 64x3", "dense 2"])
    images = np.zeros((1024, 1, 64, 64), np.float32)  # 64·64·64 values per image, 2^28 a batch
    targets = np.arange(1024) % 2
    message = (
        r"cnn.train: a batch of 1024 inputs would make 268,435,456 values .* "
        r"set batch_size to 512 or less"
    )
    with pytest.raises(ValueError, match=message):
        cnn.fit_network(
            architecture, images, targets, epochs=1, batch_size=1024, learning_rate=0.01,
            momentum=0.0, weight_decay=0.0, seed=0,
        )  # fmt: skip


# --- 2. lists that must name something ----------------------------------------------------


@pytest.mark.parametrize(
    ("pipeline", "overrides", "message"),
    [
        ("rcnn.yaml", {"train_scenes.classes": []},
         r"'classes' of synthetic.digit_scenes: List should have at least 1 item"),
        ("rcnn.yaml", {"rpn.sizes": []}, r"'sizes' of detection.train_rpn: List should have"),
        ("rcnn.yaml", {"rpn.ratios": []}, r"'ratios' of detection.train_rpn: List should have"),
        ("proposals.yaml", {"proposals.scales": []},
         r"'scales' of detection.selective_search: List should have at least 1 item"),
        ("proposals.yaml", {"proposals.colour_spaces": []},
         r"'colour_spaces' of detection.selective_search: List should have"),
        ("proposals.yaml", {"proposals.similarities": []},
         r"'similarities' of detection.selective_search: List should have"),
        ("proposals.yaml", {"proposals.similarities": ["colour+shape"]},
         r"similarity set 'colour\+shape' names \['shape'\]; use measures among"),
        ("proposals.yaml", {"proposals.colour_spaces": ["cmyk"]},
         r"'colour_spaces.0' of detection.selective_search: Input should be 'rgb'"),
    ],
)  # fmt: skip
def test_an_empty_or_unknown_list_is_refused_before_the_run(pipeline, overrides, message):
    _refused(pipeline, overrides, message)


MAY_BE_EMPTY = {
    "detection.train_head.hidden",  # no hidden layer: a linear head
    "detection.train_faster_rcnn.hidden",  # the same head, trained jointly with the RPN
    "matching.find_instances.tilts",  # no simulated view: Lowe's single training image
    "matching.find_instances_in_scenes.tilts",
}


def test_every_list_parameter_with_elements_by_default_needs_one():
    for spec in SPECS:
        model = spec.params_model
        for name, field in model.model_fields.items():
            origin = typing.get_origin(field.annotation)
            is_sequence = origin is list or (
                origin is tuple and typing.get_args(field.annotation)[-1] is Ellipsis
            )
            if not is_sequence or not field.default or f"{spec.id}.{name}" in MAY_BE_EMPTY:
                continue
            with pytest.raises(pydantic.ValidationError):
                model.model_validate({name: []})


# --- 3. bounds given as two parameters are in order --------------------------------------

PAIRS = [("low", "high"), ("min_", "max_"), ("near", "far")]


def _pairs(names: list[str]) -> list[tuple[str, str]]:
    out = []
    for lower, upper in PAIRS:
        for name in names:
            if name.startswith(lower) and upper + name[len(lower) :] in names:
                out.append((name, upper + name[len(lower) :]))
    return out


def test_every_pair_of_bounds_is_refused_reversed_before_the_run():
    checked = []
    for spec in SPECS:
        model = spec.params_model
        for lower, upper in _pairs(list(model.model_fields)):
            low, high = model.model_fields[lower].default, model.model_fields[upper].default
            if low is None or high is None or low == high:
                continue
            with pytest.raises(pydantic.ValidationError, match=rf"{lower} .* must be .* {upper}"):
                model.model_validate({lower: high, upper: low})
            checked.append(f"{spec.id}.{lower}")
    expected = {"edges.canny.low", "hough.circles.min_radius", "synthetic.digit_scenes.min_objects"}
    assert expected <= set(checked)


def test_a_colour_range_upside_down_is_refused_before_the_run():
    _refused(
        "stereo.yaml",
        {"picture.low": 60, "picture.high": 7},
        r"stereo.draw_disparity: low \(60\) must be below high \(7\)",
    )


# --- 3. degenerate results are refused, not reported ------------------------------------


def test_ransac_iterations_stay_finite_for_a_vanishing_inlier_ratio():
    # (1/163)^8 ≈ 2e-18 rounds 1 - w^s to 1: log(1 - w^s) was 0 (a ZeroDivisionError)
    good = (1 / 163) ** 8
    assert ransac_iterations(1 - 1 / 163, 8, 0.999) == pytest.approx(-np.log(0.001) / good)
    assert ransac_iterations(1.0, 8, 0.999) == 10**9  # no inlier: never, capped
    assert ransac_iterations(0.5, 4, 0.99) == 72


def _noise_points(count: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(0, 500, (count, 2))


def test_a_homography_with_fewer_inliers_than_a_sample_is_refused_naming_the_threshold():
    from graphvision_plugins.geometry import homography_ransac

    a, b = _noise_points(60, 1), _noise_points(60, 2)
    keypoints = [gv.KeypointSet(p, np.ones(60), np.zeros(60), np.ones(60)) for p in (a, b)]
    matches = gv.MatchSet(np.column_stack([np.arange(60), np.arange(60)]), np.zeros(60))
    message = (
        r"the homography: only 4 of 60 points lie within threshold=1e-09 of the "
        r"best model, none beyond the 4 of the sample"
    )
    with pytest.raises(ValueError, match=message):
        homography_ransac(*keypoints, matches, threshold=1e-9)


def test_a_line_with_fewer_inliers_than_a_sample_is_refused_naming_the_threshold():
    from graphvision_plugins.fitting import fit_line_ransac

    points = _noise_points(50, 3)
    message = (
        r"the line: only 2 of 50 points lie within threshold=1e-12 of the best "
        r"model, none beyond the 2"
    )
    with pytest.raises(ValueError, match=message):
        fit_line_ransac(points, threshold=1e-12)


def test_true_cameras_at_one_centre_are_refused_by_the_pose_error():
    from graphvision_plugins.camera import pinhole

    camera = pinhole()
    message = r"truth_a and truth_b have the same centre: a zero baseline"
    with pytest.raises(ValueError, match=message):
        pose_error(camera, camera, camera)


def test_anchors_larger_than_the_scenes_are_refused_naming_size_and_ratio():
    message = (
        r"anchor size 100000 with ratio 1 is a 100000×100000 box, larger than "
        r"the 80×80 scenes"
    )
    with pytest.raises(ValueError, match=message):
        check_anchors_fit([16.0, 100_000.0], [1.0], (80, 80))
    check_anchors_fit([16.0, 24.0, 32.0], [0.7, 1.0, 1.4], (80, 80))  # rcnn.yaml's


def test_a_split_leaving_a_class_without_training_samples_is_refused():
    labels = np.repeat([0, 1, 2], [10, 40, 40])
    message = (
        r"test_fraction=0.99 holds out all 10 samples of class 0, leaving it no "
        r"training sample: use a test_fraction below 0.95"
    )
    with pytest.raises(ValueError, match=message):
        stratified_split(labels, 0.99, seed=0)
    message = (
        r"test_fraction=0.001 holds out no sample of any class: use a "
        r"test_fraction above 0.0125"
    )
    with pytest.raises(ValueError, match=message):
        stratified_split(labels, 0.001, seed=0)
    train, test = stratified_split(labels, 0.9, seed=0)
    assert len(test) == 9 + 36 + 36 and set(labels[train]) == {0, 1, 2}


def test_a_homography_fitted_to_repeated_keypoints_only_is_refused():
    # at 1e-12 px the best model's 8 inliers are its 4 sample matches, each twice (SIFT
    # repeats a keypoint with a second orientation): no distinct match beyond the sample
    graph = gv.load_pipeline(PIPELINES / "homography.yaml")
    message = r"the homography: only 4 of \d+ points lie within threshold=1e-12 .* none beyond"
    with pytest.raises(gv.RunError, match=message):
        gv.run(graph, outputs=["inlier_ratio"], overrides={"fit.threshold": 1e-12}, cache=None)


@pytest.mark.parametrize(
    ("node", "params", "message"),
    [
        ("synthetic.digit_scenes", {"count": 10_000, "size": 512},
         r"count=10000 × size=512\^2 would make 2,621,440,000 values \(9.8 GiB as float32\)"),
        ("recognition.negative_patches", {"count": 100_000, "size": 256},
         r"count=100000 × size=256\^2 would make 6,553,600,000 values"),
    ],
)  # fmt: skip
def test_generated_data_beyond_memory_is_refused_before_it_runs(node, params, message):
    with pytest.raises(pydantic.ValidationError, match=message):
        REGISTRY.node(node).params_model.model_validate(params)
    one = {name: 1 if name == "count" else value for name, value in params.items()}
    REGISTRY.node(node).params_model.model_validate(one)


def test_an_essential_matrix_with_fewer_inliers_than_a_sample_names_the_pixel_threshold():
    from graphvision_plugins.epipolar import essential_from_points
    from graphvision_plugins.synthetic import two_view_scene

    scene = two_view_scene(count=60, noise=0.5, seed=3)
    message = r"the essential matrix: only \d of \d+ points lie within threshold=1e-12 of"
    with pytest.raises(ValueError, match=message):
        essential_from_points(scene.a, scene.b, scene.camera_a, scene.camera_b, threshold=1e-12)
    fit = essential_from_points(scene.a, scene.b, scene.camera_a, scene.camera_b, threshold=1.5)
    assert fit.inlier_count > len(scene.a) // 2


@pytest.mark.parametrize(
    "node", ["pyramids.match_multiscale", "recognition.detect", "recognition.detect_subspace"]
)
def test_a_scale_that_would_enlarge_an_image_beyond_64_times_its_area_is_refused(node):
    model = REGISTRY.node(node).params_model
    message = r"min_scale\n.*greater than or equal to 0.125"
    with pytest.raises(pydantic.ValidationError, match=message):
        model.model_validate({"min_scale": 1e-6})


def test_a_cost_volume_beyond_memory_is_refused_before_it_is_made():
    from graphvision_plugins.stereo import block_match, sgm

    image = np.zeros((512, 1024), np.float32)  # 512·1024·512 = 2^28 values, twice the maximum
    message = r"the cost volume 512×1024×512 would hold 268,435,456 values \(1.0 GiB as float32"
    for method in (block_match, sgm):
        with pytest.raises(ValueError, match=message):
            method(image, image, num_disparities=512)


def test_a_vocabulary_too_large_for_its_descriptors_is_refused():
    model = REGISTRY.node("recognition.kmeans").params_model
    message = r"words=4096 × max_descriptors=1000000 would make 4,096,000,000 values"
    with pytest.raises(pydantic.ValidationError, match=message):
        model.model_validate({"words": 4096, "max_descriptors": 1_000_000})
    # max_descriptors=0 (all of them): the node refuses once it knows how many there are
    from graphvision_plugins.recognition import kmeans
    from graphvision_plugins.recognition._types import DescriptorBags

    bags = DescriptorBags(
        np.zeros((20_000, 4), np.float32), np.zeros(20_000, np.int64), np.zeros(1, np.int64)
    )
    message = r"4096 words × 20,000 descriptors would make 81,920,000 distances per iteration"
    with pytest.raises(ValueError, match=message):
        kmeans(bags, words=4096, max_descriptors=0)
