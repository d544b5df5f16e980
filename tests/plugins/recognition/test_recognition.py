"""Recognition: features against scikit-image, models against synthetic truths, the
issue's pipelines against their accuracy truths, and the messages for bad input."""

from __future__ import annotations

import numpy as np
import pytest

import graphvision as gv
from graphvision_plugins import recognition as rec
from graphvision_plugins.recognition._models import LinearModel, StumpModel
from graphvision_plugins.recognition._types import FeatureSet, SampleSet, SubspaceModel

from ...conftest import PIPELINES


def samples(images, labels):
    return SampleSet(np.asarray(images, np.float32), np.asarray(labels, np.int64))


def features(rows, labels, recipe="{}"):
    return FeatureSet(np.asarray(rows, np.float64), np.asarray(labels, np.int64), recipe)


@pytest.fixture(scope="module")
def lfw():
    return rec.lfw_faces()


# --- data ---------------------------------------------------------------------------


def test_lfw_split_is_stratified_150_50_and_seeded(lfw):
    assert lfw.train.images.shape == (150, 25, 25) and lfw.test.images.shape == (50, 25, 25)
    assert np.bincount(lfw.train.labels).tolist() == [75, 75]
    assert np.bincount(lfw.test.labels).tolist() == [25, 25]
    again = rec.lfw_faces()
    np.testing.assert_array_equal(again.test.images, lfw.test.images)
    other = rec.lfw_faces(seed=1)
    assert not np.array_equal(other.test.images, lfw.test.images)


def test_texture_patches_split_each_image_into_halves():
    split = rec.texture_patches(size=64, stride=64)
    # 512×256 halves hold 8 × 4 patches of 64×64; three textures
    assert split.train.images.shape == (96, 64, 64) == split.test.images.shape
    assert np.bincount(split.train.labels).tolist() == [32, 32, 32]
    import skimage.data

    brick = skimage.data.brick() / np.float32(255)
    np.testing.assert_allclose(split.test.images[0], brick[:64, 256:320], atol=1e-6)


def test_augment_adds_the_mirror_images_and_jittered_copies(lfw):
    grown = rec.augment(lfw.test, copies=2, seed=0)
    assert len(grown) == 4 * len(lfw.test)
    np.testing.assert_array_equal(grown.images[50:100], lfw.test.images[:, :, ::-1])
    untouched = rec.augment(lfw.test, copies=1, shift=0, scale=0, angle=0)
    for jittered, image in zip(untouched.images[100:], lfw.test.images, strict=True):
        assert np.allclose(jittered, image, atol=1e-5) or np.allclose(
            jittered, image[:, ::-1], atol=1e-5
        )


# --- HOG and Haar-like features against scikit-image ---------------------------------


def test_hog_equals_scikit_image(lfw):
    from skimage.feature import hog

    images = lfw.test.images[:10]
    mine = rec.hog(samples(images, np.zeros(10)), pixels_per_cell=(6, 6)).features
    reference = np.stack([hog(im, 9, (6, 6), (2, 2), block_norm="L2-Hys") for im in images])
    np.testing.assert_allclose(mine, reference, atol=1e-6)


@pytest.mark.parametrize("orientations, cell, block", [(8, (5, 7), (2, 3)), (12, (16, 16), (1, 1))])
def test_hog_blocks_equal_scikit_image_for_odd_cells_and_cropped_borders(orientations, cell, block):
    from skimage import data
    from skimage.feature import hog

    image = (data.camera()[:203, :190] / 255).astype(np.float32)
    reference = hog(image, orientations, cell, block, block_norm="L2-Hys", feature_vector=False)
    mine = rec.hog_features(image[None], orientations, cell, block)
    np.testing.assert_allclose(mine[0], reference.ravel(), atol=1e-6)


