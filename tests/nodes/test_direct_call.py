"""A node called as a plain function checks what a run checks (issue 8, item 2).

For each built-in family: a dtype the dtype policy refuses (a ``uint8`` photo
is taken, as ``gv.run`` takes it: test_direct_call_dtypes.py), a wrong
number of channels (or a wrong shape) and a bad parameter on a direct call fail
with the engine's own error types, naming the node and the port or parameter. A correct call gives
the same value as the unchecked function.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import graphvision as gv
from graphvision.nodes.marks import unchecked
from graphvision_plugins import (
    colour,
    features,
    filters,
    fitting,
    geometry,
    matching,
    metrics,
    morphology,
    regions,
    threshold,
)

RNG = np.random.default_rng(7)
GRAY = RNG.random((24, 24), dtype=np.float32)
RGB = RNG.random((24, 24, 3), dtype=np.float32)
MASK = GRAY > 0.5
DESCRIPTORS = RNG.random((10, 128), dtype=np.float32)
POINTS = RNG.random((20, 2)) * 10
CROSS = np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], dtype=bool)

# (call with wrong dtype, call with wrong channels/shape, call with a bad parameter,
#  what the messages name)
CASES: dict[str, tuple[Callable[[], Any], Callable[[], Any], Callable[[], Any], str]] = {
    "colour": (
        lambda: colour.chromaticity((RGB * 255).astype(np.int64)),
        lambda: colour.chromaticity(GRAY),
        lambda: colour.to_gray(RGB, method="median"),
        "colour.",
    ),
    "filters": (
        lambda: filters.gaussian((GRAY * 255).astype(np.int16)),
        lambda: filters.gaussian(np.dstack([GRAY] * 5)),
        lambda: filters.gaussian(GRAY, sigma=-1.0),
        "filters.gaussian",
    ),
    "features": (
        lambda: features.harris(GRAY.astype(np.complex64)),
        lambda: features.harris(RGB),
        lambda: features.harris(GRAY, alpha=0.5),
        "features.harris",
    ),
    "threshold": (
        lambda: threshold.otsu((GRAY * 255).astype(np.int32)),
        lambda: threshold.otsu(RGB),
        lambda: threshold.otsu(GRAY, foreground="sideways"),
        "threshold.otsu",
    ),
    "morphology": (
        lambda: morphology.erode(np.where(MASK, 1, -1).astype(np.int8), CROSS),
        lambda: morphology.erode(MASK, np.ones((3, 3, 3), dtype=bool)),
        lambda: morphology.footprint(shape="disk", size=-3),
        "morphology.",
    ),
    "regions": (
        lambda: regions.label(GRAY),
        lambda: regions.label(np.dstack([MASK] * 3)),
        lambda: regions.label(MASK, connectivity=6),
        "regions.label",
    ),
    "matching": (
        lambda: matching.match(DESCRIPTORS.astype(np.int32), DESCRIPTORS),
        lambda: matching.match(DESCRIPTORS[0], DESCRIPTORS),
        lambda: matching.match(DESCRIPTORS, DESCRIPTORS, ratio=1.5),
        "matching.match",
    ),
    "fitting": (
        lambda: fitting.fit_line_ransac(POINTS.astype(str)),
        lambda: fitting.fit_line_ransac(np.c_[POINTS, POINTS[:, :1]]),
        lambda: fitting.fit_line_ransac(POINTS, confidence=1.0),
        "fitting.",
    ),
    "geometry": (
        lambda: geometry.warp(GRAY, np.eye(3, dtype=np.complex128)),
        lambda: geometry.warp(GRAY, np.eye(2)),
        lambda: geometry.warp(GRAY, np.eye(3), width=-5),
        "geometry.warp",
    ),
    "metrics": (
        lambda: metrics.psnr(GRAY, (GRAY * 255).astype(np.int16)),
        lambda: metrics.psnr(np.dstack([GRAY] * 5), np.dstack([GRAY] * 5)),
        lambda: metrics.psnr(GRAY, GRAY, peak=2),
        "metrics.psnr",
    ),
}


@pytest.mark.parametrize("family", sorted(CASES))
def test_wrong_dtype_is_refused_naming_node_and_port(family: str) -> None:
    wrong_dtype, _, _, names = CASES[family]
    with pytest.raises(gv.PortValueError, match=rf"^{names}.*input '\w+'.* expected"):
        wrong_dtype()


@pytest.mark.parametrize("family", sorted(CASES))
def test_wrong_channels_or_shape_is_refused(family: str) -> None:
    _, wrong_shape, _, names = CASES[family]
    with pytest.raises(gv.PortValueError, match=rf"^{names}.*input '\w+'.*got (array )?shape"):
        wrong_shape()


@pytest.mark.parametrize("family", sorted(CASES))
def test_bad_parameter_is_refused_naming_it(family: str) -> None:
    _, _, bad_param, names = CASES[family]
    with pytest.raises(gv.ParameterError, match=rf"parameter '\w+' of {names}"):
        bad_param()


def test_a_checked_call_gives_what_the_unchecked_function_gives() -> None:
    checked = filters.gaussian(GRAY, sigma=2.0)
    raw = unchecked(filters.gaussian)(GRAY, sigma=2.0, boundary="mirror")
    np.testing.assert_array_equal(checked, raw)


@gv.node("test.blend", version=1)
def blend(a: gv.ImageT, b: gv.ImageT, *, weight: float = 0.5) -> gv.ImageT:
    """Weighted mean of two images of one type."""
    return (weight * a + (1 - weight) * b).astype(np.float32)


def test_type_variable_binds_once_per_call() -> None:
    """A gray and a colour image given to one ``ImageT`` pair are refused."""
    assert blend(GRAY, GRAY).shape == GRAY.shape
    with pytest.raises(gv.PortValueError, match=r"input 'b' is ColorImage .* is GrayImage"):
        blend(GRAY, RGB)


def test_missing_input_and_extra_positional_are_named() -> None:
    with pytest.raises(gv.PortValueError, match=r"filters\.gaussian: missing input 'image'"):
        filters.gaussian()
    with pytest.raises(gv.PortValueError, match=r"takes 1 input\(s\) \(image\), got 2"):
        filters.gaussian(GRAY, GRAY)
