"""Filters against hand-computed values, identities, and scipy/scikit-image references."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.ndimage as ndi

from graphvision_plugins import filters, synthetic

ROW = (np.arange(1, 7, dtype=np.float32) / 10)[None, :]  # [[.1 .2 .3 .4 .5 .6]]
PICK_LEFT_2 = np.array([[1.0, 0, 0, 0, 0]])  # correlation: out[i] = in[i - 2]


@pytest.mark.parametrize(
    ("boundary", "expected"),
    [
        ("mirror", [0.2, 0.1, 0.1, 0.2, 0.3, 0.4]),  # b a | a b c ...
        ("replicate", [0.1, 0.1, 0.1, 0.2, 0.3, 0.4]),  # a a | a b c ...
        ("wrap", [0.5, 0.6, 0.1, 0.2, 0.3, 0.4]),  # e f | a b c ...
        ("zero", [0.0, 0.0, 0.1, 0.2, 0.3, 0.4]),  # 0 0 | a b c ...
        ("crop", [0.1, 0.2]),  # only where the window fits
    ],
)
def test_boundary_conditions_by_hand(boundary, expected):
    out = filters.correlate(ROW, PICK_LEFT_2, boundary=boundary)
    np.testing.assert_allclose(out[0], expected, atol=1e-7)
    assert out.dtype == np.float32


def test_convolution_flips_the_kernel():
    impulse = np.zeros((7, 7), np.float32)
    impulse[3, 3] = 1.0
    kernel = np.arange(9, dtype=np.float64).reshape(3, 3)
    np.testing.assert_allclose(filters.convolve(impulse, kernel)[2:5, 2:5], kernel)
    np.testing.assert_allclose(filters.correlate(impulse, kernel)[2:5, 2:5], kernel[::-1, ::-1])


def test_convolution_is_commutative_and_associative():
    rng = np.random.default_rng(0)
    f, g = rng.random((5, 5)), rng.random((3, 3))
    image = np.zeros((15, 15), np.float32)
    image[4:9, 4:9] = f
    both = filters.convolve(filters.convolve(image, g, boundary="zero"), g, boundary="zero")
    g_g = filters.convolve(np.pad(g, 2).astype(np.float32), g, boundary="zero").astype(np.float64)
    once = filters.convolve(image, g_g, boundary="zero")
    np.testing.assert_allclose(both, once, atol=1e-5)


def test_gaussian_kernel_half_size_is_three_sigma():
    for sigma, side in [(0.5, 5), (1.0, 7), (1.2, 9), (2.0, 13)]:
        kernel = filters.gaussian_kernel(sigma=sigma)
        assert kernel.shape == (side, side)
        assert kernel.sum() == pytest.approx(1.0)
        h = side // 2
        # ratio of centre to edge-of-axis weight is exp(h^2 / 2 sigma^2)
        assert kernel[h, h] / kernel[h, 0] == pytest.approx(np.exp(h * h / (2 * sigma**2)))
    assert filters.gaussian_kernel(sigma=1.0, half_size=1).shape == (3, 3)


@pytest.mark.parametrize("sigma", [1.0, 2.0])
@pytest.mark.parametrize("shape", [(40, 50), (30, 20, 3)])
def test_separable_gaussian_matches_2d_correlation_and_scipy(sigma, shape):
    image = np.random.default_rng(1).random(shape).astype(np.float32)
    fast = filters.gaussian(image, sigma=sigma)
    direct = filters.correlate(image, filters.gaussian_kernel(sigma=sigma))
    np.testing.assert_allclose(fast, direct, atol=2e-6)
    # reference: scipy.ndimage.gaussian_filter(image, sigma, mode="reflect", truncate=3.0),
    # whose radius int(3 sigma + 0.5) equals ceil(3 sigma) for these sigmas
    axes_sigma = (sigma, sigma, 0) if len(shape) == 3 else sigma
    reference = ndi.gaussian_filter(
        image.astype(np.float64), axes_sigma, mode="reflect", truncate=3.0
    )
    np.testing.assert_allclose(fast, reference, atol=2e-6)


def test_gaussian_crop_shrinks_by_the_kernel():
    image = np.random.default_rng(2).random((30, 30)).astype(np.float32)
    cropped = filters.gaussian(image, sigma=1.0, boundary="crop")
    assert cropped.shape == (24, 24)
    np.testing.assert_allclose(cropped, filters.gaussian(image, sigma=1.0)[3:-3, 3:-3], atol=1e-6)
    with pytest.raises(ValueError, match=r"filter window 7×7 is larger than the image 5×5"):
        filters.gaussian(image[:5, :5], sigma=1.0, boundary="crop")


def test_box_filter_is_the_window_mean():
    image = np.random.default_rng(3).random((20, 20)).astype(np.float32)
    out = filters.box(image, size=5, boundary="replicate")
    assert out[10, 10] == pytest.approx(image[8:13, 8:13].mean(), abs=1e-6)
    np.testing.assert_allclose(
        out, ndi.uniform_filter(image.astype(np.float64), 5, mode="nearest"), atol=1e-6
    )


def test_sharpen_default_is_the_course_kernel():
    image = np.random.default_rng(4).random((25, 25)).astype(np.float32) * 0.5 + 0.25
    kernel = -np.full((3, 3), 1 / 9)
    kernel[1, 1] += 2.0
    expected = np.clip(filters.correlate(image, kernel), 0, 1)
    np.testing.assert_allclose(filters.sharpen(image), expected, atol=1e-6)
    np.testing.assert_array_equal(filters.sharpen(image, amount=0.0), image)


MEDIAN_MODES = [
    ("mirror", "reflect"),
    ("replicate", "nearest"),
    ("wrap", "wrap"),
    ("zero", "constant"),
]


@pytest.mark.parametrize("size", [1, 3, 5, 7, 9, 15])
@pytest.mark.parametrize(("boundary", "mode"), MEDIAN_MODES)
def test_median_matches_scipy(size, boundary, mode):
    image = np.random.default_rng(size).random((37, 41)).astype(np.float32)
    # reference: scipy.ndimage.median_filter(image, size, mode=mode)
    np.testing.assert_array_equal(
        filters.median(image, size=size, boundary=boundary),
        ndi.median_filter(image, size=size, mode=mode),
    )


@pytest.mark.parametrize("size", [3, 5, 7])
@pytest.mark.parametrize(("boundary", "mode"), MEDIAN_MODES)
@pytest.mark.parametrize(
    "shape", [(1, 9), (2, 2), (5, 1), (13, 600)], ids=["one-row", "tiny", "one-column", "wide"]
)
def test_median_matches_scipy_on_odd_shapes_and_ties(size, boundary, mode, shape):
    """Shapes smaller than the window, wider than one column block; 8-bit levels tie often."""
    levels = np.random.default_rng(sum(shape) + size).integers(0, 6, shape)
    image = (levels / 255).astype(np.float32)
    # reference: scipy.ndimage.median_filter(image, size, mode=mode)
    np.testing.assert_array_equal(
        filters.median(image, size=size, boundary=boundary),
        ndi.median_filter(image, size=size, mode=mode),
    )


@pytest.mark.parametrize("size", [3, 5, 7])
def test_median_of_a_constant_image_is_the_image(size):
    image = np.full((20, 30), 0.3, np.float32)
    for boundary in ("mirror", "replicate", "wrap", "crop"):
        out = filters.median(image, size=size, boundary=boundary)
        assert np.all(out == np.float32(0.3))


@pytest.mark.parametrize("size", [3, 5, 7])
def test_median_crop_is_the_valid_part(size):
    image = np.random.default_rng(size).random((23, 31)).astype(np.float32)
    half = size // 2
    np.testing.assert_array_equal(
        filters.median(image, size=size, boundary="crop"),
        filters.median(image, size=size)[half:-half, half:-half],
    )


def test_median_colour_and_crop():
    image = np.random.default_rng(9).random((20, 22, 3)).astype(np.float32)
    out = filters.median(image, size=3)
    for c in range(3):
        np.testing.assert_array_equal(
            out[..., c], ndi.median_filter(image[..., c], 3, mode="reflect")
        )
    np.testing.assert_array_equal(filters.median(image, size=3, boundary="crop"), out[1:-1, 1:-1])


def test_median_removes_salt_and_pepper_that_a_gaussian_smears():
    clean = np.full((64, 64), 0.5, np.float32)
    noisy = synthetic.salt_and_pepper(clean, amount=0.05, seed=0)
    assert (
        np.abs(filters.median(noisy, size=3) - clean).max() < 1e-6
    )  # 5% never fills a window half
    assert np.abs(filters.gaussian(noisy, sigma=1.0) - clean).max() > 0.05


def test_to_image():
    response = np.array([[-1.0, 0.5, 2.0]], np.float32)
    np.testing.assert_array_equal(filters.to_image(response), [[0.0, 0.5, 1.0]])
    np.testing.assert_allclose(filters.to_image(response, method="minmax"), [[0.0, 0.5, 1.0]])
    assert filters.to_image(np.ones((2, 2), np.float32), method="minmax").max() == 0.0


RANK_ONE_KERNELS = {
    "gaussian": filters.gaussian_kernel(sigma=1.2),
    "box": filters.box_kernel(size=5),
    "sobel": np.outer([1.0, 2.0, 1.0], [-1.0, 0.0, 1.0]) / 8,
    "row": np.array([[0.1, -0.4, 0.2, 0.3, 0.5]]),
    "column": np.array([[0.2], [0.5], [0.3]]),
}


@pytest.mark.parametrize("name", list(RANK_ONE_KERNELS))
@pytest.mark.parametrize(
    ("boundary", "mode"),
    [("mirror", "reflect"), ("replicate", "nearest"), ("wrap", "grid-wrap"), ("zero", "constant")],
)
def test_rank_one_kernels_through_the_separable_core_equal_scipy(name, boundary, mode):
    kernel = RANK_ONE_KERNELS[name]
    image = np.random.default_rng(len(name)).random((29, 34)).astype(np.float32)
    # reference: scipy.ndimage.correlate / convolve(image, kernel, mode=mode)
    np.testing.assert_allclose(
        filters.correlate(image, kernel, boundary=boundary),
        ndi.correlate(image, kernel, mode=mode),
        atol=1e-6,
    )
    np.testing.assert_allclose(
        filters.convolve(image, kernel, boundary=boundary),
        ndi.convolve(image, kernel, mode=mode),
        atol=1e-6,
    )


def test_rank_one_factoring_keeps_crop_colour_and_refuses_other_kernels():
    image = np.random.default_rng(3).random((21, 26, 3)).astype(np.float32)
    kernel = RANK_ONE_KERNELS["gaussian"]
    full = filters.correlate(image, kernel)
    for c in range(3):
        # reference: scipy.ndimage.correlate(channel, kernel, mode="reflect")
        np.testing.assert_allclose(full[..., c], ndi.correlate(image[..., c], kernel), atol=1e-6)
    half = kernel.shape[0] // 2
    np.testing.assert_array_equal(
        filters.correlate(image, kernel, boundary="crop"), full[half:-half, half:-half]
    )
    rank_two = np.eye(3)  # not separable: scipy.ndimage.correlate does it
    gray = image[..., 0]
    np.testing.assert_allclose(
        filters.correlate(gray, rank_two), ndi.correlate(gray, rank_two), atol=1e-6
    )


@pytest.mark.parametrize("shape", [(3, 3), (4, 5), (5, 2), (7, 7), (1, 4)])
@pytest.mark.parametrize(
    ("boundary", "mode"),
    [("mirror", "reflect"), ("replicate", "nearest"), ("wrap", "grid-wrap"), ("zero", "constant")],
)
def test_any_kernel_correlation_equals_scipy(shape, boundary, mode):
    """Kernels of rank above one (and even sides) take the compiled 2-D path, which
    accumulates in float32: within its documented bound of scipy's float64 sums."""
    rng = np.random.default_rng(sum(shape))
    kernel = rng.normal(size=shape)
    image = rng.random((23, 31)).astype(np.float32)
    bound = _float32_bound(kernel)
    # reference: scipy.ndimage.correlate(image, kernel, mode=mode) (accumulates in double)
    np.testing.assert_allclose(
        filters.correlate(image, kernel, boundary=boundary),
        ndi.correlate(image, kernel, mode=mode),
        atol=bound,
    )
    # convolve is correlation with the flipped kernel, centred again at (kh // 2, kw // 2)
    np.testing.assert_allclose(
        filters.convolve(image, kernel, boundary=boundary),
        ndi.correlate(image, kernel[::-1, ::-1], mode=mode),
        atol=bound,
    )


