"""Gray and chromaticity by hand, colour spaces against scikit-image, histograms against numpy,
distances by hand, retrieval; the ops renamed when ``color`` joined ``colour``."""

from __future__ import annotations

import math

import numpy as np
import pytest
import skimage.color
import skimage.data

import graphvision as gv
from graphvision_plugins import colour

from ...conftest import PIPELINES

REFERENCE = {
    "hsv": skimage.color.rgb2hsv,
    "lab": skimage.color.rgb2lab,  # D65, 2° observer (its defaults)
    "ycbcr": skimage.color.rgb2ycbcr,
}


def pictures() -> list[np.ndarray]:
    rng = np.random.default_rng(0)
    corners = np.array(np.meshgrid([0, 1], [0, 1], [0, 1], indexing="ij")).reshape(3, 1, 8).T
    return [
        skimage.data.astronaut()[::4, ::4] / 255.0,
        rng.random((40, 40, 3)),
        corners.reshape(8, 1, 3).astype(np.float64),  # the cube's corners: black, white, primaries
    ]


def test_gray_is_the_channel_mean_or_bt601_luminance():
    rgb = np.array([[[0.3, 0.6, 0.9], [1.0, 0.0, 0.0]]], np.float32)
    np.testing.assert_allclose(colour.to_gray(rgb), [[0.6, 1 / 3]], rtol=1e-6)
    np.testing.assert_allclose(
        colour.to_gray(rgb, method="luminance"),
        [[0.299 * 0.3 + 0.587 * 0.6 + 0.114 * 0.9, 0.299]],
        rtol=1e-6,
    )
    gray = np.full((2, 2), 0.25, np.float32)
    assert colour.to_gray(gray) is gray


def test_chromaticity_sums_to_one_and_ignores_intensity():
    rgb = np.random.default_rng(0).random((10, 10, 3)).astype(np.float32) * 0.5
    chroma = colour.chromaticity(rgb)
    np.testing.assert_allclose(chroma.sum(axis=2), 1.0, rtol=1e-6)
    np.testing.assert_allclose(colour.chromaticity(rgb * 2), chroma, rtol=1e-5)
    black = np.zeros((1, 1, 3), np.float32)
    np.testing.assert_allclose(colour.chromaticity(black), 1 / 3)


@pytest.mark.parametrize("space", colour.SPACES)
def test_spaces_equal_scikit_image(space):
    for rgb in pictures():
        # reference: skimage.color.rgb2hsv / rgb2lab / rgb2ycbcr on the same float64 image
        np.testing.assert_allclose(colour.rgb_to(rgb, space), REFERENCE[space](rgb), atol=1e-4)
        single = rgb.astype(np.float32)
        expected = REFERENCE[space](single.astype(np.float64))
        np.testing.assert_allclose(colour.from_rgb(single, space=space), expected, atol=1e-4)


@pytest.mark.parametrize("space", colour.SPACES)
def test_round_trips(space):
    for rgb in pictures():
        back = colour.to_rgb_from(colour.rgb_to(rgb, space), space)
        np.testing.assert_allclose(back, rgb, atol=1e-5)
    image = pictures()[0].astype(np.float32)
    again = colour.to_rgb(colour.from_rgb(image, space=space), space=space)
    np.testing.assert_allclose(again, image, atol=1e-4)  # float32 in between


def test_known_colours():
    red = np.array([[[1.0, 0.0, 0.0]]])
    np.testing.assert_allclose(colour.rgb_to(red, "hsv")[0, 0], [0, 1, 1])
    white = np.ones((1, 1, 3))
    # the published sRGB matrix and D65 white agree to 4 digits: a*, b* of white are ~0.005
    np.testing.assert_allclose(colour.rgb_to(white, "lab")[0, 0], [100, 0, 0], atol=0.01)
    np.testing.assert_allclose(colour.rgb_to(white, "ycbcr")[0, 0], [235, 128, 128], atol=1e-3)


