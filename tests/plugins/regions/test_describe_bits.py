"""regions.describe's one-pass kernel against the NumPy code it replaced, to the bit.

The reference below is the former implementation (eight ``np.bincount`` passes with
float64 weights, per-pixel perimeter weights from whole-image boolean passes, boxes
from ``scipy.ndimage.find_objects``), kept here only to check that the kernel's sums
add the same float64 terms in the same order.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.ndimage as ndi
import skimage.data
import skimage.filters

from graphvision.nodes.marks import unchecked
from graphvision_plugins import regions

SQRT2 = float(np.sqrt(2.0))
# the table of the former code, written out again (not imported from the kernel's module)
REFERENCE_WEIGHTS = np.zeros(50)
REFERENCE_WEIGHTS[[5, 7, 15, 17, 25, 27]] = 1.0
REFERENCE_WEIGHTS[[21, 33]] = SQRT2
REFERENCE_WEIGHTS[[13, 23]] = (1.0 + SQRT2) / 2.0


def reference_perimeter_weights(labels):
    """The former per-pixel weights: Benkrid & Crookes codes by whole-image passes."""
    padded = np.pad(labels, 1)
    centre = padded[1:-1, 1:-1]
    inside = centre > 0
    boundary = np.zeros_like(padded, dtype=bool)
    interior = inside.copy()
    for dy, dx in ((-1, 0), (1, 0), (0, -1), (0, 1)):
        interior &= (
            padded[1 + dy : padded.shape[0] - 1 + dy, 1 + dx : padded.shape[1] - 1 + dx] == centre
        )
    boundary[1:-1, 1:-1] = inside & ~interior
    code = boundary[1:-1, 1:-1].astype(np.int64)
    rows, cols = labels.shape
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            if dy == dx == 0:
                continue
            same = boundary[1 + dy : rows + 1 + dy, 1 + dx : cols + 1 + dx] & (
                padded[1 + dy : rows + 1 + dy, 1 + dx : cols + 1 + dx] == centre
            )
            code += same * (10 if dy and dx else 2)
    code[~boundary[1:-1, 1:-1]] = 0
    return REFERENCE_WEIGHTS[np.minimum(code, REFERENCE_WEIGHTS.size - 1)]


def reference_sums(labels, image):
    """The former per-region sums: (present labels, area, named float64 sums, boxes)."""
    size = int(labels.max()) + 1
    flat = labels.ravel()
    ys, xs = np.indices(labels.shape, dtype=np.float64)

    def total(weights=None):
        return np.bincount(flat, weights=weights, minlength=size)

    count = total()
    present = np.flatnonzero(count)
    present = present[present > 0]
    sums = {
        "x": total(xs.ravel()),
        "y": total(ys.ravel()),
        "xx": total((xs * xs).ravel()),
        "yy": total((ys * ys).ravel()),
        "xy": total((xs * ys).ravel()),
        "perimeter": total(reference_perimeter_weights(labels).ravel()),
    }
    if image is not None:
        sums["intensity"] = total(image.ravel().astype(np.float64))
    boxes = ndi.find_objects(labels)
    box = np.array(
        [
            [b[1].start, b[0].start, b[1].stop - 1, b[0].stop - 1]
            for b in (boxes[i - 1] for i in present)
        ],
        dtype=np.int64,
    ).reshape(-1, 4)
    return present, count[present], {k: v[present] for k, v in sums.items()}, box


def reference_describe(labels, image=None):
    """The former table, column for column, from the former sums."""
    present, area, total, box = reference_sums(labels, image)
    cx, cy = total["x"] / area, total["y"] / area
    mu20 = total["xx"] / area - cx * cx
    mu02 = total["yy"] / area - cy * cy
    mu11 = total["xy"] / area - cx * cy
    half_trace, spread = (mu20 + mu02) / 2, np.sqrt(((mu20 - mu02) / 2) ** 2 + mu11**2)
    major_var, minor_var = half_trace + spread, np.maximum(half_trace - spread, 0.0)
    perimeter = total["perimeter"]
    box_area = (box[:, 2] - box[:, 0] + 1) * (box[:, 3] - box[:, 1] + 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        eccentricity = np.where(major_var > 0, np.sqrt(1 - minor_var / major_var), 0.0)
        circularity = np.where(perimeter > 0, 4 * np.pi * area / perimeter**2, 0.0)
        compactness = np.where(area > 0, perimeter**2 / area, 0.0)
    table = {
        "label": present.astype(np.int32),
        "area": area.astype(np.int64),
        "perimeter": perimeter,
        "compactness": compactness,
        "circularity": circularity,
        "centroid_x": cx,
        "centroid_y": cy,
        "x_min": box[:, 0],
        "y_min": box[:, 1],
        "x_max": box[:, 2],
        "y_max": box[:, 3],
        "extent": area / box_area,
        "orientation": 0.5 * np.arctan2(2 * mu11, mu20 - mu02),
        "major_axis": 4 * np.sqrt(major_var),
        "minor_axis": 4 * np.sqrt(minor_var),
        "eccentricity": eccentricity,
    }
    if image is not None:
        table["mean_intensity"] = total["intensity"] / area
    return table


def assert_same_bits(labels, image=None):
    """Every column of describe's table equals the former code's: names, dtypes, bytes."""
    expected = reference_describe(labels, image)
    table = unchecked(regions.describe)(labels, image)
    assert list(table) == list(expected)
    for name, column in expected.items():
        assert table[name].dtype == column.dtype, name
        assert table[name].shape == column.shape, name
        assert table[name].tobytes() == column.tobytes(), name


def coins_labels():
    """scikit-image's coins thresholded (Otsu), filled and labelled (8-connectivity)."""
    gray = skimage.data.coins().astype(np.float32) / 255
    mask = ndi.binary_fill_holes(gray > skimage.filters.threshold_otsu(gray))
    return regions.label(mask, connectivity=8), gray


