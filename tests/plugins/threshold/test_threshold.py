"""Thresholds against scikit-image, OpenCV-free truths and Barron's stated special cases."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.ndimage as ndi
import skimage.data
import skimage.filters

from graphvision_plugins import threshold

SAMPLES = ["camera", "coins", "page"]


def sample(name):
    return (getattr(skimage.data, name)() / 255.0).astype(np.float32)


def two_modes(seed=0, low=0.3, high=0.7, spread=0.05, share=0.3, size=(120, 150)):
    rng = np.random.default_rng(seed)
    dark = rng.random(size) < share
    values = np.where(dark, rng.normal(low, spread, size), rng.normal(high, spread, size))
    return np.clip(values, 0, 1).astype(np.float32), dark


@pytest.mark.parametrize("name", SAMPLES)
def test_otsu_equals_scikit_image(name):
    image = sample(name)
    # reference: skimage.filters.threshold_otsu(image, nbins=256)
    assert threshold.otsu(image).threshold == pytest.approx(
        float(skimage.filters.threshold_otsu(image, nbins=256)), abs=1e-6
    )


def test_otsu_separates_two_modes():
    image, dark = two_modes()
    result = threshold.otsu(image)
    assert 0.4 < result.threshold < 0.6
    assert (result.mask == ~dark).mean() > 0.99
    np.testing.assert_array_equal(threshold.otsu(image, foreground="dark").mask, ~result.mask)


def test_constant_image_has_no_threshold():
    with pytest.raises(ValueError, match=r"image is constant \(every pixel is 0.5\)"):
        threshold.otsu(np.full((5, 5), 0.5, np.float32))
    with pytest.raises(ValueError, match="no threshold exists"):
        threshold.ght(np.zeros((5, 5), np.float32))


def test_ght_reduces_to_otsu():
    """Barron 2020: nu -> infinity with tau -> 0 is Otsu's method."""
    for name in SAMPLES:
        image = sample(name)
        assert threshold.ght(image, nu=1e30, tau=1e-6).threshold == pytest.approx(
            threshold.otsu(image).threshold
        )


def kittler_illingworth(image, bins=256):
    """Minimum error thresholding written from Kittler & Illingworth (1986), eq. 15, directly."""
    counts, centres = threshold.histogram(image, bins)
    p = counts / counts.sum()
    best, best_t = np.inf, None
    for t in range(bins - 1):
        p0, p1 = p[: t + 1].sum(), p[t + 1 :].sum()
        if p0 == 0 or p1 == 0:
            continue
        m0 = (p[: t + 1] * centres[: t + 1]).sum() / p0
        m1 = (p[t + 1 :] * centres[t + 1 :]).sum() / p1
        v0 = (p[: t + 1] * (centres[: t + 1] - m0) ** 2).sum() / p0
        v1 = (p[t + 1 :] * (centres[t + 1 :] - m1) ** 2).sum() / p1
        if v0 <= 0 or v1 <= 0:
            continue
        j = (
            1
            + 2 * (p0 * np.log(np.sqrt(v0)) + p1 * np.log(np.sqrt(v1)))
            - 2 * (p0 * np.log(p0) + p1 * np.log(p1))
        )
        if j < best:
            best, best_t = j, centres[t]
    return best_t


@pytest.mark.parametrize("seed", range(4))
def test_ght_defaults_are_minimum_error_thresholding(seed):
    """Barron 2020: nu = kappa = 0 is MET (up to the bins where a class is a single level)."""
    image, _ = two_modes(seed=seed, low=0.25, high=0.6, spread=0.04 + 0.02 * seed, share=0.2)
    # thresholds anywhere in an empty stretch of the histogram split the pixels alike
    # (MET is flat there; GHT takes the middle of ties): compare the partitions
    np.testing.assert_array_equal(threshold.ght(image).mask, image > kittler_illingworth(image))