def test_hog_picture_draws_the_edge_direction():
    image = np.zeros((32, 32), np.float32)
    image[:, 16:] = 1.0  # a vertical edge: horizontal gradient, drawn as a vertical line
    picture = rec.hog_picture(image, pixels_per_cell=(8, 8))
    cell = picture[8:16, 16:24]  # the cell right of the edge holds the gradient
    assert cell.max() == 1.0
    rows, cols = np.nonzero(cell)
    assert np.ptp(rows) == 7 and np.ptp(cols) <= 2  # a near-vertical line (bin centre 10°)
    assert picture[:, :8].max() == 0  # no gradient, nothing drawn


def test_integral_image_and_haar_values_equal_scikit_image(lfw):
    from skimage.feature import haar_like_feature, haar_like_feature_coord
    from skimage.transform import integral_image

    image = lfw.test.images[0].astype(np.float64)
    np.testing.assert_allclose(
        rec.integral_image_node(image.astype(np.float32)), integral_image(image), atol=1e-9
    )
    coords, _ = haar_like_feature_coord(25, 25)
    assert len(rec.haar_feature_table((25, 25))) == len(coords) == 190736
    table = rec.sample_haar_features((25, 25), 300, seed=3)
    names = list(rec.HAAR_TYPES)
    kinds = np.array([names[t] for t in table[:, 0]], dtype=object)
    rects = np.empty(len(table), dtype=object)
    for i, (t, r, c, h, w) in enumerate(table):
        offsets = rec.HAAR_TYPES[names[t]][1]
        rects[i] = [[(r + dr * h, c + dc * w), (r + dr * h + h - 1, c + dc * w + w - 1)]
                    for dr, dc in offsets]  # fmt: skip
    reference = haar_like_feature(
        integral_image(image), 0, 0, 25, 25, feature_type=kinds, feature_coord=rects
    )
    mine = rec.haar(samples(image[None], [1]), count=300, seed=3).features[0]
    np.testing.assert_allclose(mine, reference, atol=1e-9)


# --- subspaces ---------------------------------------------------------------------


def test_dual_pca_equals_pca(lfw):
    from scipy.linalg import subspace_angles

    data = rec.pixel_features(lfw.train.images)
    _, basis, values, method = rec.fit_pca(data, 20, "covariance")
    _, basis_d, values_d, method_d = rec.fit_pca(data, 20, "gram")
    assert (method, method_d) == ("covariance", "gram")
    assert subspace_angles(basis, basis_d).max() < 1e-6
    np.testing.assert_allclose(basis, basis_d, atol=1e-6)  # signs fixed the same way
    np.testing.assert_allclose(values[:149], values_d[:149], rtol=1e-8)
    assert rec.fit_pca(data, 5, "auto")[3] == "gram"  # 625 dimensions > 150 samples


def test_reconstruction_error_on_training_data_is_the_sum_of_left_out_eigenvalues(lfw):
    train = rec.pixels(lfw.train)
    subspace = rec.pca(train, components=10)
    error = rec.residual(train, subspace)
    n = len(train)
    expected = subspace.eigenvalues[10:].sum() * (n - 1) / n  # ε(m) = Σ_{j>m} λ_j
    assert error.mean() == pytest.approx(expected, rel=1e-9)
    projected = rec.project(train, subspace).features
    np.testing.assert_allclose(projected.mean(axis=0), 0, atol=1e-12)
    np.testing.assert_allclose(projected.var(axis=0, ddof=1), subspace.eigenvalues[:10], rtol=1e-8)


# --- classifiers against synthetic truths -----------------------------------------


def test_linear_svm_matches_the_closed_form_of_a_symmetric_pair():
    # points ±1 on a line: ½w² + 2C(1 − w)² is least at w = 4C / (1 + 4C), b = 0
    for C in (0.1, 1.0, 10.0):
        model = rec.linear_svm(features([[1.0], [-1.0]], [1, 0]), C=C)
        assert model.weights[0, 0] == pytest.approx(4 * C / (1 + 4 * C), rel=1e-6)
        assert model.bias[0] == pytest.approx(0.0, abs=1e-6)


