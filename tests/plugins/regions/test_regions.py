"""Labelling and region descriptors against scipy.ndimage, scikit-image and drawn shapes."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.ndimage as ndi
import skimage.measure

import graphvision as gv
from graphvision_plugins import regions


def blobs(seed, shape=(80, 90)):
    return ndi.gaussian_filter(np.random.default_rng(seed).random(shape), 2) > 0.5


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize(("connectivity", "structure"), [(4, None), (8, np.ones((3, 3)))])
def test_labels_equal_scipy(seed, connectivity, structure):
    mask = blobs(seed)
    # reference: scipy.ndimage.label(mask, structure) — same raster-order numbering
    expected, count = ndi.label(mask, structure=structure)
    labels = regions.label(mask, connectivity=connectivity)
    np.testing.assert_array_equal(labels, expected)
    assert labels.dtype == np.int32 and labels.max() == count


@pytest.mark.parametrize("density", [0.2, 0.45, 0.6, 0.8])
@pytest.mark.parametrize(("connectivity", "structure"), [(4, None), (8, np.ones((3, 3)))])
def test_labels_equal_scipy_on_noisy_masks(density, connectivity, structure):
    """Uniform noise: many small regions and long chains of equivalences (the union paths)."""
    mask = np.random.default_rng(int(density * 100)).random((61, 97)) < density
    # reference: scipy.ndimage.label(mask, structure) — same raster-order numbering
    expected, count = ndi.label(mask, structure=structure)
    labels = regions.label(mask, connectivity=connectivity)
    np.testing.assert_array_equal(labels, expected)
    assert labels.max() == count


def test_connectivity_by_hand():
    mask = np.array([[1, 0, 0, 1], [0, 1, 0, 1], [0, 0, 0, 1]], bool)
    assert regions.label(mask, connectivity=8).tolist() == [
        [1, 0, 0, 2],
        [0, 1, 0, 2],
        [0, 0, 0, 2],
    ]
    assert regions.label(mask, connectivity=4).tolist() == [
        [1, 0, 0, 2],
        [0, 3, 0, 2],
        [0, 0, 0, 2],
    ]


def test_equivalences_merge_a_u_and_a_spiral():
    u_shape = np.array([[1, 0, 1, 0, 1], [1, 0, 1, 0, 1], [1, 1, 1, 1, 1]], bool)
    assert set(np.unique(regions.label(u_shape, connectivity=4))) == {0, 1}
    stairs = np.eye(6, dtype=bool) | np.eye(6, k=1, dtype=bool)[::-1]
    assert regions.label(stairs, connectivity=8).max() == 1
    # reference: scipy.ndimage.label(stairs) (4-connectivity)
    assert regions.label(stairs, connectivity=4).max() == ndi.label(stairs)[1]


def test_empty_and_full_masks():
    assert not regions.label(np.zeros((4, 4), bool)).any()
    assert (regions.label(np.ones((4, 4), bool)) == 1).all()
    table = regions.describe(np.zeros((4, 4), np.int32))
    assert all(len(column) == 0 for column in table.values())


def test_label_overflow_is_named():
    regions.check_label_count(regions.MAX_LABEL)
    with pytest.raises(OverflowError, match=r"2147483648 regions do not fit in int32"):
        regions.check_label_count(regions.MAX_LABEL + 1)
    with pytest.raises(gv.PortValueError, match="expected LabelImage"):
        gv.LabelImagePort.validate(np.zeros((3, 3), np.int64))
    with pytest.raises(gv.PortValueError, match="labels >= 0"):
        gv.LabelImagePort.validate(np.full((3, 3), -1, np.int32))


def test_relabel():
    labels = np.array([[0, 5, 5], [9, 0, 2]], np.int32)
    assert regions.relabel(labels).tolist() == [[0, 2, 2], [3, 0, 1]]


def test_descriptors_equal_scikit_image():
    labels = regions.label(blobs(3, (120, 130)), connectivity=8)
    image = np.random.default_rng(0).random(labels.shape).astype(np.float32)
    table = regions.describe(labels, image)
    # reference: skimage.measure.regionprops(labels, image)
    props = skimage.measure.regionprops(labels, intensity_image=image)
    assert table["label"].tolist() == [p.label for p in props]
    for i, p in enumerate(props):
        assert table["area"][i] == p.area
        assert (table["centroid_y"][i], table["centroid_x"][i]) == pytest.approx(p.centroid)
        y0, x0, y1, x1 = p.bbox
        assert [table[k][i] for k in ("y_min", "x_min", "y_max", "x_max")] == [
            y0,
            x0,
            y1 - 1,
            x1 - 1,
        ]
        assert table["mean_intensity"][i] == pytest.approx(p.intensity_mean)
        if p.area > 5:
            assert table["major_axis"][i] == pytest.approx(p.axis_major_length, rel=1e-6)
            assert table["minor_axis"][i] == pytest.approx(p.axis_minor_length, rel=1e-6, abs=1e-6)
            assert table["eccentricity"][i] == pytest.approx(p.eccentricity, abs=1e-6)
            # skimage measures from the row axis: theta_x = pi/2 - theta_rows (mod pi)
            difference = (table["orientation"][i] - (np.pi / 2 - p.orientation)) % np.pi
            assert min(difference, np.pi - difference) < 1e-6 or p.eccentricity < 1e-3


def test_perimeter_equals_scikit_image_per_region():
    labels = regions.label(blobs(4, (100, 100)), connectivity=4)
    table = regions.describe(labels)
    for i, lab in enumerate(table["label"]):
        # reference: skimage.measure.perimeter(labels == lab, neighborhood=4)
        assert table["perimeter"][i] == pytest.approx(
            skimage.measure.perimeter(labels == lab, neighborhood=4)
        )


def test_drawn_shapes():
    y, x = np.ogrid[:200, :200]
    disk = ((y - 100) ** 2 + (x - 100) ** 2 <= 60**2).astype(np.int32)
    table = regions.describe(disk)
    assert table["area"][0] == pytest.approx(np.pi * 60**2, rel=0.01)
    # the boundary-pixel estimate runs about 5% long on a digital circle (as skimage's does)
    assert table["perimeter"][0] == pytest.approx(2 * np.pi * 60, rel=0.06)
    assert table["circularity"][0] == pytest.approx(1.0, abs=0.12)
    assert table["eccentricity"][0] < 0.05
    bar = np.zeros((50, 80), np.int32)
    bar[20:30, 10:70] = 1  # 10 rows × 60 columns: major axis along x
    table = regions.describe(bar)
    assert table["area"][0] == 600 and table["extent"][0] == 1.0
    assert table["orientation"][0] == pytest.approx(0.0, abs=1e-9)
    assert table["major_axis"][0] == pytest.approx(4 * np.sqrt((60**2 - 1) / 12))
    tilted = np.zeros((100, 100), np.int32)
    for i in range(60):
        tilted[20 + i, 20 + i : 23 + i] = 1  # a diagonal stroke going down-right
    assert regions.describe(tilted)["orientation"][0] == pytest.approx(np.pi / 4, abs=0.05)


def test_filter_keeps_ranges_and_renumbers():
    labels = np.zeros((10, 30), np.int32)
    labels[1:3, 1:3] = 1  # area 4
    labels[1:6, 10:15] = 2  # area 25
    labels[1:9, 20:28] = 3  # area 64
    table = regions.describe(labels)
    kept = regions.filter_regions(labels, table, ranges={"area": [10, None]})
    assert kept.count == 2 and kept.table["label"].tolist() == [1, 2]
    assert kept.table["area"].tolist() == [25, 64]
    assert set(np.unique(kept.labels)) == {0, 1, 2} and kept.labels[3, 12] == 1
    assert regions.filter_regions(labels, table, ranges={"area": [None, 30]}).count == 2
    with pytest.raises(ValueError, match="unknown descriptor 'size' in ranges; columns: label"):
        regions.filter_regions(labels, table, ranges={"size": [1, 2]})


def test_drawings():
    labels = np.zeros((20, 20), np.int32)
    labels[2:8, 2:8] = 1
    labels[10:18, 10:18] = 2
    coloured = regions.colorize(labels)
    assert coloured.shape == (20, 20, 3) and (coloured[0, 0] == 0).all()
    assert not np.array_equal(coloured[4, 4], coloured[12, 12])
    gray = np.full((20, 20), 0.5, np.float32)
    drawn = regions.overlay(gray, labels, regions.describe(labels))
    assert np.array_equal(drawn[2, 6], coloured[4, 4])  # outline pixel in the region's colour
    assert drawn[4, 4].tolist() == [1.0, 0.0, 0.0]  # centroid (4.5, 4.5) rounds to (4, 4)
    assert drawn[0, 0].tolist() == [0.5, 0.5, 0.5]