def _float32_bound(kernel: np.ndarray) -> float:
    """The float32 kernel's documented error bound on a [0, 1] image:
    ``(kh·⌈kw/5⌉ + 5) · 2⁻²⁴ · Σ|kernel|`` (one rounding per addition, relative to a
    running sum bounded by Σ|kernel|)."""
    kh, kw = kernel.shape
    return (kh * -(-kw // 5) + 5) * 2.0**-24 * float(np.abs(kernel).sum())


def _float64_taps(image: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """The replaced kernel's sums, written out: every tap's shifted mirror-padded image
    added in float64, rounded once to float32."""
    kh, kw = kernel.shape
    padded = np.pad(
        image.astype(np.float64),
        ((kh // 2, kh - 1 - kh // 2), (kw // 2, kw - 1 - kw // 2)),
        mode="symmetric",
    )
    total = np.zeros(image.shape)
    for i in range(kh):
        for j in range(kw):
            total += kernel[i, j] * padded[i : i + image.shape[0], j : j + image.shape[1]]
    return total.astype(np.float32)


def test_float32_accumulation_stays_within_its_bound_of_the_float64_kernel():
    """The bench's 5×5 kernel (uniform weights, total 13) on a 64² image: the float32
    sums differ from the replaced float64 ones by a few float32 steps of the outputs
    (up to 13), inside the documented bound, and on 8-bit levels too."""
    rng = np.random.default_rng(3)
    kernel = rng.random((5, 5))
    for image in (rng.random((64, 64)), np.round(rng.random((64, 64)) * 255) / 255):
        image = image.astype(np.float32)
        difference = np.abs(filters.correlate(image, kernel) - _float64_taps(image, kernel))
        assert 0 < difference.max() <= _float32_bound(kernel)


def test_any_kernel_on_colour_and_crop():
    rng = np.random.default_rng(8)
    kernel = rng.normal(size=(4, 3))
    image = rng.random((17, 19, 3)).astype(np.float32)
    out = filters.correlate(image, kernel)
    for c in range(3):
        # reference: scipy.ndimage.correlate(channel, kernel, mode="reflect")
        np.testing.assert_allclose(
            out[..., c], ndi.correlate(image[..., c], kernel), atol=_float32_bound(kernel)
        )
    np.testing.assert_array_equal(
        filters.correlate(image, kernel, boundary="crop"), out[2:-1, 1:-1]
    )
