"""Semantic segmentation: each layer's gradient against finite differences, the
up-convolution against a hand scatter, the whole U-Net's gradient, the pixel loss, mean IU
on hand-built label pairs, the scenes' geometry, a tiny network learning a two-class
scene, the pictures, and the checks of direct calls."""

from __future__ import annotations

import json

import numpy as np
import pytest

import graphvision as gv
from graphvision_plugins import segmentation, synthetic
from graphvision_plugins.segmentation import Conv, MaxPool, Relu, UpConv
from graphvision_plugins.synthetic import LabelledSceneSet

pytestmark = pytest.mark.heavy  # trains networks: run first (tests/conftest.py)


def _relative_error(analytic: np.ndarray, numeric: np.ndarray) -> float:
    return float(np.abs(analytic - numeric).max() / max(np.abs(numeric).max(), 1e-12))


def _numeric_gradient(f, x: np.ndarray, step: float = 1e-6) -> np.ndarray:
    """Central differences of the scalar f at x (x changed in place and restored)."""
    grad = np.zeros_like(x)
    flat, out = x.reshape(-1), grad.reshape(-1)
    for i in range(flat.size):
        keep = flat[i]
        flat[i] = keep + step
        up = f()
        flat[i] = keep - step
        down = f()
        flat[i] = keep
        out[i] = (up - down) / (2 * step)
    return grad


@pytest.mark.parametrize(
    ("layer", "shape"),
    [
        (Conv(3, 3), (5, 6, 2)),
        (Conv(2, 5), (4, 4, 3)),
        (Conv(4, 1), (3, 5, 3)),
        (Relu(), (4, 4, 2)),
        (MaxPool(), (4, 6, 3)),
        (UpConv(3), (3, 2, 4)),
    ],
    ids=["conv3", "conv5", "conv1", "relu", "maxpool", "upconv"],
)
def test_each_layer_gradient_equals_finite_differences(layer, shape):
    rng = np.random.default_rng(0)
    x = rng.normal(size=(2, *shape))
    params = [rng.normal(size=s) for s in layer.parameter_shapes(shape[2])]
    y, saved = layer.forward(x, params)
    probe = rng.normal(size=y.shape)  # the loss sum(probe · y) has dL/dy = probe

    def loss() -> float:
        return float((layer.forward(x, params)[0] * probe).sum())

    d_x, d_params = layer.backward(probe, saved, params)
    assert _relative_error(d_x, _numeric_gradient(loss, x)) < 1e-5
    for analytic, param in zip(d_params, params, strict=True):
        assert _relative_error(analytic, _numeric_gradient(loss, param)) < 1e-5


def test_upconv_spreads_each_pixel_over_its_own_two_by_two_cell():
    rng = np.random.default_rng(1)
    x = rng.normal(size=(1, 2, 3, 4))
    weights, bias = rng.normal(size=(4, 2, 2, 5)), rng.normal(size=5)
    y, _ = UpConv(5).forward(x, [weights, bias])
    assert y.shape == (1, 4, 6, 5)
    expected = np.zeros((4, 6, 5))
    for i in range(2):
        for j in range(3):
            for a in range(2):
                for b in range(2):
                    expected[2 * i + a, 2 * j + b] = x[0, i, j] @ weights[:, a, b] + bias
    np.testing.assert_allclose(y[0], expected, atol=1e-12)


def test_conv_equals_a_direct_correlation_with_zero_padding():
    rng = np.random.default_rng(2)
    x = rng.normal(size=(1, 4, 5, 2))
    weights, bias = rng.normal(size=(3, 3, 2, 2)), rng.normal(size=2)
    y, _ = Conv(2, 3).forward(x, [weights, bias])
    padded = np.pad(x[0], ((1, 1), (1, 1), (0, 0)))
    for r in range(4):
        for c in range(5):
            window = padded[r : r + 3, c : c + 3]
            direct = np.einsum("abc,abco->o", window, weights) + bias
            np.testing.assert_allclose(y[0, r, c], direct, atol=1e-12)


