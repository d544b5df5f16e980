"""Formation family: optics formulas, defocus, vignetting, Bayer mosaics, against known truth."""

from __future__ import annotations

import numpy as np
import pytest

import graphvision as gv
from graphvision_plugins.formation import (
    circle_of_confusion,
    correct_vignetting,
    defocus,
    demosaic,
    depth_of_field,
    draw_vignetting,
    estimate_vignetting,
    field_of_view,
    focus_distance,
    mosaic,
    vignette,
)

from ...conftest import PIPELINES

PATTERNS = ["RGGB", "BGGR", "GRBG", "GBRG"]


def test_field_of_view_of_a_normal_lens():
    # 50 mm on a 36 mm wide sensor: 2·atan(0.36) = 39.6° (the "normal" lens of 35 mm film)
    assert field_of_view(sensor_size=36, focal_length=50) == pytest.approx(39.5978, abs=1e-4)
    assert field_of_view(sensor_size=36, focal_length=18) == pytest.approx(90.0, abs=1e-9)


def test_negative_sensor_size_is_refused():
    with pytest.raises(gv.ParameterError, match="sensor_size"):
        field_of_view(sensor_size=-36)


def test_thin_lens_focus_and_its_refusal_inside_the_focal_length():
    assert focus_distance(object_distance=100, focal_length=50) == pytest.approx(100.0)
    with pytest.raises(ValueError, match="not beyond the focal length"):
        focus_distance.__wrapped__(object_distance=40, focal_length=50)


def test_depth_of_field_limits_have_the_allowed_blur():
    f, n, c = 50.0, 2.8, 0.03
    dof = depth_of_field(focal_length=f, f_number=n, focus=3000, circle_of_confusion=c)
    assert dof.near < 3000 < dof.far
    # at both limits the blur circle is exactly the accepted one
    for z in (dof.near, dof.far):
        blur = (f / n) * f / (3000 - f) * abs(z - 3000) / z
        assert blur == pytest.approx(c, rel=1e-9)
    beyond = depth_of_field(focal_length=f, f_number=n, focus=dof.hyperfocal + 1)
    assert beyond.far == float("inf")
    assert beyond.near == pytest.approx(dof.hyperfocal / 2, rel=0.01)  # near limit → H/2


def test_defocus_keeps_the_focus_plane_sharp_and_blurs_by_the_circle_of_confusion():
    rng = np.random.default_rng(0)
    image = rng.uniform(0, 1, (40, 60)).astype(np.float32)
    depth = np.full((40, 60), 2000.0, np.float32)
    depth[:, 30:] = 4000.0  # the right half far behind the focus plane
    out = defocus(image, depth, focal_length=50, f_number=1.8, focus=2000, pixel_pitch=0.01)
    np.testing.assert_allclose(out[:, :20], image[:, :20], atol=1e-6)
    # radius = ½ (50/1.8)·50/1950·2000/4000 / 0.01 = 17.8 px: the noise averages out
    assert out[10:30, 48:52].std() < 0.1 * image.std()


def test_vignetting_is_estimated_from_a_flat_field_and_corrected():
    rng = np.random.default_rng(1)
    flat = np.full((60, 80), 0.8, np.float32)
    dark = vignette(flat, model="polynomial", a1=-0.4, a2=0.1, a3=-0.05)
    noisy = np.clip(dark + rng.normal(0, 0.005, dark.shape), 0, 1).astype(np.float32)
    coefficients = estimate_vignetting(noisy)
    np.testing.assert_allclose(coefficients, [-0.4, 0.1, -0.05], atol=0.03)
    restored = correct_vignetting(dark, coefficients)
    assert np.abs(restored - flat).max() < 0.01
    drawing = draw_vignetting(noisy, coefficients)
    assert (
        drawing.shape == (60, 80, 3) and (drawing[30, 40] == noisy[30, 40]).all()
    )  # centre: V = 1
    assert (drawing[..., 2] == 0).sum() > 50  # the orange iso-lines
    natural = vignette(flat, model="cos4", focal=40.0)
    corner = (1 + (np.hypot(39.5, 29.5) / 40.0) ** 2) ** -2  # cos⁴ θ at the corner
    assert natural[0, 0] == pytest.approx(0.8 * corner, rel=1e-5)