def test_linear_svm_finds_the_separating_direction_and_handles_three_classes():
    rng = np.random.default_rng(0)
    centres = np.array([[0.0, 0.0], [6.0, 0.0], [0.0, 6.0]])
    labels = np.repeat([0, 1, 2], 50)
    points = centres[labels] + rng.normal(0, 1, (150, 2))
    model = rec.linear_svm(features(points, labels))
    assert model.weights.shape == (3, 2)
    assert np.mean(model.predict(points) == labels) > 0.97


def test_adaboost_recovers_a_threshold_and_an_axis_aligned_box():
    x = np.linspace(0, 1, 41)[:, None]
    stump = rec.adaboost(features(x, x[:, 0] > 0.31), rounds=1)
    assert stump.threshold[0] == pytest.approx(0.3125)  # midway between 0.3 and 0.325
    assert stump.polarity[0] == 1.0
    rng = np.random.default_rng(1)
    points = rng.uniform(-1, 1, (300, 2))
    inside = (np.abs(points) < 0.5).all(axis=1)
    model = rec.adaboost(features(points, inside), rounds=40)
    assert np.mean(model.predict(points) == inside) > 0.97


def test_cascade_reports_per_stage_rejections_and_meets_its_targets(lfw):
    train = rec.haar(rec.combine(lfw.train, rec.negative_patches(count=200)), count=500)
    model = rec.cascade(train, detection_rate=0.99, false_positive_rate=0.5, max_stages=4)
    table = rec.cascade_table(model)
    negatives = int((train.labels == 0).sum())
    passed = model.predict(train.features) == 1
    # the survivors of the last stage are what every stage let through
    assert negatives - table["rejected"].sum() == int((passed & (train.labels == 0)).sum())
    assert table["false_positive_rate"][-1] == pytest.approx(
        (passed & (train.labels == 0)).sum() / negatives
    )
    assert np.all(np.diff(table["false_positive_rate"]) <= 0)
    assert table["detection_rate"][-1] >= 0.99 ** len(table["stage"]) - 1e-9
    assert rec.predict(model, rec.haar(lfw.test, count=500)).shape == (50,)


def test_kmeans_finds_known_centres_and_is_seeded():
    rng = np.random.default_rng(2)
    centres = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0], [10.0, 10.0]])
    points = np.concatenate([c + rng.normal(0, 0.5, (100, 2)) for c in centres])
    found = rec.fit_kmeans(points, 4, 100, seed=0)
    distance = np.linalg.norm(centres[:, None] - found[None], axis=2)
    assert sorted(distance.argmin(axis=1)) == [0, 1, 2, 3]  # one centre per cluster
    assert distance.min(axis=1).max() < 0.15
    np.testing.assert_array_equal(found, rec.fit_kmeans(points, 4, 100, seed=0))


def test_bag_of_words_histograms_count_the_nearest_words():
    bags = rec._types.DescriptorBags(
        np.array([[0, 0], [0.1, 0], [5, 5], [5, 5.2], [0, 0.2]], np.float32),
        np.array([0, 0, 0, 1, 1], np.int64),
        np.array([3, 4, 5], np.int64),
    )
    words = np.array([[0.0, 0.0], [5.0, 5.0]])
    histograms = rec.bag_of_words(bags, words)
    expected = np.array([[2 / 3, 1 / 3], [0.5, 0.5], [0.0, 0.0]])
    np.testing.assert_allclose(histograms.features, expected)
    assert histograms.labels.tolist() == [3, 4, 5]


# --- detection ----------------------------------------------------------------------


def test_iou_and_nms_on_known_boxes():
    boxes = np.array([[0, 0, 10, 10], [5, 0, 15, 10], [20, 20, 30, 30]], np.float64)
    np.testing.assert_allclose(rec.iou_matrix(boxes[:1], boxes)[0], [1.0, 50 / 150, 0.0])
    scored = gv.BoxSet(boxes, np.array([0.5, 0.9, 0.1]))
    kept = rec.nms(scored, iou=0.3)
    np.testing.assert_array_equal(kept.xyxy, boxes[[1, 2]])
    assert len(rec.nms(scored, iou=0.4)) == 3
    assert rec.box_iou(kept, truth=(5, 0, 15, 10)) == 1.0


