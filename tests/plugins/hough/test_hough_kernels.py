"""The compiled Hough helpers equal what they replace: scipy's maximum filter for peaks,
a scan of every point for a line's support, and the greedy loop of close-peak suppression."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import ndimage

from graphvision_plugins.hough._circle_kernels import window_maxima
from graphvision_plugins.hough._kernels import line_peaks, vote_lines
from graphvision_plugins.hough._lines import _point_index, _rho_grid
from graphvision_plugins.hough._peaks import suppress_close
from graphvision_plugins.hough._support_kernels import line_support, pruned_support, support_bounds


@pytest.mark.parametrize("size", [3, 5, 17, 70, 101])  # wider than the rows, or all
def test_window_maxima_equal_scipy_maximum_filter(size):
    rng = np.random.default_rng(size)
    values = np.round(rng.random((60, 80)) * 20) / 4  # plateaus: ties count as maxima
    values[:, :3] = 0.0
    expected = np.argwhere(
        (values == ndimage.maximum_filter(values, size, mode="nearest")) & (values > 0.5)
    )
    np.testing.assert_array_equal(window_maxima(values, size, 0.5), expected)


def test_line_peaks_equal_scipy_maximum_filter_on_the_kept_rows():
    rng = np.random.default_rng(3)
    extended = np.round(rng.random((40, 90)) * 10)
    pad, bins = 5, 30
    maxima = (extended == ndimage.maximum_filter(extended, 3, mode="nearest")) & (extended > 0)
    expected = np.argwhere(maxima)
    expected = expected[(expected[:, 0] >= pad) & (expected[:, 0] < pad + bins)]
    expected = expected[(expected[:, 1] > 0) & (expected[:, 1] < 89)]
    np.testing.assert_array_equal(line_peaks(extended, pad, bins), expected)


def _covered(x, y, rho, theta, tolerance, extent):
    """Support by brute force: distinct 1-px cells along the line of the points near it."""
    near = np.abs(x * np.cos(theta) + y * np.sin(theta) - rho) <= tolerance
    along = np.floor(y[near] * np.cos(theta) - x[near] * np.sin(theta)) + int(np.ceil(extent)) + 2
    return len(np.unique(along))


def _scene(seed, density=0.08):
    """Edge pixels of a 120×160 image (a line of 200 and 1,500 scattered at ``density``
    0.08) and 400 lines across θ in [0, π) and beyond it (the padded rows and refits: ρ
    changes sign there)."""
    rng = np.random.default_rng(seed)
    shape = (120, 160)
    mask = rng.random(shape) < density
    u = np.arange(160)
    mask[np.round(30 + 0.3 * u).astype(int), u] = True
    y, x = (v.astype(np.float64) for v in np.nonzero(mask))
    _, rho0 = _rho_grid(shape, 1.0)
    theta = rng.uniform(-0.3, math.pi + 0.3, 400)
    rho = rng.uniform(rho0, -rho0, 400)
    theta[:2], rho[:2] = math.atan2(1, -0.3), 30 / math.hypot(1, 0.3)
    theta[2:6] = (0.0, math.pi / 2, math.pi, math.pi / 4)  # axis-parallel and diagonal
    return shape, x, y, rho, theta, math.hypot(*shape) + 1.0


def test_support_of_the_points_by_row_and_column_equals_a_scan_of_every_point():
    """Replaces the points bucketed by ρ at every θ: the same support, visiting only the
    band around each line."""
    shape, x, y, rho, theta, extent = _scene(11)
    index = _point_index(x, y, shape, False)
    support = line_support(x, y, np.zeros(len(x)), False, rho, theta, 1.0, 0.0, extent, index)
    expected = [_covered(x, y, r, t, 1.0, extent) for r, t in zip(rho, theta, strict=True)]
    np.testing.assert_array_equal(support, expected)
    assert support[0] > 150


@pytest.mark.parametrize("density", [0.08, 0.02])
@pytest.mark.parametrize("threshold", [0.0, 0.3, 1.0])
def test_pruned_support_is_exact_where_a_line_can_be_kept(threshold, density):
    """Unit votes bound every line's support, so the lines measured by decreasing bound
    until one falls under ``threshold`` × the largest support give every support at least
    that exactly (and the largest); the others are 0. At density 0.02 the points are few
    for the image's size (at most 4 per row and column) and every line scans them all;
    at 0.08 only its band's rows."""
    shape, x, y, rho, theta, extent = _scene(5, density)
    assert (len(x) <= 4 * (shape[0] + shape[1] + 2)) == (density == 0.02)
    bins, pad = 90, 4
    rho[6:] = rho[6:] * 0.2 + 50  # many lines through the points, not only beyond them
    _, rho0 = _rho_grid(shape, 1.0)
    table = np.arange(bins) * (math.pi / bins)
    n_rho = _rho_grid(shape, 1.0)[0]
    args = (x, y, np.ones(len(x)), np.zeros(len(x), np.int64), bins, np.cos(table))
    raw = vote_lines(*args, np.sin(table), rho0, n_rho, pad)
    index = _point_index(x, y, shape, False)
    bounds = support_bounds(raw, pad, rho, theta, rho0, 1.0, 1.0, 159.0, 119.0)
    expected = np.array(
        [_covered(x, y, r, t, 1.0, extent) for r, t in zip(rho, theta, strict=True)]
    )
    assert (bounds >= expected).all()
    support = pruned_support(x, y, index, bounds, rho, theta, 1.0, extent, threshold)
    kept = expected >= threshold * expected.max()
    np.testing.assert_array_equal(support[kept], expected[kept])
    assert ((support == expected) | (support == 0)).all()
    if threshold == 0.3:
        assert 0 < (support > 0).sum() < 0.8 * len(rho)  # lines were skipped