def test_histograms_equal_numpy_and_sum_to_one():
    image = (skimage.data.astronaut()[::4, ::4] / 255.0).astype(np.float32)
    joint = colour.histogram(image, bins=4)
    # reference: numpy.histogramdd over [0, 1]³ with 4 bins per axis (last bin closed)
    expected, _ = np.histogramdd(image.reshape(-1, 3), bins=4, range=[(0, 1)] * 3)
    np.testing.assert_allclose(joint, expected / expected.sum())
    channels = colour.histogram(image, bins=5, kind="channels")
    assert channels.shape == (15,) and channels.sum() == pytest.approx(1.0)
    gray = colour.histogram(image.mean(axis=2), bins=3)
    # reference: numpy.histogram(gray, bins=3, range=(0, 1))
    counts, _ = np.histogram(image.mean(axis=2), bins=3, range=(0, 1))
    np.testing.assert_allclose(gray, counts / counts.sum())


def test_distances_by_hand():
    a = np.array([0.5, 0.5, 0.0])
    b = np.array([0.25, 0.25, 0.5])
    assert colour.histogram_distance(a, b, metric="euclidean") == pytest.approx(
        math.sqrt(0.0625 + 0.0625 + 0.25)
    )
    # χ² = ½ (0.0625/0.75 + 0.0625/0.75 + 0.25/0.5) = ½ (1/6 + 1/2)
    assert colour.histogram_distance(a, b, metric="chi2") == pytest.approx(1 / 3)
    # Bhattacharyya coefficient 2 √(0.125) = 0.7071
    assert colour.histogram_distance(a, b, metric="hellinger") == pytest.approx(
        math.sqrt(1 - 2 * math.sqrt(0.125))
    )
    assert colour.histogram_distance(a, b, metric="intersection") == pytest.approx(0.5)
    for metric in colour.METRICS:
        assert colour.histogram_distance(a, a, metric=metric) == pytest.approx(0.0, abs=1e-12)


def test_retrieval_pipeline_finds_the_copies():
    out = gv.run(gv.load_pipeline(PIPELINES / "retrieval.yaml")).outputs
    # 4 same-picture entries exist for each query: precision at 4 of 1 would be perfect
    assert out["precision_chi2"] >= 0.9 and out["precision_intersection"] >= 0.9
    assert out["ranking"].shape == (25, 24)


def test_bad_input_is_refused_naming_it():
    image = np.zeros((4, 4, 3), np.float32)
    with pytest.raises(gv.ParameterError, match="bins"):
        colour.histogram(image, bins=0)
    with pytest.raises(ValueError, match=r"histograms a and b must have the same shape"):
        colour.histogram_distance(np.ones(3) / 3, np.ones(4) / 4)
    with pytest.raises(gv.PortValueError, match="expected ColorImage"):
        colour.from_rgb(np.zeros((4, 4), np.float32))
    with pytest.raises(ValueError, match=r"k \(5\) must be smaller than the gallery \(3 entries\)"):
        colour.retrieve(np.ones((3, 2), np.float32), np.arange(3), k=5)
    with pytest.raises(gv.PortValueError, match="expected Histogram"):
        colour.HistogramPort.validate(np.array([0.5, -0.1]))


# -- one family: the former ``color`` ops live here under new ids (issue 23, item 3) ----------


def test_the_renamed_ops_are_exactly_the_ops_that_moved(registry):
    # the ops of the ``color`` family before the merge (``graphvision nodes`` at 0ccde11)
    assert set(colour.RENAMED_OPS) == {"color.chromaticity", "color.to_gray"}
    moved = {
        spec.id
        for spec in registry.nodes.values()
        if spec.ref.module == "graphvision_plugins.colour._intensity"
    }
    assert set(colour.RENAMED_OPS.values()) == moved
    for old, new in colour.RENAMED_OPS.items():
        assert new == "colour." + old.removeprefix("color.")
        assert old not in registry.nodes and registry.node(new).plugin == "colour"
    assert "color" not in registry.plugins
    assert not [op for op in registry.nodes if op.startswith("color.")]


@pytest.mark.parametrize("path", sorted(PIPELINES.glob("*.yaml")), ids=lambda p: p.name)
def test_no_shipped_pipeline_uses_an_old_op_id(path):
    ops = {decl.op for decl in gv.load_pipeline(path).nodes.values()}
    assert not ops & colour.RENAMED_OPS.keys()
    assert not [old for old in colour.RENAMED_OPS if old in path.read_text()]  # nor names one
