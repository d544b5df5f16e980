"""A label map's report picture, coloured through a per-label table: the same pixels as
colouring every pixel (graphvision.values.pictures.label_colours, the reference)."""

from __future__ import annotations

import numpy as np
import pytest

from graphvision.values.pictures import label_colours
from graphvision.views.viewers import _label_picture


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.int32, np.int64, np.uint64])
def test_the_table_gives_every_pixel_the_colour_of_its_label(dtype):
    rng = np.random.default_rng(7)
    labels = rng.integers(0, 200, (97, 131)).astype(dtype)
    labels[:5] = 0
    assert np.array_equal(_label_picture(labels), label_colours(labels))


@pytest.mark.parametrize(
    "labels",
    [
        np.array([[0, -3], [5, 2]], np.int32),  # negative labels
        np.array([[0, 2**40], [7, 1]], np.int64),  # a label far larger than the map
        np.zeros((0, 4), np.int32),  # empty
        np.array([[0.0, 2.0], [1.0, 0.0]]),  # floating-point labels
    ],
)
def test_maps_the_table_does_not_suit_are_coloured_pixel_by_pixel(labels):
    assert np.array_equal(_label_picture(labels), label_colours(labels))
