"""Morphology against hand-drawn truths and scipy.ndimage's binary operators."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.ndimage as ndi

import graphvision as gv
from graphvision_plugins import morphology as morph


def disk_image(shape=(60, 60), centre=(30, 30), radius=15):
    y, x = np.ogrid[: shape[0], : shape[1]]
    return (y - centre[0]) ** 2 + (x - centre[1]) ** 2 <= radius**2


def test_footprints():
    assert morph.footprint(shape="square", size=3).sum() == 9
    assert morph.footprint(shape="rectangle", height=3, width=5).shape == (3, 5)
    np.testing.assert_array_equal(
        morph.footprint(shape="cross", size=3), [[0, 1, 0], [1, 1, 1], [0, 1, 0]]
    )
    np.testing.assert_array_equal(morph.footprint(shape="diamond", size=5)[2], [1, 1, 1, 1, 1])
    disk = morph.footprint(shape="disk", size=7)
    assert disk.sum() == 29 and disk[3].all() and not disk[0, 0]  # 29 lattice points in r=3
    with pytest.raises(ValueError, match=r"parameter 'size' of morphology\.footprint: must be odd"):
        morph.footprint(shape="disk", size=4)


@pytest.mark.parametrize(
    ("value", "message"),
    [
        (np.ones((4, 4), bool), "must have odd sides so that it has a centre, got 4×4"),
        (np.zeros((3, 3), bool), "structuring element is empty"),
        (np.ones((3, 3), np.uint8), "expected Footprint"),
    ],
)
def test_bad_structuring_elements(value, message):
    with pytest.raises(gv.PortValueError, match=message):
        morph.FootprintPort.validate(value)


@pytest.mark.parametrize("shape", ["square", "disk", "cross", "diamond"])
def test_binary_operators_equal_scipy(shape):
    rng = np.random.default_rng(0)
    mask = ndi.gaussian_filter(rng.random((50, 70)), 2) > 0.5
    element = morph.footprint(shape=shape, size=5)
    # references: scipy.ndimage.binary_erosion(mask, element, border_value=1) and
    # binary_dilation(mask, element); opening/closing as their compositions
    eroded = ndi.binary_erosion(mask, element, border_value=1)
    dilated = ndi.binary_dilation(mask, element)
    np.testing.assert_array_equal(morph.erode(mask, element), eroded)
    np.testing.assert_array_equal(morph.dilate(mask, element), dilated)
    np.testing.assert_array_equal(morph.open(mask, element), ndi.binary_dilation(eroded, element))
    np.testing.assert_array_equal(
        morph.close(mask, element), ndi.binary_erosion(dilated, element, border_value=1)
    )


def test_erosion_and_dilation_of_a_disk_change_its_radius():
    element = morph.footprint(shape="disk", size=7)  # radius 3
    eroded = morph.erode(disk_image(radius=15), element)
    # on the pixel lattice the radius changes by 3 up to a pixel
    assert (disk_image(radius=11.5) <= eroded).all() and (eroded <= disk_image(radius=12.5)).all()
    grown = morph.dilate(disk_image(radius=10), element)
    assert (disk_image(radius=12.5) <= grown).all() and (grown <= disk_image(radius=13.5)).all()


def test_opening_removes_small_objects_and_closing_fills_small_holes():
    mask = disk_image(radius=15)
    mask[5:7, 5:7] = True  # a 2×2 speck
    mask[29:31, 29:31] = False  # a 2×2 hole
    element = morph.footprint(shape="square", size=3)
    opened = morph.open(mask, element)
    assert not opened[5:7, 5:7].any() and opened[20, 30]
    assert morph.close(mask, element)[29:31, 29:31].all()


def test_gray_morphology_is_min_and_max():
    image = np.random.default_rng(1).random((20, 20)).astype(np.float32)
    square = morph.footprint(shape="square", size=3)
    eroded = morph.erode(image, square)
    assert eroded[10, 10] == image[9:12, 9:12].min()
    assert morph.dilate(image, square)[5, 7] == image[4:7, 6:9].max()
    assert eroded.dtype == np.float32


def test_fill_holes_fills_only_enclosed_background():
    ring = disk_image(radius=15) & ~disk_image(radius=8)
    open_ring = ring.copy()
    open_ring[28:33, 30:] = False  # a channel from the hole to the outside
    np.testing.assert_array_equal(morph.fill_holes(ring), disk_image(radius=15))
    np.testing.assert_array_equal(morph.fill_holes(open_ring), open_ring)
    assert morph.fill_holes(ring, max_area=10).sum() == ring.sum()  # the hole is larger


def test_remove_small_objects():
    mask = np.zeros((20, 20), bool)
    mask[2:4, 2:4] = True  # 4 pixels
    mask[10:15, 10:15] = True  # 25 pixels
    kept = morph.remove_small_objects(mask, min_area=5)
    assert kept.sum() == 25 and kept[12, 12]
    assert not morph.remove_small_objects(np.zeros((5, 5), bool)).any()  # empty mask: empty


def test_logical():
    a = np.array([[1, 1, 0, 0]], bool)
    b = np.array([[1, 0, 1, 0]], bool)
    assert morph.logical(a, b, op="xor").tolist() == [[False, True, True, False]]
    assert morph.logical(a, b, op="and_not").tolist() == [[False, True, False, False]]


def test_a_colour_image_is_refused_where_gray_or_binary_is_required(registry):
    graph = gv.Graph("m")
    fp = graph.add("fp", "morphology.footprint")
    graph.output(
        "o",
        graph.add("e", "morphology.erode", image=graph.input("image", "ColorImage"), footprint=fp),
    )
    with pytest.raises(
        gv.PipelineError,
        match="gives ColorImage but 'e.image' "
        r"\(morphology.erode\) takes BinaryImage or GrayImage",
    ):
        gv.compile_graph(graph, registry)


@pytest.mark.parametrize("width", [1, 63, 64, 65, 130])
def test_packed_rows_handle_every_width_and_asymmetric_elements(width):
    mask = np.random.default_rng(width).random((17, width)) > 0.4
    element = np.array([[1, 0, 0], [1, 1, 0], [0, 1, 1]], bool)  # not symmetric
    # reference: scipy.ndimage binary_erosion / binary_dilation with the same structure
    np.testing.assert_array_equal(
        morph.erode(mask, element), ndi.binary_erosion(mask, element, border_value=1)
    )
    np.testing.assert_array_equal(morph.dilate(mask, element), ndi.binary_dilation(mask, element))


def test_wide_elements_fall_back_to_scipy_with_the_same_result():
    mask = np.random.default_rng(0).random((40, 200)) > 0.3
    element = morph.footprint(shape="rectangle", height=3, width=71)  # half width 35 > 31
    np.testing.assert_array_equal(
        morph.erode(mask, element), ndi.binary_erosion(mask, element, border_value=1)
    )