def test_whole_unet_gradient_with_the_pixel_loss_equals_finite_differences():
    net = segmentation.build_unet([2, 3], classes=3, convs=1)
    rng = np.random.default_rng(3)
    weights = net.initial_weights(0)
    x = rng.normal(size=(2, 4, 4, 1))
    y = rng.integers(0, 3, size=(2, 4, 4))
    class_weights = np.array([0.5, 1.0, 2.0])

    def loss() -> float:
        return segmentation.pixel_cross_entropy(net.forward(weights, x)[0], y, class_weights)[0]

    scores, saved = net.forward(weights, x, keep=True)
    assert scores.shape == (2, 4, 4, 3)
    _, grad = segmentation.pixel_cross_entropy(scores, y, class_weights)
    analytic = net.backward(weights, grad, saved)
    assert analytic.shape == weights.shape == (net.size,)
    assert _relative_error(analytic, _numeric_gradient(loss, weights)) < 1e-5


def test_pixel_cross_entropy_is_the_weighted_mean_of_minus_log_p():
    scores = np.array([[[[2.0, 0.0], [0.0, 1.0]]]])  # one scene 1×2, two classes
    labels = np.array([[[0, 0]]])
    p0 = np.array([np.exp(2) / (np.exp(2) + 1), 1 / (1 + np.e)])
    loss, _ = segmentation.pixel_cross_entropy(scores, labels, np.array([1.0, 1.0]))
    assert loss == pytest.approx(-np.log(p0).mean(), rel=1e-12)
    labels = np.array([[[0, 1]]])  # class 1 weighs 3: (−log p_a + 3 · −log p_b) / 4
    p1 = np.e / (1 + np.e)
    loss, _ = segmentation.pixel_cross_entropy(scores, labels, np.array([1.0, 3.0]))
    assert loss == pytest.approx((-np.log(p0[0]) - 3 * np.log(p1)) / 4, rel=1e-12)


# --------------------------------------------------------------------------- scores


def _scenes(labels: np.ndarray, names=("background", "disc", "square")) -> LabelledSceneSet:
    labels = np.asarray(labels, np.int32)
    return LabelledSceneSet(np.zeros(labels.shape, np.float32), labels, json.dumps(list(names)))


def test_mean_iou_and_pixel_accuracy_of_a_hand_built_pair():
    truth = _scenes([[[0, 0, 1, 1], [0, 0, 1, 1], [2, 2, 2, 2]]])
    predicted = _scenes([[[0, 1, 1, 1], [0, 0, 1, 2], [2, 2, 0, 2]]])
    scores = segmentation.evaluate(predicted, truth)
    # background: 3 hit, 4 true, 4 predicted → 3 / 5; disc: 3 / 5; square: 3 / 5
    np.testing.assert_allclose(scores.classes["iou"], [3 / 5, 3 / 5, 3 / 5])
    assert scores.miou == pytest.approx(3 / 5)
    assert scores.pixel_accuracy == pytest.approx(9 / 12)
    np.testing.assert_array_equal(scores.classes["pixels"], [4, 4, 4])


def test_a_class_absent_everywhere_is_left_out_of_the_mean():
    truth = _scenes([[[0, 0], [1, 1]]])
    scores = segmentation.evaluate(_scenes([[[0, 1], [1, 1]]]), truth)
    iou = scores.classes["iou"]
    assert iou[:2] == pytest.approx([1 / 2, 2 / 3]) and np.isnan(iou[2])
    assert scores.miou == pytest.approx((1 / 2 + 2 / 3) / 2)


def test_evaluate_refuses_other_classes_and_other_shapes():
    truth = _scenes([[[0, 1]]])
    with pytest.raises(ValueError, match="labelling names the classes"):
        segmentation.evaluate(_scenes([[[0, 1]]], ("background", "cat")), truth)
    with pytest.raises(ValueError, match="must have the same shape"):
        segmentation.confusion_matrix(np.zeros((2, 2), int), np.zeros((2, 3), int), 2)


# --------------------------------------------------------------------------- scenes


