"""The compiled helpers of board corners equal the NumPy / SciPy calls they replace:
``np.gradient``, the saddle response and its peaks by ``maximum_filter``, bilinear samples
by ``map_coordinates(order=1)``, and the grid's homography by the normalised DLT."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from graphvision_plugins.camera._corner_kernels import (
    gradient,
    saddle_peaks,
    saddle_response,
    sample,
)
from graphvision_plugins.camera._grid_kernels import grid_homography
from graphvision_plugins.geometry import estimate_homography


@pytest.mark.parametrize("shape", [(37, 53), (2, 2), (2, 5), (6, 2), (3, 3)])
def test_gradient_and_saddle_response_equal_numpy_to_the_bit(shape):
    f = np.random.default_rng(0).random(shape)
    f[0, 0] = 1e-310  # subnormal: the product by 0.5 is the division by 2 there too
    gy, gx = gradient(f)
    ny, nx = np.gradient(f)
    np.testing.assert_array_equal(gy, ny)
    np.testing.assert_array_equal(gx, nx)
    iyy, iyx = np.gradient(ny)
    ixy, ixx = np.gradient(nx)
    np.testing.assert_array_equal(saddle_response(f), -(ixx * iyy - ixy * iyx))


def test_saddle_peaks_equal_maximum_filter_away_from_the_border():
    rng = np.random.default_rng(1)
    response = np.round(rng.standard_normal((60, 70)) * 4) / 4  # ties count as peaks
    for radius in (2, 4):
        peaks = (response == ndimage.maximum_filter(response, 2 * radius + 1)) & (response > 0)
        border = radius + 1
        peaks[:border], peaks[-border:], peaks[:, :border], peaks[:, -border:] = (False,) * 4
        rows, cols = saddle_peaks(response, radius)
        np.testing.assert_array_equal(np.column_stack([rows, cols]), np.argwhere(peaks))


def test_sample_equals_map_coordinates_order_1():
    rng = np.random.default_rng(2)
    values = rng.random((20, 30))
    xs = np.concatenate([rng.uniform(-2, 31, 500), [0.0, 29.0, 29.0, -1e-9, 29.000001]])
    ys = np.concatenate([rng.uniform(-2, 21, 500), [0.0, 19.0, 0.5, 3.0, 5.0]])
    expected = ndimage.map_coordinates(values, [ys, xs], order=1)
    np.testing.assert_allclose(sample(values, xs, ys), expected, rtol=0, atol=1e-12)


def test_grid_homography_equals_the_normalised_dlt():
    j, i = np.mgrid[0:3, 0:7]
    src = np.column_stack([i.ravel(), j.ravel()]).astype(np.float64)
    h_true = np.array([[30.0, 2.0, 100.0], [-1.5, 28.0, 80.0], [1e-3, -2e-3, 1.0]])
    mapped = np.column_stack([src, np.ones(len(src))]) @ h_true.T
    dst = mapped[:, :2] / mapped[:, 2:]
    dst += np.random.default_rng(3).normal(0, 0.2, dst.shape)
    ok, h = grid_homography(src, dst)
    assert ok
    np.testing.assert_allclose(h, estimate_homography(src, dst), rtol=1e-8, atol=1e-10)
    assert not grid_homography(src[:7], dst[:7])[0]  # one row: collinear, degenerate


def _forstner_per_sample(gx, gy, corners, radius, iterations):
    """The iteration as it was before the window's rows and columns were shared: every
    sample of every corner through ``sample`` (one bilinear sample each), sums in the
    window's row-major order, all corners until none moves by 1e-4 px."""
    half = int(np.ceil(radius.max()))
    offsets = np.arange(-half, half + 1, dtype=np.float64)
    oy, ox = (a.ravel() for a in np.meshgrid(offsets, offsets, indexing="ij"))
    r = radius[:, None]
    weight = np.exp(-(ox**2 + oy**2) / (2 * r**2)) * ((np.abs(ox) <= r) & (np.abs(oy) <= r))
    weight[:, (ox == 0) & (oy == 0)] = 0.0
    q = corners.copy()
    for _ in range(iterations):
        new = q.copy()
        for i, (qx, qy) in enumerate(q):
            px, py = qx + ox, qy + oy
            sxs, sys_ = sample(gx, px, py), sample(gy, px, py)
            axx = axy = ayy = bx = by = 0.0
            for k in np.flatnonzero(weight[i]):
                w, sx, sy = weight[i, k], sxs[k], sys_[k]
                axx += w * sx * sx
                axy += w * sx * sy
                ayy += w * sy * sy
                bx += w * (sx * sx * px[k] + sx * sy * py[k])
                by += w * (sx * sy * px[k] + sy * sy * py[k])
            det = axx * ayy - axy * axy
            if det > 1e-12:
                new[i] = ((ayy * bx - axy * by) / det, (axx * by - axy * bx) / det)
        shift = np.abs(new - q).max()
        q = new
        if shift < 1e-4:
            break
    return q