def test_suppress_close_keeps_strongest_first_apart():
    positions = np.array([[0.0, 0.0], [3.0, 0.0], [10.0, 0.0], [12.0, 0.0], [0.0, 4.0]])
    scores = np.array([1.0, 5.0, 2.0, 2.0, 0.5])
    # 1 (5) first; 2 and 3 tie (stable: 2 first), 3 within 5 of 2; 0 within 5 of 1; 4 is 5 from 1
    np.testing.assert_array_equal(suppress_close(positions, scores, 5.0, 10), [1, 2, 4])
    np.testing.assert_array_equal(suppress_close(positions, scores, 5.0, 2), [1, 2])


def test_folding_radii_equals_the_whole_stack_of_scores():
    from graphvision_plugins.hough._circle_kernels import fold_plane

    rng = np.random.default_rng(5)
    stack = np.round(rng.random((6, 20, 30)) * 8) / 8  # ties: the first radius wins
    n = len(stack)
    best, below, above, previous = (np.empty((20, 30)) for _ in range(4))
    k_best = np.zeros((20, 30), dtype=np.int64)
    for k, plane in enumerate(stack):
        fold_plane(plane * 3.0, k, n - 1, 0.5, 1.5, best, k_best, below, above, previous)
    scores = stack * 3.0 * 0.5 / 1.5
    k = scores.argmax(axis=0)
    y, x = np.mgrid[0:20, 0:30]
    np.testing.assert_array_equal(best, scores.max(axis=0))
    np.testing.assert_array_equal(k_best, k)
    np.testing.assert_array_equal(below, scores[np.maximum(k - 1, 0), y, x])
    np.testing.assert_array_equal(above, scores[np.minimum(k + 1, n - 1), y, x])


@pytest.mark.parametrize("width", [64, 300])
@pytest.mark.parametrize("vote_sigma", [0.0, 0.5, 1.0, 2.5])
def test_radii_in_one_call_equal_the_stack_smoothed_plane_by_plane(vote_sigma, width):
    """``_best_over_radii`` (votes, spreading and folding of every radius compiled in one
    call) equals, to the bit, the whole stack of votes of ``vote_circles`` smoothed plane
    by plane by ``smooth_gaussian(mode="constant")``, then its max and argmax over radii.
    The spreading's taps reach 2, 4 and 10 pixels (pairs of taps four at a time and one
    at a time); 300 columns leave runs of columns without a vote, which it skips."""
    from graphvision_plugins.hough._circle_kernels import vote_circles
    from graphvision_plugins.hough._circles import _best_over_radii, _voters
    from graphvision_plugins.shared.separable import smooth_gaussian

    y, x = np.mgrid[0:48, 0:width]
    image = (np.hypot(x - 30.3, y - 22.6) < 11.2).astype(np.float32)
    image[5:12, 40:60] = 0.6  # a bar: votes that meet no centre
    image[(np.hypot(x - 270.5, y - 30.2) < 9.0)] = 0.8  # beyond 64 columns: a second disc
    edges = np.abs(np.gradient(image.astype(np.float64))[0]) + np.abs(np.gradient(image)[1]) > 0
    radii = np.arange(8.0, 14.5, 1.0)
    best, k_best, below, above = _best_over_radii(edges, image, radii, 1.0, "both", vote_sigma)
    rows, cols, ux, uy, signs = _voters(edges, image, 1.0, "both")
    stack = vote_circles(rows, cols, ux, uy, radii, signs, *edges.shape)
    if vote_sigma > 0:
        stack = np.stack([smooth_gaussian(p, vote_sigma, "constant") for p in stack])
    spread = 2.0 * math.pi * vote_sigma**2 if vote_sigma > 0 else 1.0
    scores = np.stack([p * spread / (2.0 * math.pi * r) for p, r in zip(stack, radii, strict=True)])
    k = scores.argmax(axis=0)
    yy, xx = np.mgrid[0:48, 0:width]
    np.testing.assert_array_equal(best, scores.max(axis=0))
    np.testing.assert_array_equal(k_best, k)
    np.testing.assert_array_equal(below, scores[np.maximum(k - 1, 0), yy, xx])
    np.testing.assert_array_equal(above, scores[np.minimum(k + 1, len(radii) - 1), yy, xx])
    peak = np.unravel_index(best[:, :64].argmax(), (48, 64))  # the disc's centre, 22.6 30.3
    assert abs(peak[0] - 22.6) < 1.5 and abs(peak[1] - 30.3) < 1.5
    if width == 300:
        other = np.unravel_index(best[:, 200:].argmax(), (48, 100))  # row 30.2, column 270.5
        assert abs(other[0] - 30.2) < 1.5 and abs(other[1] + 200 - 270.5) < 1.5