@pytest.mark.parametrize(
    ("shape", "area"),
    [
        ("disc", np.pi),
        ("square", 1.6**2),
        ("triangle", 3 * np.sqrt(3) / 4),
        ("cross", 2 * 2 * 0.6 - 0.6**2),
    ],
)
def test_a_shape_labels_the_pixels_of_its_area(shape, area):
    """One shape of size 10 in a flat scene without noise: its label covers its area
    (r² times the shape's factor) to within its perimeter's half-pixels, and its pixels
    carry its gray level."""
    from graphvision_plugins.synthetic._shape_scenes import _coverage, _paint

    canvas, labels = np.full((96, 96), 0.1), np.zeros((96, 96), np.int32)
    coverage, shade, corner = _coverage(shape, np.array([50.3, 40.7]), 10.0, 0.3)
    _paint(canvas, labels, (coverage, shade), corner, (0.8, 1))
    assert set(np.unique(labels)) == {0, 1}
    assert coverage.sum() == pytest.approx(area * 100, rel=0.01)  # 16 samples per pixel
    assert (labels == 1).sum() == pytest.approx(area * 100, rel=0.06)
    images = canvas[None]
    labels = labels[None]
    inside = labels[0] == 1
    assert np.median(images[0][inside]) == pytest.approx(0.8, abs=1e-6)
    assert np.median(images[0][~inside]) == pytest.approx(0.1, abs=1e-6)


def test_shape_scenes_are_seeded_and_name_their_classes():
    a = synthetic.shape_scenes(count=3, side=32, max_size=8, classes=["cross", "disc"], seed=4)
    b = synthetic.shape_scenes(count=3, side=32, max_size=8, classes=["cross", "disc"], seed=4)
    np.testing.assert_array_equal(a.images, b.images)
    assert a.class_names == ["background", "cross", "disc"]
    assert a.labels.max() <= 2 and a.images.dtype == np.float32


def test_shape_scenes_refuse_bad_parameters():
    with pytest.raises(gv.ParameterError, match="min_size"):
        synthetic.shape_scenes(min_size=9, max_size=8)
    with pytest.raises(gv.ParameterError, match="classes"):
        synthetic.shape_scenes(classes=["hexagon"])
    with pytest.raises(ValueError, match=r"max_size \(20\) must be below half the scene's side"):
        synthetic.shape_scenes(side=32, max_size=20)
    with pytest.raises(ValueError, match="names a shape twice"):
        synthetic.shape_scenes(classes=["disc", "disc"])
    bad = LabelledSceneSet(np.zeros((1, 4, 4), np.float32), np.full((1, 4, 4), 3, np.int32),
                           json.dumps(["background", "disc"]))  # fmt: skip
    with pytest.raises(gv.PortValueError, match=r"'labels' must lie in \[0, 2\)"):
        synthetic.LabelledScenesPort.validate(bad)


# --------------------------------------------------------------------------- learning


def test_a_tiny_network_learns_a_two_class_scene():
    """Discs on textured backgrounds: a two-level network of 4 and 8 filters, trained for
    a few seconds, labels held-out scenes (another seed) nearly right."""
    kwargs = {"side": 32, "classes": ["disc"], "min_size": 4, "max_size": 7, "max_objects": 3}
    train = synthetic.shape_scenes(count=24, seed=0, **kwargs)
    test = synthetic.shape_scenes(count=12, seed=99, **kwargs)
    network = segmentation.train(train, widths=[4, 8], convs=1, epochs=12, batch_size=4,
                                 learning_rate=0.02, seed=0)  # fmt: skip
    assert network.history[-1] < 0.5 * network.history[0]
    scores = segmentation.evaluate(segmentation.predict(network, test), test)
    assert scores.miou > 0.85
    assert scores.pixel_accuracy > 0.95
    again = segmentation.train(train, widths=[4, 8], convs=1, epochs=12, batch_size=4,
                               learning_rate=0.02, seed=0)  # fmt: skip
    np.testing.assert_array_equal(again.weights, network.weights)  # seeded: reproducible


def test_class_weights_balance_by_the_median_frequency():
    labels = np.array([0] * 6 + [1] * 3 + [2] * 1)  # f = 0.6, 0.3, 0.1; median 0.3
    weights = segmentation.class_weights(labels, 4, "median_frequency")
    np.testing.assert_allclose(weights, [0.5, 1.0, 3.0, 1.0], rtol=1e-6)
    np.testing.assert_array_equal(segmentation.class_weights(labels, 3, "none"), 1.0)


# --------------------------------------------------------------------------- direct calls


