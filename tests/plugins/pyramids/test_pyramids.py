"""Pyramids on a zone plate, exact Laplacian reconstruction, NCC against scikit-image,
peaks and multi-scale matching against templates cut with a known place and scale."""

from __future__ import annotations

import numpy as np
import pytest
import skimage.color
import skimage.data
import skimage.feature

import graphvision as gv
from graphvision_plugins import pyramids

from ...conftest import PIPELINES


def aliased_energy(level: np.ndarray, size: int) -> float:
    """Mean squared deviation from mid-gray of a half-size zone plate level where the
    original frequency lies in [0.3, 0.45] cycles/pixel: above the half-size Nyquist limit
    (0.25), so the ideal reduced image is flat 0.5 there and anything else is aliasing."""
    centre = (level.shape[0] - 1) / 2
    y, x = np.mgrid[0 : level.shape[0], 0 : level.shape[1]] - centre
    frequency = 2 * np.hypot(x, y) / size  # r / N in the original's pixels
    band = (frequency >= 0.3) & (frequency <= 0.45)
    return float(((level[band] - 0.5) ** 2).mean())


def test_gaussian_pyramid_removes_what_naive_subsampling_aliases():
    plate = pyramids.zone_plate(size=256)
    smooth = pyramids.gaussian_pyramid(plate, levels=2).levels[1]
    naive = pyramids.naive_pyramid(plate, levels=2).levels[1]
    aliased_naive = aliased_energy(naive, 256)
    aliased_smooth = aliased_energy(smooth, 256)
    # a full-amplitude cosine has energy 0.125; naive keeps it all (measured 0.125),
    # σ = 1 attenuates f ≥ 0.3 to ≤ e^{-2π²·0.09} = 0.17 in amplitude (measured 0.0008)
    assert aliased_naive > 0.1
    assert aliased_smooth < 0.01 * aliased_naive


@pytest.mark.parametrize("shape", [(64, 64), (75, 50), (40, 33, 3)])
def test_laplacian_pyramid_reconstructs_exactly(shape):
    image = np.random.default_rng(0).random(shape).astype(np.float32)
    pyramid = pyramids.laplacian_pyramid(image, levels=4)
    assert pyramid.levels[0].shape == shape
    np.testing.assert_allclose(pyramids.reconstruct(pyramid), image, atol=1e-6)


def test_pyramid_levels_halve_and_keep_the_mean():
    camera = (skimage.data.camera() / 255).astype(np.float32)
    levels = pyramids.gaussian_pyramid(camera, levels=4).levels
    assert [level.shape for level in levels] == [(512, 512), (256, 256), (128, 128), (64, 64)]
    assert abs(levels[3].mean() - camera.mean()) < 0.01


@pytest.mark.parametrize("seed", range(3))
def test_ncc_equals_scikit_image(seed):
    rng = np.random.default_rng(seed)
    image = rng.random((50, 61)).astype(np.float32)
    image[10:20, 10:30] = 0.5  # a flat region: both give 0 there
    template = rng.random((7, 12)).astype(np.float32)
    # reference: skimage.feature.match_template(image, template) in float64
    expected = skimage.feature.match_template(image.astype(np.float64), template.astype(np.float64))
    np.testing.assert_allclose(pyramids.match_template(image, template), expected, atol=1e-5)


def test_correlation_kinds_by_definition():
    rng = np.random.default_rng(1)
    image = rng.random((12, 13)).astype(np.float32)
    template = rng.random((3, 4)).astype(np.float32)
    window = image[5:8, 6:10].astype(np.float64)
    plain = pyramids.match_template(image, template, method="correlation")
    zero_mean = pyramids.match_template(image, template, method="zero_mean")
    assert plain[5, 6] == pytest.approx((window * template).sum(), rel=1e-5)
    assert zero_mean[5, 6] == pytest.approx(
        (window * (template - template.mean())).sum(), rel=1e-4, abs=1e-6
    )


def test_peaks_find_every_placed_copy_with_sub_pixel_precision():
    camera = (skimage.data.camera()[::2, ::2] / 255).astype(np.float32)
    template = camera[100:130, 60:100].copy()
    response = pyramids.match_template(camera, template)
    found = pyramids.find_peaks(response, threshold=0.9, min_distance=5)
    assert len(found.points) == 1
    np.testing.assert_allclose(found.points[0], [60, 100], atol=0.05)
    assert found.scores[0] == pytest.approx(1.0, abs=1e-6)


@pytest.mark.parametrize("factor", [0.5, 0.8, 1.6])
def test_multiscale_matching_recovers_place_and_scale(factor):
    gray = skimage.color.rgb2gray(skimage.data.astronaut()[::2, ::2]).astype(np.float32)
    cut = pyramids.sample_template(gray, x=90, y=30, size=32, factor=factor)
    found = pyramids.match_multiscale(gray, cut.template, min_scale=0.5, max_scale=2.2, steps=13)
    errors = pyramids.match_error(found.location, found.scale, cut.location, cut.scale)
    assert errors.location_error < 1.5
    assert errors.scale_error < 0.05


def test_pipelines_pyramid_and_template():
    out = gv.run(gv.load_pipeline(PIPELINES / "pyramid.yaml")).outputs
    assert out["reconstruction_error"] < 1e-12
    size = 256
    naive = aliased_energy(out["plate_naive_levels"].levels[1], size)
    smooth = aliased_energy(out["plate_gaussian_levels"].levels[1], size)
    assert smooth < 0.01 * naive
    found = gv.run(gv.load_pipeline(PIPELINES / "template.yaml")).outputs
    assert found["location_error"] < 1.0 and found["scale_error"] < 0.02
    drawing = found["drawing"]
    # the patch was cut at x = 180..243, y = 60..123: the box's sides fall on its columns
    np.testing.assert_allclose(drawing[91, [180, 243]], [[0.1, 0.95, 0.1]] * 2, rtol=1e-6)


def test_bad_input_is_refused_naming_it():
    image = np.zeros((10, 10), np.float32)
    with pytest.raises(ValueError, match=r"template 12×3 is larger than the image 10×10"):
        pyramids.match_template(image, np.zeros((12, 3), np.float32))
    with pytest.raises(ValueError, match=r"min_scale \(2\) must be at most max_scale \(1\)"):
        pyramids.match_multiscale(image, image[:3, :3], min_scale=2.0, max_scale=1.0)
    with pytest.raises(ValueError, match="must be a Laplacian pyramid"):
        pyramids.reconstruct(pyramids.gaussian_pyramid(image))
    with pytest.raises(ValueError, match="index 7 is past the pyramid's 4 levels"):
        pyramids.pyramid_level(pyramids.gaussian_pyramid(image), index=7)
    with pytest.raises(ValueError, match=r"patch at x=5, y=0 of size 8 leaves the image"):
        pyramids.sample_template(image, x=5, size=8)
