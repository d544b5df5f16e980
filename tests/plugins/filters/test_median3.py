"""The 3×3 median (``_median_kernels.median_3x3``): the median of the nine neighbours under
each boundary rule, and to the bit the values of the kernel it replaced (the sign of a zero
median among +0 and −0 included), on small, odd, wide, constant, tied and subnormal images."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from numpy.lib.stride_tricks import sliding_window_view

from graphvision import PortValueError
from graphvision_plugins import filters

BOUNDARIES = ["mirror", "replicate", "wrap", "zero", "crop"]
# the op's rules as numpy.pad modes (docs: plugins/filters/_boundary.py)
_PAD = {"mirror": "symmetric", "replicate": "edge", "wrap": "wrap", "zero": "constant"}
# 1..5 on each side (windows over both borders at once), and wide rows (the vector loop and
# its remainder)
SHAPES = [*itertools.product(range(1, 6), repeat=2), (7, 600), (4, 513), (9, 257)]
# every rule on every shape but crop on an image smaller than the window (refused by the op)
CASES = [(b, s) for b in BOUNDARIES for s in SHAPES if b != "crop" or min(s) >= 3]


def _padded(image: np.ndarray, boundary: str) -> np.ndarray:
    return image if boundary == "crop" else np.pad(image, 1, mode=_PAD[boundary])


def _first_min(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """numba's ``min(p, q)``: ``q`` only when it is smaller (``p`` on a tie, or NaN)."""
    return np.where(q < p, q, p)


def _first_max(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    return np.where(q > p, q, p)


def _previous_kernel(image: np.ndarray, boundary: str, ring: bool = True) -> np.ndarray:
    """The 3×3 kernel before it read the rows in place, in NumPy: padded row ``p`` copied
    into slot ``p mod 3`` of a ring of three lines, each column sorted in slot order, and
    Paeth's network over the sorted triples, every comparison as numba's ``min``/``max``
    (``ring=False``: the rows in top-to-bottom order instead)."""
    padded = _padded(image, boundary)
    out = np.empty((padded.shape[0] - 2, padded.shape[1] - 2), np.float32)
    for r in range(out.shape[0]):
        a, b, c = (padded[r + ((slot - r) % 3 if ring else slot)] for slot in range(3))
        small, large = _first_min(a, b), _first_max(a, b)
        low, high = _first_min(small, c), _first_max(large, c)
        mid = _first_max(small, _first_min(large, c))
        lows = _first_max(_first_max(low[:-2], low[1:-1]), low[2:])
        highs = _first_min(_first_min(high[:-2], high[1:-1]), high[2:])
        small, large = _first_min(mid[:-2], mid[1:-1]), _first_max(mid[:-2], mid[1:-1])
        mids = _first_max(small, _first_min(large, mid[2:]))
        small, large = _first_min(lows, mids), _first_max(lows, mids)
        out[r] = _first_max(small, _first_min(large, highs))
    return out


def _images(shape: tuple[int, int]) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(shape[0] * 100 + shape[1])
    signed_zeros = rng.choice(np.array([0.0, -0.0], np.float32), shape)
    mixed = rng.random(shape).astype(np.float32)
    mixed[rng.random(shape) < 0.4] = 0.0
    mixed[rng.random(shape) < 0.4] = -0.0
    return {
        "random": rng.random(shape).astype(np.float32),
        "constant": np.full(shape, 0.3, np.float32),
        "levels": (rng.integers(0, 3, shape) / np.float32(2)).astype(np.float32),  # ties
        "signed zeros": signed_zeros,
        "zeros and values": mixed,
        "subnormals": rng.choice(np.array([0.0, -0.0, 1e-45, 1e-40, 1.2e-38], np.float32), shape),
    }


def _bits(values: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(values).view(np.uint32)


@pytest.mark.parametrize(("boundary", "shape"), CASES, ids=str)
def test_3x3_median_is_the_median_of_the_nine_neighbours(boundary, shape):
    for name, image in _images(shape).items():
        windows = sliding_window_view(_padded(image, boundary).astype(np.float64), (3, 3))
        expected = np.median(windows, axis=(-2, -1))  # +0 equals −0 here
        found = filters.median(image, size=3, boundary=boundary)
        np.testing.assert_array_equal(found, expected, err_msg=name)


@pytest.mark.parametrize(("boundary", "shape"), CASES, ids=str)
def test_3x3_median_keeps_the_previous_kernels_bits(boundary, shape):
    """Which of +0 and −0 a zero median is depends on the order the comparators met
    them: the kernel keeps the order it had, so the bits are the same."""
    for name, image in _images(shape).items():
        found = filters.median(image, size=3, boundary=boundary)
        expected = _previous_kernel(image, boundary)
        assert np.array_equal(_bits(found), _bits(expected)), name


def test_the_signed_zeros_tell_the_orders_apart():
    """The test above can fail: on this image the median is +0 at some pixels and −0 at
    others, and the same network over the rows in top-to-bottom order picks other zeros."""
    image = _images((40, 53))["signed zeros"]
    found = filters.median(image, size=3)
    assert np.signbit(found).any() and not np.signbit(found).all()
    top_down = _previous_kernel(image, "mirror", ring=False)
    np.testing.assert_array_equal(top_down, found)  # the same values,
    assert not np.array_equal(_bits(top_down), _bits(found))  # not the same bits


@pytest.mark.parametrize("boundary", BOUNDARIES)
def test_3x3_kernel_keeps_the_previous_bits_off_the_port_range(boundary):
    """NaN, infinities and negative values do not pass the image port; the kernel itself
    (the node's function) still gives the previous kernel's values on them."""
    rng = np.random.default_rng(7)
    values = np.array([np.nan, np.inf, -np.inf, -1.0, -0.0, 0.0, 0.5], np.float32)
    for shape in [(1, 1), (3, 4), (5, 5), (11, 600)]:
        image = rng.choice(values, shape)
        if boundary == "crop" and min(shape) < 3:
            continue
        found = filters.median.__wrapped__(image, size=3, boundary=boundary)
        assert np.array_equal(_bits(found), _bits(_previous_kernel(image, boundary)))


def test_the_node_refuses_nan():
    image = np.full((4, 4), 0.5, np.float32)
    image[1, 2] = np.nan
    with pytest.raises(PortValueError, match="has NaN or infinite values"):
        filters.median(image, size=3)