@pytest.mark.parametrize("pattern", PATTERNS)
def test_mosaic_samples_the_pattern_colour_at_each_pixel(pattern):
    image = np.zeros((4, 4, 3), np.float32)
    image[..., 0], image[..., 1], image[..., 2] = 0.2, 0.5, 0.9
    raw = mosaic(image, pattern=pattern)
    value = {"R": 0.2, "G": 0.5, "B": 0.9}
    assert [raw[0, 0], raw[0, 1], raw[1, 0], raw[1, 1]] == [
        pytest.approx(value[letter]) for letter in pattern
    ]


@pytest.mark.parametrize("pattern", PATTERNS)
@pytest.mark.parametrize("method", ["bilinear", "malvar"])
def test_demosaic_is_exact_on_a_linear_colour_ramp(pattern, method):
    y, x = np.mgrid[0:24, 0:32] / 64.0
    image = np.stack([0.1 + x, 0.2 + 0.5 * y, 0.3 + 0.3 * x + 0.2 * y], -1).astype(np.float32)
    out = demosaic(mosaic(image, pattern=pattern), pattern=pattern, method=method)
    inner = (slice(2, -2), slice(2, -2))  # both interpolators are exact on linear images
    np.testing.assert_allclose(out[inner], image[inner], atol=1e-5)


def test_demosaic_refuses_a_tiny_mosaic():
    with pytest.raises(ValueError, match="at least 5×5"):
        demosaic.__wrapped__(np.zeros((4, 8), np.float32))


@pytest.mark.parametrize("sample", ["astronaut", "cat"])
def test_gradient_corrected_beats_bilinear_by_2_db(sample):
    result = gv.run(
        gv.load_pipeline(PIPELINES / "demosaic.yaml"),
        inputs={"image": f"sample:{sample}"},
        outputs=["psnr_bilinear", "psnr_gradient_corrected"],
    )
    out = result.outputs
    assert out["psnr_gradient_corrected"] >= out["psnr_bilinear"] + 2.0
    assert out["psnr_bilinear"] > 25


def test_defocus_at_one_depth_is_the_disc_of_its_circle_of_confusion():
    from scipy import ndimage

    from graphvision_plugins.formation._optics import _disc

    image = np.random.default_rng(2).uniform(0, 1, (50, 70)).astype(np.float32)
    depth = np.full(image.shape, 4000.0, np.float32)
    out = defocus(image, depth, focal_length=50, f_number=1.8, focus=2000, pixel_pitch=0.02)
    radius = 0.5 * float(circle_of_confusion(np.array(4000.0), 50, 1.8, 2000)) / 0.02
    assert radius == pytest.approx(0.5 * (50 / 1.8) * 50 / 1950 * 0.5 / 0.02)  # 8.9 px
    # the direct convolution with the same anti-aliased disc, borders mirrored alike
    expected = ndimage.convolve(image.astype(np.float64), _disc(radius), mode="reflect")
    np.testing.assert_allclose(out, expected, atol=1e-5)


def test_defocus_pipeline_is_sharpest_at_the_focus_distance():
    out = gv.run(gv.load_pipeline(PIPELINES / "defocus.yaml")).outputs
    assert out["near_limit"] < 2000 < out["far_limit"]
    gradient = np.abs(np.diff(out["defocused"].mean(axis=2), axis=1))
    band = np.abs(out["depth"][:, 0] - 2000)  # distance of each row from the focus plane
    sharp = gradient[band < 150].mean()
    assert sharp > 1.8 * gradient[band > 1500].mean()