def test_detection_finds_drawn_squares_at_their_place_and_scale():
    """A pixel classifier of bright 12×12 squares finds two drawn at 1× and 2× scale."""
    rng = np.random.default_rng(0)
    positive = np.full((40, 12, 12), 0.1) + rng.uniform(0, 0.1, (40, 12, 12))
    positive[:, 2:10, 2:10] = 0.9
    negative = rng.uniform(0, 1, (200, 12, 12)) * rng.uniform(0, 1, (200, 1, 1))
    train = rec.pixels(samples(np.concatenate([positive, negative]), [1] * 40 + [0] * 200))
    model = rec.linear_svm(train)
    scene = np.full((80, 100), 0.1, np.float32)
    scene[22:30, 12:20] = 0.9  # a 12×12 window at (10, 20)
    scene[44:60, 54:70] = 0.9  # a 24×24 window at (50, 40)
    boxes = rec.nms(rec.detect(scene, model, scale_step=2.0, step=2, threshold=0.5), iou=0.2)
    truths = np.array([[10, 20, 22, 32], [50, 40, 74, 64]], np.float64)
    assert (rec.iou_matrix(truths, boxes.xyxy).max(axis=1) > 0.7).all()
    drawing = rec.draw_boxes(scene, boxes)
    assert drawing.shape == (80, 100, 3) and (drawing[20, 10:22] != scene[20, 10]).any()


def test_boxes_port_checks_corners():
    with pytest.raises(gv.PortValueError, match="x0 < x1 and y0 < y1"):
        gv.BoxesPort.validate(gv.BoxSet(np.array([[5.0, 0, 1, 10]]), np.array([1.0])))
    with pytest.raises(gv.PortValueError, match="'score' must be float64"):
        gv.BoxesPort.validate(gv.BoxSet(np.array([[0.0, 0, 1, 1]]), np.zeros(2)))


# --- models are port values: encoded as arrays, cached, sent to other processes -----


def test_every_model_round_trips_through_the_array_encoding(lfw):
    train = rec.hog(lfw.train)
    models = [
        rec.linear_svm(train),
        rec.adaboost(train, rounds=3),
        rec.nearest_neighbour(train),
        rec.cascade(train, max_stages=2, max_stumps=3),
    ]
    for model in models:
        arrays, meta = rec.ClassifierPort.encode(model)
        assert all(isinstance(a, np.ndarray) and not a.dtype.hasobject for a in arrays.values())
        back = rec.ClassifierPort.decode(arrays, meta)
        assert type(back) is type(model)
        np.testing.assert_array_equal(back.predict(train.features), model.predict(train.features))
    subspace = rec.pca(rec.pixels(lfw.train), components=5)
    back = rec.SubspacePort.decode(*rec.SubspacePort.encode(subspace))
    np.testing.assert_array_equal(back.basis, subspace.basis)


def test_a_changed_test_side_reuses_the_cached_model(tmp_path):
    cache = gv.Cache(gv.MemoryStore(), gv.DiskStore(tmp_path))
    graph = gv.load_pipeline(PIPELINES / "faces_cascade.yaml")
    first = gv.run(graph, cache=cache, outputs=["false_positives"])
    again = gv.run(graph, cache=gv.Cache(disk=gv.DiskStore(tmp_path)),
                   outputs=["false_positives"], overrides={"params.threshold": 3.0})  # fmt: skip
    status = {node.name: node.status for node in again.record.nodes}
    assert status["cascade"] == "cached" and status["found"] == "computed"
    assert again.outputs["false_positives"] <= first.outputs["false_positives"]