def blocks(rng, shape, values, block):
    """Piecewise-constant labels: random labels from ``values`` on ``block``² squares."""
    rows, cols = -(-shape[0] // block), -(-shape[1] // block)
    coarse = rng.choice(values, size=(rows, cols))
    return np.kron(coarse, np.ones((block, block), coarse.dtype))[: shape[0], : shape[1]]


@pytest.mark.parametrize("with_image", [False, True])
def test_coins_labelled_to_the_bit(with_image):
    labels, gray = coins_labels()
    assert labels.max() > 20  # the coins and bits of the background
    assert_same_bits(labels, gray if with_image else None)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("dtype", [np.int32, np.int64])
def test_random_labels_to_the_bit(seed, dtype):
    """Touching regions of every size (one pixel up), labels absent and with gaps, regions
    on every border of the image, with and without an image."""
    rng = np.random.default_rng(seed)
    shape = (int(rng.integers(30, 90)), int(rng.integers(30, 90)))
    image = rng.random(shape).astype(np.float32)
    gaps = np.array([0, 0, 0, 3, 7, 8, 40, 41, 300], dtype)  # 1, 2, 4.. 39, 42.. absent
    cases = [
        rng.integers(0, 400, shape).astype(dtype),  # mostly one-pixel regions, touching
        rng.choice(gaps, size=shape),
        blocks(rng, shape, np.arange(60, dtype=dtype), 3),  # squares, touching, many labels
        blocks(rng, shape, gaps, 5),
        ndi.label(ndi.gaussian_filter(rng.random(shape), 2) > 0.5)[0].astype(dtype) * 3,
        np.full(shape, 5, dtype),  # one region covering the image
    ]
    for labels in cases:
        assert labels.dtype == dtype
        assert_same_bits(labels)
        assert_same_bits(labels, image)


@pytest.mark.parametrize("shape", [(1, 1), (1, 37), (37, 1), (2, 2), (1, 200), (200, 1)])
def test_thin_images_to_the_bit(shape):
    rng = np.random.default_rng(sum(shape))
    image = rng.random(shape).astype(np.float32)
    for labels in (
        rng.integers(0, 4, shape).astype(np.int32),
        np.ones(shape, np.int32),
        np.full(shape, 9, np.int32),
    ):
        assert_same_bits(labels)
        assert_same_bits(labels, image)


def test_an_all_zero_image_has_no_rows():
    labels = np.zeros((7, 9), np.int32)
    assert_same_bits(labels)
    assert_same_bits(labels, np.full(labels.shape, 0.5, np.float32))
    table = regions.describe(labels, np.full(labels.shape, 0.5, np.float32))
    assert len(table) == 17 and all(len(column) == 0 for column in table.values())


def test_large_coordinates_to_the_bit():
    """A wide image: x² and the sums of thousands of pixels far from the origin."""
    labels = np.zeros((3, 5000), np.int32)
    labels[:, 4000:] = 1
    labels[1, 4990:] = 2
    assert_same_bits(labels)


def test_values_by_hand():
    """A 3×3 square and a one-pixel region: sums, perimeter and box written out."""
    labels = np.zeros((5, 6), np.int32)
    labels[1:4, 1:4] = 2
    labels[0, 5] = 4
    table = regions.describe(labels)
    assert table["label"].tolist() == [2, 4]
    assert table["area"].tolist() == [9, 1]
    # the square's 8 boundary pixels: 4 corners (code 1 + 2·2 = 5, weight 1) and 4 edge
    # middles (1 + 2·2 + 10·2 = 25, weight 1); the lone pixel: code 1, weight 0
    assert table["perimeter"].tolist() == [8.0, 0.0]
    assert table["centroid_x"].tolist() == [2.0, 5.0]
    assert table["centroid_y"].tolist() == [2.0, 0.0]
    assert [table[k].tolist() for k in ("x_min", "y_min", "x_max", "y_max")] == [
        [1, 5],
        [1, 0],
        [3, 5],
        [3, 0],
    ]


def test_views_to_the_bit():
    """Labels and image that are not C-contiguous (transposed, strided) read in raster order."""
    labels, gray = coins_labels()
    assert_same_bits(labels.T, gray.T)
    assert_same_bits(labels[::2, ::3], gray[::2, ::3])


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("with_zero", [True, False])
def test_labels_larger_than_the_image_to_the_bit(seed, with_zero):
    """Label values past the pixel count (the kernel then works on their ranks): the same
    bits as the former code, background present or not, touching regions, one-pixel ones."""
    rng = np.random.default_rng(seed)
    shape = (int(rng.integers(20, 50)), int(rng.integers(20, 50)))
    sparse = np.array([0, 5, 70_000, 70_001, 99_999], np.int64)[0 if with_zero else 1 :]
    labels = blocks(rng, shape, sparse, int(rng.integers(1, 6)))
    assert labels.max() >= labels.size  # the ranks' path
    assert_same_bits(labels, rng.random(shape).astype(np.float32))


def test_a_label_near_the_largest_int32_costs_memory_by_pixels_not_by_value():
    """One pixel labelled 2³¹ − 1 on 50×50 (the former code's bincounts, and the kernel
    before its ranks, needed tables of 2³¹ entries: tens of GB): the table of the same
    image labelled 1, but for the label."""
    labels = np.zeros((50, 50), np.int32)
    labels[10:12, 20:23] = 2**31 - 1
    table = unchecked(regions.describe)(labels)
    small = unchecked(regions.describe)(np.minimum(labels, 1))
    assert table["label"].tolist() == [2**31 - 1]
    for name in set(small) - {"label"}:
        assert table[name].tobytes() == small[name].tobytes(), name
