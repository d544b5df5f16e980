"""The row kernels of census matching (``_match_kernels``, ``_sgm_kernels``) against the
volume kernels they replace for census costs (``_kernels``: the full cost volume, box sum,
per-path aggregation, winner take all), which still serve the other costs: equal to the bit."""

from __future__ import annotations

import numpy as np
import pytest

from graphvision_plugins import stereo, synthetic
from graphvision_plugins.stereo import _kernels, _match_kernels, _sgm_kernels
from graphvision_plugins.stereo._disparity import PATHS, _jumps


@pytest.fixture(scope="module")
def pair():
    return synthetic.stereo_pair(width=96, height=64, seed=5)


def _signatures(pair, half):
    return _kernels.census(pair.left, half, half), _kernels.census(pair.right, half, half)


def test_census_signatures_equal_the_volume_kernels(pair):
    for half in (1, 2, 3):
        found = _match_kernels.census_signatures(pair.left, half)
        np.testing.assert_array_equal(found, _kernels.census(pair.left, half, half))


def _volume(pair, d_min, count, half, block_half):
    left, right = _signatures(pair, half)
    outside = (2 * half + 1) ** 2 - 1
    costs = _kernels.census_costs(left, right, d_min, count, outside)
    return (left, right, outside), _kernels.box_sum(costs, block_half)


@pytest.mark.parametrize(
    ("d_min", "count", "half", "block_half"),
    [(0, 24, 3, 4), (-6, 30, 2, 0), (3, 17, 1, 7), (-200, 4, 3, 2), (90, 12, 3, 2)],
)
def test_block_matching_rows_equal_the_volume(pair, d_min, count, half, block_half):
    (left, right, outside), volume = _volume(pair, d_min, count, half, block_half)
    found, found_right = _match_kernels.census_block_match(
        left, right, d_min, count, outside, block_half, 0.1, True
    )
    expected = _kernels.winner_take_all(volume, d_min, 0.1, True)
    np.testing.assert_array_equal(found, expected)
    np.testing.assert_array_equal(found_right, _kernels.right_disparity(volume, d_min))
    summed = _match_kernels.census_volume(left, right, d_min, count, outside, block_half)
    np.testing.assert_array_equal(summed, volume.transpose(0, 2, 1))  # disparity-major


@pytest.mark.parametrize(
    ("paths", "edge", "d_min", "count"),
    # 1, 2 and 3 disparities: the horizontal step's vector loop over the inner ones is empty
    [
        (8, 0.02, 0, 20),
        (4, None, -3, 20),
        (8, 0.1, 2, 20),
        (8, 0.02, 0, 1),
        (4, 0.02, 1, 2),
        (8, 0.02, -1, 3),
    ],
)
def test_sgm_sweeps_equal_the_path_kernels(pair, paths, edge, d_min, count):
    _, volume = _volume(pair, d_min, count, 3, 2)
    p1, p2 = 12 * 25, 128 * 25
    total = np.zeros_like(volume)
    for step_y, step_x in PATHS[:paths]:
        jumps = _jumps(pair.left, step_y, step_x, p1, p2, edge).astype(np.uint16)
        _kernels.aggregate_path(volume, total, step_y, step_x, np.uint16(p1), jumps)
    jumps = [
        _match_kernels.jump_penalties(
            pair.left,
            np.array([[0, s], [s, 0], [s, s], [s, -s]])[: paths // 2],
            float(p1),
            float(p2),
            -1.0 if edge is None else edge,
        )
        for s in (1, -1)
    ]
    by_disparity = np.ascontiguousarray(volume.transpose(0, 2, 1))
    found, found_right = _sgm_kernels.sweep_paths(by_disparity, p1, *jumps, d_min, 0.05, True)
    np.testing.assert_array_equal(found, _kernels.winner_take_all(total, d_min, 0.05, True))
    np.testing.assert_array_equal(found_right, _kernels.right_disparity(total, d_min))
    # the block sums made row by row inside the forward sweep: the same disparities
    fused = _sgm_kernels.census_sweep_paths(
        _signatures(pair, 3), (d_min, count, 48, 2), p1, *jumps, (0.05, True)
    )
    np.testing.assert_array_equal(fused[0], found)
    np.testing.assert_array_equal(fused[1], found_right)


def _left_right_reference(disparity, right_disparity, tolerance):
    """The array formula ``left_right_check`` was before it was compiled."""
    rows, cols = disparity.shape
    valid = np.isfinite(disparity)
    estimate = np.where(valid, disparity, 0)
    y = np.broadcast_to(np.arange(rows)[:, None], (rows, cols))
    keep = np.zeros(disparity.shape, dtype=bool)
    for whole in (np.floor(estimate), np.ceil(estimate)):
        x_right = np.arange(cols)[None, :] - whole.astype(np.int64)
        inside = valid & (x_right >= 0) & (x_right < cols)
        seen = np.full(disparity.shape, np.nan, dtype=np.float32)
        seen[inside] = right_disparity[y[inside], x_right[inside]]
        keep |= np.abs(whole - seen) <= tolerance
    return np.where(keep, disparity, np.float32(np.nan)).astype(np.float32)


def test_left_right_check_equals_the_array_formula():
    rng = np.random.default_rng(3)
    disparity = rng.uniform(-2, 12, (30, 40)).astype(np.float32)
    disparity[rng.random(disparity.shape) < 0.2] = np.nan
    right = np.round(rng.uniform(-2, 12, (30, 40))).astype(np.float32)
    right[rng.random(right.shape) < 0.2] = np.nan
    for tolerance in (0.0, 0.5, 1.0, 2.5):
        np.testing.assert_array_equal(
            stereo.left_right_check(disparity, right, tolerance),
            _left_right_reference(disparity, right, tolerance),
        )