def test_models_cross_process_boundaries():
    graph = gv.load_pipeline(PIPELINES / "faces_pca.yaml")
    here = gv.run(graph, executor="sync").outputs
    there = gv.run(graph, executor="processes", workers=2).outputs
    assert there["accuracy"] == here["accuracy"]
    np.testing.assert_array_equal(there["subspace"].basis, here["subspace"].basis)


# --- the issue's pipelines against its truths ---------------------------------------


@pytest.mark.parametrize(
    "name, least",
    [("faces_pca", 0.94), ("faces_hog_svm", 0.94), ("faces_boosted", 0.96), ("textures_bow", 0.9)],
)
def test_pipeline_accuracy_reaches_the_issue_truth(name, least):
    out = gv.run(gv.load_pipeline(PIPELINES / f"{name}.yaml"), outputs=["accuracy"]).outputs
    assert out["accuracy"] >= least


def test_face_detect_finds_the_astronaut_face():
    out = gv.run(gv.load_pipeline(PIPELINES / "face_detect.yaml")).outputs
    truth = np.array([[175, 60, 270, 165]], np.float64)  # the issue's face box
    assert rec.iou_matrix(out["boxes"].xyxy, truth).max() >= 0.5
    assert out["face_iou"] >= 0.5
    assert out["count"] == len(out["boxes"]) <= 12  # false positives: count − 1
    assert out["drawing"].shape == (512, 512, 3)


# --- bad input ----------------------------------------------------------------------


def test_a_single_class_is_refused_by_every_trainer():
    one = features(np.eye(4), [1, 1, 1, 1])
    for trainer in (rec.linear_svm, rec.adaboost, rec.nearest_neighbour, rec.cascade):
        with pytest.raises(ValueError, match=r"at least two classes, got only class \[1\]"):
            trainer(one)


def test_fewer_samples_than_components_is_refused():
    with pytest.raises(ValueError, match=r"asked for 8 components, but the 5 training samples"):
        rec.pca(features(np.random.default_rng(0).normal(size=(5, 20)), [0] * 5), components=8)


def test_images_of_different_sizes_are_refused(lfw):
    small = samples(np.zeros((2, 13, 13)), [0, 0])
    with pytest.raises(ValueError, match=r"one size, got \(25, 25\) in 'a' and \(13, 13\) in 'b'"):
        rec.combine(lfw.test, small)
    model = rec.linear_svm(rec.hog(lfw.train))
    with pytest.raises(ValueError, match="trained on 324 features, got 36"):
        rec.predict(model, rec.hog(small))


def test_a_model_of_the_wrong_kind_is_refused_before_running(tmp_path):
    text = (PIPELINES / "faces_pca.yaml").read_text()
    broken = tmp_path / "broken.yaml"
    broken.write_text(text.replace("{classifier: nn,", "{classifier: subspace,"))
    with pytest.raises(gv.PipelineError, match=r"gives Subspace but 'predicted\.classifier'"):
        gv.run(gv.load_pipeline(broken))  # PipelineError: nothing ran


def test_a_window_larger_than_the_image_is_refused(lfw):
    model = rec.linear_svm(rec.hog(lfw.train))
    with pytest.raises(
        ValueError, match=r"window 25×25 \(× min_scale 1\) is larger than the image 20×40"
    ):
        rec.detect(np.zeros((20, 40), np.float32), model)


def test_kmeans_with_more_clusters_than_descriptors_is_refused():
    bags = rec._types.DescriptorBags(
        np.zeros((3, 2), np.float32), np.zeros(3, np.int64), np.zeros(1, np.int64)
    )
    with pytest.raises(ValueError, match="cannot make 5 words from 3 descriptors"):
        rec.kmeans(bags, words=5)


def test_model_ports_refuse_malformed_models():
    with pytest.raises(gv.PortValueError, match="needs at least two classes"):
        rec.ClassifierPort.validate(LinearModel(np.ones((1, 2)), np.zeros(1), np.array([1])))
    with pytest.raises(gv.PortValueError, match="'basis' must be 3×K"):
        rec.SubspacePort.validate(SubspaceModel(np.zeros(3), np.zeros((2, 1)), np.ones(1)))
    stumps = StumpModel(
        np.zeros(1, np.int64), np.zeros(1), np.ones(1), np.ones(1), np.array([0, 1]), 4
    )
    with pytest.raises(ValueError, match="trained on 4 features, got 2"):
        stumps.predict(np.zeros((3, 2)))