@pytest.mark.parametrize("width", [7, 30])
def test_votes_extended_in_place_equal_the_wrapped_copy(width):
    """``vote_lines`` with ``pad`` rows equals the accumulator without them wrapped by
    ``np.concatenate`` (θ + π is θ with ρ negated), as ``hough.lines`` extended it before."""
    rng = np.random.default_rng(7)
    x, y, weights = rng.uniform(0, 40, 300), rng.uniform(0, 30, 300), rng.uniform(0, 2, 300)
    first = rng.integers(0, 30, 300)
    table = np.arange(30) * (math.pi / 30)
    args = (x, y, weights, first, width, np.cos(table) / 0.7, np.sin(table) / 0.7, -75.0, 150)
    plain = vote_lines(*args, 0)
    for pad in (1, 9, 30):
        wrapped = np.concatenate([plain[-pad:, ::-1], plain, plain[:pad, ::-1]], axis=0)
        np.testing.assert_array_equal(vote_lines(*args, pad), wrapped)
    assert plain.sum() > 0


def test_peak_offsets_equal_the_quadratic_fit_they_replace():
    from graphvision_plugins.hough._kernels import peak_offsets
    from graphvision_plugins.hough._lines import _quadratic_solve
    from graphvision_plugins.hough._peaks import quadratic_peak_2d

    rng = np.random.default_rng(2)
    array = ndimage.gaussian_filter(rng.random((40, 60)), 1.5)
    array[10:13, 20:23] = 0.5  # a flat top: no maximum, the parabolas' fallback
    rows, cols = np.meshgrid(np.arange(1, 39), np.arange(1, 59), indexing="ij")
    rows, cols = rows.ravel(), cols.ravel()
    expected = quadratic_peak_2d(array, rows, cols)
    found = peak_offsets(array, rows, cols, _quadratic_solve())
    np.testing.assert_allclose(found, expected, rtol=0, atol=1e-12)
    assert (np.abs(expected) == 0.5).any() and (np.abs(expected) < 0.5).any()


def test_points_by_row_and_column_equal_lexsort():
    from graphvision_plugins.hough._kernels import points_by_row_and_column

    rng = np.random.default_rng(4)
    y, x = (v.astype(np.float64) for v in np.nonzero(rng.random((30, 40)) < 0.2))
    shuffled = rng.permutation(len(x))
    x, y = x[shuffled], y[shuffled]
    rows, by_row, keys, columns, by_column, column_keys = points_by_row_and_column(x, y, 30, 40)
    np.testing.assert_array_equal(by_row, np.lexsort((x, y)))
    np.testing.assert_array_equal(by_column, np.lexsort((y, x)))
    np.testing.assert_array_equal(rows, np.searchsorted(y[by_row], np.arange(31) - 0.5))
    np.testing.assert_array_equal(columns, np.searchsorted(x[by_column], np.arange(41) - 0.5))
    np.testing.assert_array_equal(keys, x[by_row])
    np.testing.assert_array_equal(column_keys, y[by_column])


@pytest.mark.parametrize("width", [5, 24])
def test_votes_equal_np_add_at_in_the_points_order(width):
    """Every point's two ρ shares, summed into each cell in the points' order (np.add.at
    applies them one by one): the kernel's two-pass rows (positions, then votes) change no
    bit; ``width`` 24 of 24 bins is the all-θ path."""
    rng = np.random.default_rng(11)
    x, y = rng.integers(0, 40, 400).astype(float), rng.integers(0, 30, 400).astype(float)
    weights, first = rng.uniform(0, 2, 400), rng.integers(0, 24, 400)
    table = np.arange(24) * (math.pi / 24)
    cos, sin, rho0, n_rho = np.cos(table) / 0.7, np.sin(table) / 0.7, -73.0, 147
    point = np.repeat(np.arange(400), width)  # point-major: each cell's shares in order
    t = (np.repeat(first, width) + np.tile(np.arange(width), 400)) % 24
    position = x[point] * cos[t] + y[point] * sin[t] - rho0
    lower = np.floor(position)
    frac = position - lower
    cells = t[:, None] * n_rho + lower.astype(int)[:, None] + [0, 1]  # lower, upper share
    shares = weights[point][:, None] * np.column_stack([1.0 - frac, frac])
    expected = np.zeros(24 * n_rho)
    np.add.at(expected, cells.ravel(), shares.ravel())
    expected = expected.reshape(24, n_rho)
    np.testing.assert_array_equal(
        vote_lines(x, y, weights, first, width, cos, sin, rho0, n_rho, 0), expected
    )