def test_direct_calls_check_inputs_and_parameters():
    scenes = synthetic.shape_scenes(count=2, side=24, max_size=6, classes=["disc"], seed=1)
    with pytest.raises(gv.ParameterError, match="widths"):
        segmentation.train(scenes, widths=[8])
    with pytest.raises(gv.ParameterError, match="learning_rate"):
        segmentation.train(scenes, learning_rate=2.0)
    with pytest.raises(ValueError, match="multiples of 16: use fewer widths"):
        segmentation.train(scenes, widths=[2, 2, 2, 2, 2], epochs=1)
    with pytest.raises(ValueError, match="lower batch_size"):
        big = synthetic.shape_scenes(count=80, side=64, classes=["disc"], seed=1)
        segmentation.train(big, batch_size=80, epochs=1, crop=0)
    with pytest.raises(ValueError, match="crop 12 must be a multiple of 8"):
        segmentation.train(scenes, widths=[2, 2, 2, 2], crop=12)
    with pytest.raises(
        ValueError, match=r"crop 32 must be a multiple of 2 .* no larger than the 24×24"
    ):
        segmentation.train(scenes, widths=[2, 2])
    network = segmentation.train(scenes, widths=[2, 2], convs=1, epochs=1, crop=0)
    other = synthetic.shape_scenes(count=1, side=24, max_size=6, classes=["square"])
    with pytest.raises(ValueError, match="the network labels"):
        segmentation.predict(network, other)
    bad = segmentation.SegmenterModel(network.architecture, network.weights[:-1], network.names,
                                      network.history, network.accuracy)  # fmt: skip
    with pytest.raises(gv.PortValueError, match=r"'weights' must hold \d+ values"):
        segmentation.SegmenterPort.validate(bad)


def test_predict_refuses_sides_the_levels_do_not_divide():
    scenes = synthetic.shape_scenes(count=2, side=24, max_size=6, classes=["disc"], seed=1)
    network = segmentation.train(scenes, widths=[2, 2], convs=1, epochs=1, crop=0)
    odd = LabelledSceneSet(np.zeros((1, 9, 10), np.float32), np.zeros((1, 9, 10), np.int32),
                           scenes.names)  # fmt: skip
    with pytest.raises(ValueError, match="sides must be multiples of 2; got 9×10"):
        segmentation.predict(network, odd)


# --------------------------------------------------------------------------- pictures


def test_label_picture_shows_scenes_truth_prediction_and_legend():
    truth = _scenes([[[0, 0, 1, 1], [0, 0, 1, 1], [2, 2, 2, 2], [2, 2, 2, 2]]])
    predicted = _scenes([[[0, 0, 1, 1], [0, 0, 1, 1], [2, 2, 2, 2], [2, 2, 2, 1]]])
    picture = segmentation.draw_labels(truth, predicted, count=1)
    colours = segmentation.class_colours(3)
    top = 4 + 4 + 4  # margin, the scene, margin: the truth row starts here
    np.testing.assert_allclose(picture[top, 4], colours[0])
    np.testing.assert_allclose(picture[top, 6], colours[1])
    np.testing.assert_allclose(picture[top + 2, 4], colours[2])
    wrong = picture[top + 8 + 3, 4 + 3]  # the one pixel labelled wrong: outlined white
    np.testing.assert_allclose(wrong, 1.0)
    legend = picture[3 * (4 + 4) :]  # three rows of margin + 4-pixel scenes
    assert legend.shape[0] >= 16
    for colour in colours:  # each class's swatch is in the legend
        assert np.isclose(legend, colour, atol=1e-6).all(axis=2).any()


def test_training_curve_draws_loss_and_accuracy():
    scenes = synthetic.shape_scenes(count=2, side=24, max_size=6, classes=["disc"], seed=1)
    network = segmentation.train(scenes, widths=[2, 2], convs=1, epochs=3, crop=8)
    picture = segmentation.draw_curve(network, width=200, height=120)
    assert picture.shape == (120, 200, 3)
    red = (picture[..., 0] > 0.7) & (picture[..., 1] < 0.3)
    blue = (picture[..., 2] > 0.7) & (picture[..., 0] < 0.3)
    assert red[:, 41:160].any() and blue[:, 41:160].any()