def test_detection_by_distance_from_a_subspace_finds_a_blob_at_its_place_and_scale():
    """A subspace of Gaussian blobs (normalised pixels) finds one drawn at twice the size."""
    yy, xx = np.mgrid[0:16, 0:16]
    blobs = [
        np.exp(-((xx - 7.5 - dx) ** 2 + (yy - 7.5 - dy) ** 2) / (2 * s**2))
        for s in (2.5, 3.0, 3.5)
        for dx in (-1, 0, 1)
        for dy in (-1, 0, 1)
    ]
    train = rec.pixels(samples(blobs, np.zeros(len(blobs))), normalise=True)
    subspace = rec.pca(train, components=6)
    scene = np.random.default_rng(0).uniform(0, 0.3, (64, 96)).astype(np.float32)
    y, x = np.mgrid[0:64, 0:96]
    scene += 0.7 * np.exp(-((x - 60) ** 2 + (y - 30) ** 2) / (2 * 6.0**2)).astype(np.float32)
    boxes = rec.nms(rec.detect_subspace(scene, subspace, scale_step=1.25, max_error=0.3))
    truth = np.array([[44, 14, 76, 46]], np.float64)  # 32×32 around (60, 30): 2× the window
    assert rec.iou_matrix(boxes.xyxy[:1], truth)[0, 0] > 0.6  # the best box is the blob
    with pytest.raises(ValueError, match="needs a subspace of window pixels"):
        rec.detect_subspace(scene, rec.pca(rec.hog(samples(blobs, np.zeros(27))), components=2))


def test_previews_show_samples_and_eigenfaces(lfw):
    picture = rec.SamplesPort.preview(lfw.test)
    assert picture.shape == (7 * 26 - 1, 8 * 26 - 1) and picture.dtype == np.float32
    np.testing.assert_allclose(picture[:25, :25], rec.mosaic(lfw.test.images[:1]))
    subspace = rec.pca(rec.pixels(lfw.train), components=20)
    faces = rec.SubspacePort.preview(subspace)
    assert faces.shape == (2 * 26 - 1, 8 * 26 - 1) and 0 <= faces.min() < faces.max() <= 1
    assert rec.SubspacePort.preview(rec.pca(rec.hog(lfw.train), components=3)) is None


def test_negative_patches_are_seeded_resized_crops():
    negatives = rec.negative_patches(images=("brick", "text"), count=10, size=20, seed=4)
    assert negatives.images.shape == (10, 20, 20) and (negatives.labels == 0).all()
    again = rec.negative_patches(images=("brick", "text"), count=10, size=20, seed=4)
    np.testing.assert_array_equal(negatives.images, again.images)


def test_hard_negatives_are_the_windows_the_classifier_gets_wrong(lfw):
    train = rec.combine(lfw.train, rec.negative_patches(images=("brick", "text"), count=100))
    model = rec.linear_svm(rec.hog(train))
    hard = rec.mine_negatives(model, images=("text", "page"), count=40, min_scale=2.0)
    assert hard.images.shape == (40, 25, 25) and (hard.labels == 0).all()
    easy = rec.negative_patches(images=("text", "page"), count=40, seed=1)
    hard_scores = model.decision(rec.hog(hard).features)
    assert np.median(hard_scores) > np.percentile(model.decision(rec.hog(easy).features), 90)
    # retrained with them, the classifier accepts fewer windows of those images
    retrained = rec.linear_svm(rec.hog(rec.combine(train, hard)))
    page = rec._data.face_free_image("page")

    def accepted(m):
        return len(rec.detect(page, m, min_scale=2.0, max_scale=4.0))

    assert accepted(retrained) < accepted(model)