def test_forstner_equals_the_per_sample_iteration():
    """To rounding: a window inside the image sums its rows in vectorised (reassociated)
    loops, one crossing the border sample by sample as before."""
    from graphvision_plugins.camera._corners import _refine

    y, x = np.mgrid[0:40, 0:50].astype(np.float64)
    smooth = np.tanh(x - 20.3) * np.tanh(y - 17.6) + 0.01 * np.sin(3 * x + y)  # an X-junction
    gy, gx = gradient(smooth)
    # one window inside, one crossing the border (its samples outside count zero)
    corners = np.array([[21.0, 17.0], [2.5, 37.2], [30.4, 18.9]])
    radius = np.array([4.0, 5.0, 4.0])  # two corners share their weights
    expected = _forstner_per_sample(gx, gy, corners, radius, 8)
    refined = _refine(smooth, corners, radius, 8)
    np.testing.assert_allclose(refined, expected, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(refined[1], expected[1])  # the border's: unchanged
    assert np.abs(expected[0] - (20.3, 17.6)).max() < 0.05


def test_rot90_and_grown_grid_equal_the_numpy_loop():
    from graphvision_plugins import synthetic
    from graphvision_plugins.camera._corners import saddle_candidates
    from graphvision_plugins.camera._grid import _ANGLES, MAX_ASYMMETRY, TOLERANCE, _Grower, _Photo
    from graphvision_plugins.camera._grid_kernels import _rot90, next_row

    grid = np.arange(12).reshape(3, 4)
    for turn in range(4):
        np.testing.assert_array_equal(_rot90(grid, turn), np.rot90(grid, turn))
    view = synthetic.board_views(views=1, width=240, height=180, focal=300.0, seed=4).views[0]
    photo = _Photo(np.asarray(view, np.float64))
    candidates = saddle_candidates(view, 6 * 54 + 50, 2.0)
    grower = _Grower(candidates, photo, 9, 6)
    cell = next(c for s in range(8) if (c := grower._first_cell(s)) is not None)
    angles = (np.cos(_ANGLES), np.sin(_ANGLES), MAX_ASYMMETRY)
    expected = cell  # the loop _Grower._grow was: rows added by np.rot90 and np.vstack
    while True:
        best = None
        for turn in range(4):
            turned = np.ascontiguousarray(np.rot90(expected, turn), dtype=np.int64)
            if not any(turned.shape[0] + 1 <= a and turned.shape[1] <= b for a, b in grower.shapes):
                continue
            ok, fit, row = next_row(candidates, turned, photo.smooth, TOLERANCE, *angles)
            if ok and (best is None or fit < best[0]):
                best = (fit, turn, row)
        if best is None:
            break
        turned = np.vstack([np.rot90(expected, best[1]), best[2][None]])
        expected = np.rot90(turned, -best[1])
    assert expected.size == 54
    np.testing.assert_array_equal(grower._grow(cell), expected)


def test_coarse_candidates_lead_to_the_corners_the_full_resolution_ones_give():
    """Replaces the σ = 2 saddles at full resolution: half the resolution finds every true
    corner within 1 px as they do, and the board refined from its grid is theirs."""
    from scipy.spatial.distance import cdist

    from graphvision_plugins import synthetic
    from graphvision_plugins.camera._corners import (
        _oriented,
        _refine,
        coarse_saddle_candidates,
        find_board,
        grid_spacing,
        saddle_candidates,
    )
    from graphvision_plugins.camera._grid import _Grower, _Photo

    boards = synthetic.board_views(views=1, width=240, height=180, focal=300.0, seed=4)
    view, truth = np.asarray(boards.views[0], np.float64), boards.corners[0]
    photo = _Photo(view)
    full = saddle_candidates(view, 6 * 54 + 50, 2.0)
    coarse = coarse_saddle_candidates(photo.smooth, 6 * 54 + 50, 2.0)
    assert cdist(truth, full).min(axis=1).max() < 1.0
    assert cdist(truth, coarse).min(axis=1).max() < 1.0
    corners = _oriented(full[_Grower(full, photo, 9, 6).grid()], photo.smooth)
    radius = np.clip(0.45 * grid_spacing(corners, 9, 6), 3.0, 15)
    expected = _refine(photo.smooth, corners, radius, 20)  # the full-resolution path
    found = find_board(view, 9, 6, sigma=2.0)
    # the iteration stops when no corner moves by 1e-4 px: from other starts it stops
    # up to a few hundredths of a pixel apart, as near to the truth
    np.testing.assert_allclose(found, expected, atol=0.03)
    error, reference = (np.linalg.norm(c - truth, axis=1).mean() for c in (found, expected))
    assert error < reference + 0.002


def test_gradient_samples_equal_samples_of_the_gradient_images_to_the_bit():
    """Replaces the two full-size gradient images the board's sides were sampled in."""
    from graphvision_plugins.camera._corner_kernels import gradient_samples

    rng = np.random.default_rng(6)
    smooth = rng.random((30, 40))
    xs = np.concatenate([rng.uniform(-1, 40, 200), [0.0, 39.0, 20.0]])
    ys = np.concatenate([rng.uniform(-1, 30, 200), [0.0, 29.0, 29.0]])  # borders too
    gy, gx = gradient(smooth)
    found_x, found_y = gradient_samples(smooth, xs, ys)
    np.testing.assert_array_equal(found_x, sample(gx, xs, ys))
    np.testing.assert_array_equal(found_y, sample(gy, xs, ys))


@pytest.mark.parametrize("shape", [(48, 64), (9, 9), (5, 7), (1, 3)])
def test_smooth_unit_of_float32_equals_the_float64_copy_smoothed_to_the_bit(shape):
    """The σ = 1 image of a float32 view, without the float64 copy it was smoothed from."""
    from graphvision_plugins.camera._corner_kernels import smooth_unit
    from graphvision_plugins.shared.separable import smooth_gaussian

    rng = np.random.default_rng(7)
    image = rng.random(shape).astype(np.float32)
    image.flat[0] = np.float32(1e-40)  # a subnormal widens exactly too
    expected = smooth_gaussian(image.astype(np.float64), 1.0)
    np.testing.assert_array_equal(smooth_unit(image), expected)
    np.testing.assert_array_equal(
        smooth_unit(image[:, ::-1]), smooth_gaussian(image[:, ::-1].astype(np.float64), 1.0)
    )  # not contiguous
    np.testing.assert_array_equal(smooth_unit(image.astype(np.float64)), expected)


def test_cell_means_equal_map_coordinates_at_the_cells_centres():
    """The labellings' first and last cells, sampled in one call (was one map_coordinates
    per cell)."""
    from graphvision_plugins.camera._corners import _cell_means

    rng = np.random.default_rng(8)
    image = rng.random((30, 40))
    corners = rng.uniform(0, [39, 29], (3, 4 * 3, 2))  # 3 labellings of 4 × 3 corners
    idx = [1 * 4 + 2, 1 * 4 + 3, 2 * 4 + 2, 2 * 4 + 3]
    centres = corners[:, idx].mean(axis=1)
    expected = ndimage.map_coordinates(image, [centres[:, 1], centres[:, 0]], order=1)
    np.testing.assert_allclose(_cell_means(image, corners, 4, 2, 1), expected, rtol=0, atol=1e-12)


def test_parabola_peaks_equal_the_numpy_arithmetic_they_replace_to_the_bit():
    """The coarse saddles' sub-pixel step, compiled: the same bits as the array form it
    replaced, flat and upward curvatures (−1e-300) and offsets clipped at ±0.5 included."""
    from graphvision_plugins.camera._corner_kernels import parabola_peaks

    rng = np.random.default_rng(9)
    response = np.round(rng.standard_normal((30, 40)) * 4) / 4  # flat triples too
    rows, cols = rng.integers(1, 29, 300), rng.integers(1, 39, 300)
    offsets = []
    for step in ((1, 0), (0, 1)):  # the array form, as coarse_saddle_candidates had it
        before = response[rows - step[0], cols - step[1]]
        centre, after = response[rows, cols], response[rows + step[0], cols + step[1]]
        curvature = np.minimum(before - 2 * centre + after, -1e-300)
        offsets.append(np.clip((before - after) / (2 * curvature), -0.5, 0.5))
    expected = np.column_stack([2.0 * (cols + offsets[1]), 2.0 * (rows + offsets[0])])
    assert (np.abs(expected - 2 * np.column_stack([cols, rows])) == 1.0).any()  # clipped ones
    np.testing.assert_array_equal(parabola_peaks(response, rows, cols), expected)
