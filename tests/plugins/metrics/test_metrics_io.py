"""Image metrics and image reading."""

from __future__ import annotations

import imageio.v3 as iio
import numpy as np
import pytest
import skimage.data
import skimage.metrics

from graphvision_plugins import io, metrics


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
