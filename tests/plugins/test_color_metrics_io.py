"""Colour conversion, image metrics and image reading."""

from __future__ import annotations

import imageio.v3 as iio
import numpy as np
import pytest
import skimage.data
import skimage.metrics

from graphvision_plugins import color, io, metrics


def test_gray_is_the_channel_mean_or_bt601_luminance():
    rgb = np.array([[[0.3, 0.6, 0.9], [1.0, 0.0, 0.0]]], np.float32)
    np.testing.assert_allclose(color.to_gray(rgb), [[0.6, 1 / 3]], rtol=1e-6)
    np.testing.assert_allclose(
        color.to_gray(rgb, method="luminance"),
        [[0.299 * 0.3 + 0.587 * 0.6 + 0.114 * 0.9, 0.299]],
        rtol=1e-6,
    )
    gray = np.full((2, 2), 0.25, np.float32)
    assert color.to_gray(gray) is gray


def test_chromaticity_sums_to_one_and_ignores_intensity():
    rgb = np.random.default_rng(0).random((10, 10, 3)).astype(np.float32) * 0.5
    chroma = color.chromaticity(rgb)
    np.testing.assert_allclose(chroma.sum(axis=2), 1.0, rtol=1e-6)
    np.testing.assert_allclose(color.chromaticity(rgb * 2), chroma, rtol=1e-5)
    black = np.zeros((1, 1, 3), np.float32)
    np.testing.assert_allclose(color.chromaticity(black), 1 / 3)


def test_mse_and_psnr_against_scikit_image():
    a = np.random.default_rng(1).random((30, 30)).astype(np.float32)
    b = np.clip(a + 0.1, 0, 1).astype(np.float32)
    assert metrics.mse(np.zeros((2, 2), np.float32), np.full((2, 2), 0.1, np.float32)) == (
        pytest.approx(0.01)
    )
    # reference: skimage.metrics.peak_signal_noise_ratio(a, b, data_range=1.0)
    assert metrics.psnr(a, b) == pytest.approx(
        skimage.metrics.peak_signal_noise_ratio(a, b, data_range=1.0), rel=1e-6
    )
    assert metrics.psnr(a, a) == 100.0
    with pytest.raises(ValueError, match=r"a and b must have the same shape, got \(30, 30\) and"):
        metrics.mse(a, a[:10])


def test_samples_follow_the_dtype_policy():
    camera = io.read_sample("camera")
    assert camera.dtype == np.float32 and camera.shape == (512, 512)
    np.testing.assert_allclose(camera, skimage.data.camera() / 255.0, atol=1e-7)
    assert io.read_sample("astronaut").shape == (512, 512, 3)
    assert io.read_sample("horse").dtype == np.float32  # bool sample
    for name in io.SAMPLES:  # every advertised sample loads offline
        if name == "motorcycle_disparity":  # ground truth, not an image: NaN where unknown
            truth = io.sample_array(name)
            assert truth.dtype == np.float32 and truth.shape == (500, 741)
            assert np.isnan(truth).any() and np.nanmin(truth) > 0
            continue
        assert io.read_sample(name).ndim in (2, 3)


def test_reading_files(tmp_path):
    rgba = np.zeros((4, 5, 4), np.uint8)
    rgba[..., 0] = 255
    iio.imwrite(tmp_path / "a.png", rgba)
    image = io.read_file(str(tmp_path / "a.png"))
    assert image.shape == (4, 5, 3) and image[..., 0].min() == 1.0
    deep = np.arange(12, dtype=np.uint16).reshape(3, 4) * 5000
    iio.imwrite(tmp_path / "d.png", deep)
    np.testing.assert_allclose(io.read_file(str(tmp_path / "d.png")), deep / 65535, rtol=1e-6)
    with pytest.raises(FileNotFoundError, match="no such file"):
        io.read_file(str(tmp_path / "none.png"))
    np.save(tmp_path / "o.npy", np.array([object()]), allow_pickle=True)
    with pytest.raises(ValueError, match="not a plain numpy array file"):
        io.read_file(str(tmp_path / "o.npy"))