def test_ght_with_a_strong_weight_prior_is_a_percentile():
    image = np.random.default_rng(1).random((100, 100)).astype(np.float32)
    for omega in (0.25, 0.5, 0.8):
        found = threshold.ght(image, kappa=1e30, omega=omega).threshold
        assert (image <= found).mean() == pytest.approx(omega, abs=0.01)


@pytest.mark.parametrize("classes", [3, 4])
def test_multi_otsu_equals_scikit_image(classes):
    image = sample("camera")
    result = threshold.multi_otsu(image, classes=classes)
    # reference: skimage.filters.threshold_multiotsu(image, classes=classes, nbins=256)
    np.testing.assert_allclose(
        result.thresholds, skimage.filters.threshold_multiotsu(image, classes, nbins=256), atol=1e-6
    )
    assert set(np.unique(result.labels)) == set(range(1, classes + 1))


def test_multi_otsu_needs_enough_levels():
    with pytest.raises(ValueError, match="2 distinct gray levels; 3 classes need"):
        threshold.multi_otsu(np.array([[0, 1], [0, 1]], np.float32), classes=3)


def test_window_statistics_equal_direct_computation():
    image = np.random.default_rng(2).random((40, 33)).astype(np.float32)
    mean, std = threshold.window_mean_std(image, 7)
    # reference: scipy.ndimage.uniform_filter(image, 7, mode="reflect") for the mean
    np.testing.assert_allclose(
        mean, ndi.uniform_filter(image.astype(np.float64), 7, mode="reflect"), atol=1e-12
    )
    window = image[10:17, 12:19].astype(np.float64)
    assert std[13, 15] == pytest.approx(window.std(), abs=1e-8)  # E[x²] - E[x]² in float64


def test_local_niblack_and_sauvola_match_scikit_image_inside_the_border():
    image = sample("page")
    inner = (slice(12, -12), slice(12, -12))
    niblack = threshold.local(image, window=25, k=-0.2, foreground="dark")
    # reference: image < skimage.filters.threshold_niblack(image, 25, k=0.2) (skimage's sign of k)
    expected = image < skimage.filters.threshold_niblack(image, 25, k=0.2)
    assert (niblack[inner] == expected[inner]).mean() > 0.999
    sauvola = threshold.local(image, window=25, k=0.2, method="sauvola", r=0.5)
    expected = image < skimage.filters.threshold_sauvola(image, 25, k=0.2, r=0.5)
    assert (sauvola[inner] == expected[inner]).mean() > 0.999


def test_local_threshold_follows_uneven_light():
    """Dark bars on a background ramping from 0.2 to 0.9: no global threshold works."""
    ramp = np.tile(np.linspace(0.2, 0.9, 200, dtype=np.float32), (100, 1))
    image = ramp.copy()
    truth = np.zeros_like(image, dtype=bool)
    for x0 in range(10, 190, 30):
        truth[40:60, x0 : x0 + 10] = True
    image[truth] -= 0.15
    local = threshold.local(image, window=31, k=0.2, method="sauvola", foreground="dark")
    glob = threshold.otsu(image, foreground="dark").mask
    assert (local == truth).mean() > 0.95
    assert (glob == truth).mean() < 0.8


def test_manual_band():
    image = np.array([[0.1, 0.4, 0.6, 0.9]], np.float32)
    np.testing.assert_array_equal(threshold.manual(image, low=0.5), [[False, False, True, True]])
    np.testing.assert_array_equal(
        threshold.manual(image, low=0.3, high=0.6), [[False, True, True, False]]
    )
    with pytest.raises(ValueError, match="high"):
        threshold.manual(image, low=0.6, high=0.3)


def test_a_colour_image_is_refused_before_running(registry):
    import graphvision as gv

    graph = gv.Graph("t")
    graph.output("m", graph.add("o", "threshold.otsu", image=graph.input("image", "Image"))["mask"])
    with pytest.raises(
        gv.PipelineError,
        match=r"'image' gives Image but 'o.image' "
        r"\(threshold.otsu\) takes GrayImage",
    ):
        gv.compile_graph(graph, registry)
