"""Every op with more than one implementation, run by each on shared inputs
(:mod:`.cases`), agrees with the reference within the tolerance the op declares.

Skipped, with the reason, when OpenCV is not installed; the ``dev`` extra installs it,
so CI runs it. An implementation added without a case here, or an op without a
declared tolerance, fails the build.
"""

from __future__ import annotations

import numpy as np
import pytest

import graphvision as gv
from graphvision.nodes.backends import unavailable
from graphvision.testing import PluginCheckError, check_conformance

from .cases import all_cases

pytest.importorskip("cv2", reason="the opencv backend needs opencv-python-headless (dev extra)")

REGISTRY = gv.discover()
CASES = all_cases()
IMPLEMENTED = sorted(
    (op, backend)
    for op, backends in REGISTRY.implementations.items()
    for backend in backends
    if op in REGISTRY.nodes
)


def test_every_implementation_has_cases_and_every_op_a_tolerance() -> None:
    missing = [f"{op}@{backend}" for op, backend in IMPLEMENTED if op not in CASES]
    undeclared = [op for op, _ in IMPLEMENTED if REGISTRY.node(op).conformance is None]
    assert not missing, f"implementations without conformance cases: {missing}"
    assert not undeclared, f"ops with implementations but no declared tolerance: {undeclared}"
    assert len(IMPLEMENTED) >= 20


@pytest.mark.parametrize(
    ("op", "backend", "number"),
    [(op, b, n) for op, b in IMPLEMENTED for n in range(len(CASES.get(op, [])))],
)
def test_implementation_conforms(op: str, backend: str, number: int) -> None:
    reason = unavailable(REGISTRY.implementations[op][backend])
    if reason:  # a check of its requires fails here (OpenCV 5 lacks CascadeClassifier)
        pytest.skip(reason)
    inputs, params = CASES[op][number]
    check_conformance(op, backend, inputs, params, registry=REGISTRY)


def test_a_difference_beyond_the_tolerance_fails() -> None:
    """The comparison can fail: a Gaussian of another σ is refused, naming the output."""
    registry = gv.discover()
    inputs, _ = CASES["filters.gaussian"][0]
    spec = registry.implementation("filters.gaussian", "opencv")
    assert spec is not None
    wrong = registry.implementations["filters.gaussian"]["opencv"]
    shifted = type(wrong)(wrong.mark, lambda image, *, sigma, boundary: spec.func(
        image, sigma=sigma * 1.1, boundary=boundary), wrong.ref, wrong.plugin)  # fmt: skip
    registry.implementations["filters.gaussian"]["opencv"] = shifted
    registry._implementation_specs.clear()
    with pytest.raises(PluginCheckError, match=r"filters.gaussian \(opencv vs numpy\): out: max"):
        check_conformance("filters.gaussian", "opencv", inputs, {"sigma": 2.0}, registry=registry)


def test_lines_and_circles_are_compared_by_position() -> None:
    """Lines match by (ρ px, θ°) with θ wrapping at 180° (ρ → −ρ), circles by (x, y, r);
    the strength column is not compared, and a line 3 px away is refused."""
    from graphvision.nodes.conformance import _recall_problem

    rule = gv.Conformance("recall", 1.0, radius=1.5)
    lines = np.array([[40.0, np.radians(0.5), 90.0], [10.0, np.radians(60.0), 50.0]])
    wrapped = np.array([[-40.0, np.radians(179.8), 3.0], [10.5, np.radians(61.0), 7.0]])
    assert _recall_problem(rule, lines, wrapped) == ""
    shifted = wrapped + np.array([[0.0, 0.0, 0.0], [3.0, 0.0, 0.0]])
    assert _recall_problem(rule, lines, shifted) == "recall 0.500 < 1.0"
    circles = np.array([[30.0, 20.0, 12.0, 0.9]])
    assert _recall_problem(rule, circles, circles + np.array([0.5, -0.5, 0.5, -0.4])) == ""
    assert (
        _recall_problem(rule, circles, circles + np.array([0.0, 0.0, 2.0, 0.0]))
        == "recall 0.000 < 1.0"
    )


def test_disparity_maps_are_compared_where_both_are_valid() -> None:
    """NaN is invalid: pixels valid in one map alone count against ``mismatch``, pixels
    valid in both more than ``radius`` apart against ``tolerance``."""
    from graphvision.nodes.conformance import _leaf

    rule = gv.Conformance("disparity", 0.1, radius=1.0, mismatch=0.2)
    ours = np.full((4, 5), 8.0, np.float32)
    ours[0, :2] = np.nan
    theirs = ours + np.float32(0.5)
    theirs[3, 4] = np.nan  # 1 of 19 valid pixels alone
    assert _leaf(rule, ours, theirs) == ""
    theirs[1:3] += 2.0  # 10 of 17 differ by 2.5 px
    assert _leaf(rule, ours, theirs) == "58.824% of the pixels valid in both differ by > 1.0 px"
    theirs[:] = np.nan
    assert _leaf(rule, ours, theirs).startswith("100.000% of the valid pixels valid in one")


def test_opencv_fixed_point_disparity_is_divided_by_16_and_invalid_is_nan() -> None:
    from graphvision_plugins.opencv_backend.convert import disparity_from_cv

    fixed = np.array([[-16, 0, 8, 130, 400]], np.int16)  # invalid, 0, 0.5, 8.125, 25
    out = disparity_from_cv(fixed, 0, 24)
    assert out.dtype == np.float32
    np.testing.assert_array_equal(out, [[np.nan, 0.0, 0.5, 8.125, np.nan]])


def test_opencv_board_corners_are_put_in_the_reference_order_whatever_end_it_starts() -> None:
    from graphvision_plugins.opencv_backend.convert import board_from_cv
    from graphvision_plugins.synthetic import board_views

    board = board_views(views=1, width=320, height=240, focal=400.0, seed=1)
    truth = board.corners[0]  # the reference's order, built with the views
    for turned in (truth, truth[::-1]):  # OpenCV may list the board from either end
        ordered = board_from_cv(turned.astype(np.float32), 9, 6, board.views[0])
        np.testing.assert_allclose(ordered, truth, atol=1e-4)


def test_a_matrix_up_to_scale_is_compared_at_unit_norm_whatever_its_sign() -> None:
    from graphvision.nodes.conformance import _compare

    rule = gv.Conformance("up_to_scale", 0.05)
    E = np.array([[0.0, -1.0, 0.2], [1.0, 0.0, -0.5], [-0.1, 0.4, 0.0]])
    assert _compare(rule, (E,), (-3.0 * E,), "E") == []
    tilted = E + np.array([[0.0, 0.0, 0.3], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    apart = np.linalg.norm(E / np.linalg.norm(E) - tilted / np.linalg.norm(tilted))
    assert _compare(rule, (E,), (tilted,), "E") == [f"E: unit-norm distance {apart:.3g} > 0.05"]


def test_opencv_calibration_refuses_too_few_boards_naming_the_views() -> None:
    from graphvision_plugins.opencv_backend import cv_calibrate_board

    inputs, _ = CASES["camera.calibrate_board"][0]
    corners = inputs["corners"].copy()
    corners[2:] = np.nan
    with pytest.raises(
        ValueError,
        match=r"only 2 of 6 views have a board, need 3; no board found in views \[2, 3, 4, 5\]",
    ):
        cv_calibrate_board(corners, inputs["object_points"])
