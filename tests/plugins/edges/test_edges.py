"""Derivative filters and Canny against analytic truths, drawn shapes and scikit-image."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.ndimage as ndi
import skimage.data
import skimage.feature

import graphvision as gv
from graphvision_plugins import edges


def f1_score(found: np.ndarray, truth: np.ndarray, tolerance: int = 1) -> float:
    """F1 of two edge maps, a pixel matching when the other map has one within ``tolerance``."""
    near = np.ones((2 * tolerance + 1,) * 2, dtype=bool)
    precision = (found & ndi.binary_dilation(truth, near)).sum() / found.sum()
    recall = (truth & ndi.binary_dilation(found, near)).sum() / truth.sum()
    return float(2 * precision * recall / (precision + recall))


@pytest.mark.parametrize("kind", edges.DERIVATIVES)
def test_every_derivative_measures_the_slope_of_a_ramp(kind):
    y, x = np.mgrid[0:24, 0:24].astype(np.float32)
    ramp = (0.01 * x + 0.02 * y).astype(np.float32)  # ∂x = 0.01, ∂y = 0.02 by construction
    inner = (slice(8, 16), slice(8, 16))
    dx = edges.derivative(ramp, axis="x", kind=kind)
    dy = edges.derivative(ramp, axis="y", kind=kind)
    np.testing.assert_allclose(dx[inner], 0.01, rtol=1e-4)
    np.testing.assert_allclose(dy[inner], 0.02, rtol=1e-4)
    g = edges.gradient(ramp, kind=kind)
    np.testing.assert_allclose(g.magnitude[inner], math.hypot(0.01, 0.02), rtol=1e-4)
    np.testing.assert_allclose(g.orientation[inner], math.atan2(0.02, 0.01), atol=1e-4)


def test_kernels_are_the_textbook_ones():
    # Sobel (Szeliski 2022, fig. 3.14) up to its 1/8 and Prewitt up to 1/6
    sobel = [[-1, 0, 1], [-2, 0, 2], [-1, 0, 1]]
    np.testing.assert_allclose(edges.derivative_kernel(axis="x", kind="sobel") * 8, sobel)
    np.testing.assert_allclose(
        edges.derivative_kernel(axis="y", kind="sobel") * 8, np.transpose(sobel)
    )
    np.testing.assert_allclose(edges.derivative_kernel(kind="prewitt") * 6, [[-1, 0, 1]] * 3)
    np.testing.assert_allclose(edges.derivative_kernel(kind="forward"), [[0, -1, 1]])


def test_derivative_of_gaussian_attenuates_a_sinusoid_as_the_theory_says():
    # ∂x (G_σ * sin ωx) = ω cos(ωx) e^{-ω²σ²/2}: smoothing then differentiating is one filter
    omega, sigma = 0.3, 2.0
    x = np.arange(256, dtype=np.float64)
    wave = np.tile(0.5 + 0.4 * np.sin(omega * x), (32, 1)).astype(np.float32)
    response = edges.derivative(wave, axis="x", kind="gaussian", sigma=sigma, boundary="wrap")
    theory = 0.4 * omega * np.cos(omega * x) * math.exp(-((omega * sigma) ** 2) / 2)
    peak = np.abs(theory).max()  # sampling a 3σ-truncated kernel costs under 1 % of it
    np.testing.assert_allclose(response[16, 20:-20], theory[20:-20], atol=0.01 * peak)


def drawn_shapes(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A disc (radius 25 at (40, 45)) and a square (rows and columns 20..59 shifted right),
    plus Gaussian noise σ = 0.05; returns the image and each pixel's distance to the true
    boundary."""
    y, x = np.mgrid[0:96, 0:160].astype(np.float64)
    radius = np.hypot(x - 45, y - 40)
    in_square = (x >= 95) & (x <= 134) & (y >= 20) & (y <= 59)
    image = 0.2 + 0.6 * ((radius <= 25) | in_square)
    noise = np.random.default_rng(seed).normal(0, 0.05, image.shape)
    to_circle = np.abs(radius - 25)
    # the square's boundary lies half a pixel outside its outermost pixels
    dx = np.maximum(np.maximum(94.5 - x, x - 134.5), 0)
    dy = np.maximum(np.maximum(19.5 - y, y - 59.5), 0)
    outside = np.hypot(dx, dy)
    inside = np.minimum.reduce([x - 94.5, 134.5 - x, y - 19.5, 59.5 - y])
    to_square = np.where((dx > 0) | (dy > 0), outside, inside)
    distance = np.minimum(to_circle, to_square)
    return np.clip(image + noise, 0, 1).astype(np.float32), distance


@pytest.mark.parametrize("seed", range(3))
def test_canny_finds_drawn_boundaries_within_one_pixel(seed):
    image, distance = drawn_shapes(seed)
    found = edges.canny(image, sigma=1.5, low=0.05, high=0.1).edges
    assert (distance[found] <= 1.0).all()  # localisation: every edge pixel within 1 px
    truth = distance <= 0.5  # one pixel on each side of the true curve (a 1-px-wide band)
    assert f1_score(found, truth) >= 0.95


def test_canny_agrees_with_scikit_image_on_camera():
    camera = (skimage.data.camera() / 255).astype(np.float32)
    # reference: skimage.feature.canny(camera, sigma=1, low_threshold=0.8,
    #   high_threshold=0.9, use_quantiles=True); its Sobel adds the variance of
    #   [1, 2, 1]/4 (0.5) to the Gaussian's, hence σ = √1.5 here (F1 0.974 measured)
    reference = skimage.feature.canny(
        camera, sigma=1.0, low_threshold=0.8, high_threshold=0.9, use_quantiles=True
    )
    ours = edges.canny(camera, sigma=math.sqrt(1.5), low=0.8, high=0.9, thresholds="quantile")
    assert f1_score(ours.edges, reference) >= 0.95


def test_non_maximum_suppression_thins_a_blurred_step_to_its_centre():
    step = np.zeros((20, 40), np.float32)
    step[:, 20:] = 1.0  # boundary between columns 19 and 20
    found = edges.canny(step, sigma=2.0).edges
    # the two columns tie; the asymmetric rule keeps the first, as cv2.Canny does
    assert set(np.flatnonzero(found.any(axis=0))) == {19}
    assert found[:, 19].all()


@pytest.mark.parametrize("thresholds", ["absolute", "quantile"])
@pytest.mark.parametrize("value", [0.0, 0.5, 1.0])
def test_a_constant_image_has_no_edges(value, thresholds):
    flat = np.full((32, 32), value, np.float32)
    result = edges.canny(flat, low=0.1, high=0.2, thresholds=thresholds)
    assert not result.edges.any() and not result.magnitude.any()


def test_bad_thresholds_are_refused_naming_them():
    image = np.zeros((8, 8), np.float32)
    with pytest.raises(ValueError, match=r"edges.canny: low \(0.5\) must be at most high \(0.2\)"):
        edges.canny(image, low=0.5, high=0.2)
    with pytest.raises(ValueError, match=r"quantile thresholds lie in \[0, 1\], got high=2"):
        edges.canny(image, low=0.5, high=2.0, thresholds="quantile")


def test_colour_given_to_a_gray_node_names_both_types(tmp_path):
    with pytest.raises(gv.PortValueError, match="expected GrayImage"):
        edges.canny(np.zeros((8, 8, 3), np.float32))
    pipeline = tmp_path / "colour.yaml"
    pipeline.write_text(
        "version: 1\nname: colour\n"
        "inputs:\n  image: {type: ColorImage, default: 'sample:astronaut'}\n"
        "nodes:\n  canny: {op: edges.canny, in: {image: image}}\n"
        "outputs:\n  edges: canny.edges\n"
    )
    with pytest.raises(
        gv.PipelineError,
        match=r"'image' gives ColorImage but 'canny.image'.*"
        r"takes GrayImage",
    ):
        gv.compile_graph(gv.load_pipeline(pipeline), gv.discover())


def test_draw_marks_the_edges():
    image, _ = drawn_shapes(0)
    found = edges.canny(image, sigma=1.5, low=0.05, high=0.1).edges
    drawing = edges.draw_edges(image, found)
    assert drawing.shape == (*image.shape, 3)
    np.testing.assert_allclose(drawing[found], np.tile([0.1, 0.95, 0.1], (found.sum(), 1)))
    with pytest.raises(ValueError, match="image and edges must have the same size"):
        edges.draw_edges(image, found[:10])


def test_edges_pipeline_on_camera():
    from tests.conftest import PIPELINES

    out = gv.run(gv.load_pipeline(PIPELINES / "edges.yaml")).outputs
    assert out["edges"].shape == out["magnitude"].shape == (512, 512)
    # hysteresis seeds are the strongest tenth; edges are thin, so far fewer than 20 %
    assert 0.02 < out["edges"].mean() < 0.1
