r"""Checkerboard inner corners: saddle detection, grid labelling, sub-pixel refinement.

1. **Saddles.** The inner corners of a checkerboard are X-junctions, where the
   Gaussian-smoothed intensity is a saddle: the Hessian determinant
   :math:`I_{xx} I_{yy} - I_{xy}^2` is strongly negative. Candidates are the
   local maxima of :math:`-\det H`; the ``columns·rows`` strongest are kept.
2. **Labelling.** Four extreme candidates (the largest quadrilateral on the
   convex hull) are matched to the grid's corners in each of the 8 ways; a
   homography from grid to image predicts every corner, each prediction
   takes its nearest candidate and the homography is refitted on all of them.
   A labelling is accepted when every grid point has its own candidate. The
   order is then fixed: x along ``columns``, y along ``rows``, handedness
   of a board seen from its front (image cross product of the axes > 0), and
   the first square (between corners (0,0) and (1,1)) dark.
3. **Sub-pixel refinement.** For a corner q and every pixel p around it, the
   gradient :math:`g_p` is orthogonal to :math:`p - q` (p lies on an edge
   through q, or in a flat region where :math:`g_p = 0`), so q solves
   :math:`\sum_p w_p g_p g_p^T\, q = \sum_p w_p g_p g_p^T\, p` (Förstner),
   iterated with the window re-centred at q, gradients interpolated. The
   window scales with the board: 0.45 of the distance to the nearest corner.

References
----------
.. [1] W. Förstner, E. Gülch, "A fast operator for detection and precise location of
   distinct points, corners and centres of circular features", ISPRS 1987.
.. [2] A. Geiger et al., "Automatic camera and range sensor calibration using a single
   shot", ICRA 2012 (saddle-based checkerboard corners).
"""

from __future__ import annotations

from itertools import combinations
from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Array, node

from ..geometry import apply_homography, normalising_transform
from ..shared.params import Positive

__all__ = [
    "BoardCorners",
    "board_corners",
    "find_board",
    "grid_spacing",
    "refine_corners",
    "saddle_candidates",
]


def saddle_candidates(image: np.ndarray, count: int, sigma: float) -> np.ndarray:
    """The ``count`` strongest local maxima of :math:`-\\det H` (at scale ``sigma``), ``N×2``."""
    from scipy import ndimage

    from ..shared.separable import smooth_gaussian

    smooth = smooth_gaussian(image.astype(np.float64), sigma)
    iy, ix = np.gradient(smooth)
    iyy, iyx = np.gradient(iy)
    ixy, ixx = np.gradient(ix)
    response = -(ixx * iyy - ixy * iyx)
    radius = max(2, int(round(2 * sigma)))
    peaks = (response == ndimage.maximum_filter(response, 2 * radius + 1)) & (response > 0)
    border = radius + 1
    peaks[:border], peaks[-border:], peaks[:, :border], peaks[:, -border:] = (False,) * 4
    rows, cols = np.nonzero(peaks)
    strength = response[rows, cols]
    order = np.argsort(strength)[::-1][:count]
    return np.column_stack([cols[order], rows[order]]).astype(np.float64)


def _largest_quadrilateral(points: np.ndarray) -> np.ndarray:
    """The 4 hull vertices enclosing the largest area, in hull (counter-clockwise) order."""
    from scipy.spatial import ConvexHull

    hull = points[ConvexHull(points).vertices]
    best, best_area = hull[:4], -1.0
    for quad in combinations(range(len(hull)), 4):
        q = hull[list(quad)]
        x, y = q[:, 0], q[:, 1]
        area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
        if area > best_area:
            best, best_area = q, area
    return best


def _grid_homography(src: np.ndarray, dst: np.ndarray) -> np.ndarray | None:
    """Normalised DLT for the grid labelling, solved by the 9×9 normal equations.

    The same estimate as :func:`~graphvision_plugins.geometry.estimate_homography`
    (the smallest eigenvector of :math:`A^T A` is the smallest right singular
    vector of A) without the full SVD of the 2N×9 system, which this loop
    runs dozens of times per view.
    """
    t_src, t_dst = normalising_transform(src), normalising_transform(dst)
    a = apply_homography(t_src, src)
    b = apply_homography(t_dst, dst)
    xs = np.column_stack([a, np.ones(len(a))])
    zeros = np.zeros((len(a), 3))
    rows = np.vstack(
        [np.hstack([-xs, zeros, b[:, :1] * xs]), np.hstack([zeros, -xs, b[:, 1:] * xs])]
    )
    values, vectors = np.linalg.eigh(rows.T @ rows)
    if values[1] < 1e-12 * values[-1]:
        return None
    h = np.linalg.inv(t_dst) @ vectors[:, 0].reshape(3, 3) @ t_src
    return h / h[2, 2] if abs(h[2, 2]) > 1e-15 else None


def _label(
    candidates: np.ndarray, grid: np.ndarray, quad: np.ndarray, extremes: np.ndarray
) -> np.ndarray | None:
    """Candidates in grid order for one quad-to-grid correspondence, or None."""
    from scipy.spatial import cKDTree

    tree = cKDTree(candidates)
    h = _grid_homography(extremes, quad)
    for _ in range(3):
        if h is None:
            return None
        predicted = apply_homography(h, grid)
        if not np.isfinite(predicted).all():
            return None
        distance, index = tree.query(predicted)
        spacing = np.median(np.linalg.norm(np.diff(predicted, axis=0), axis=1))
        if len(set(index.tolist())) != len(grid) or distance.max() > 0.35 * spacing:
            return None
        h = _grid_homography(grid, candidates[index])
    return candidates[index]


def _cell_mean(image: np.ndarray, corners: np.ndarray, columns: int, a: int, b: int) -> float:
    """Mean intensity at the centre of the cell between corners (a, b) and (a+1, b+1)."""
    from scipy import ndimage

    idx = [b * columns + a, b * columns + a + 1, (b + 1) * columns + a, (b + 1) * columns + a + 1]
    x, y = corners[idx].mean(axis=0)
    return float(ndimage.map_coordinates(image, [[y], [x]], order=1)[0])


def find_board(
    image: np.ndarray, columns: int, rows: int, sigma: float = 2.0, max_window: int = 15
) -> np.ndarray | None:
    """The ``rows·columns`` inner corners in fixed order (module docstring), or None."""
    from scipy.spatial import QhullError

    from ..shared.separable import smooth_gaussian

    count = columns * rows
    candidates = saddle_candidates(image, count, sigma)
    if len(candidates) < count:
        return None
    try:
        quad = _largest_quadrilateral(candidates)
    except QhullError:
        return None
    j, i = np.mgrid[0:rows, 0:columns]
    grid = np.column_stack([i.ravel(), j.ravel()]).astype(np.float64)
    corners4 = np.array([[0, 0], [columns - 1, 0], [columns - 1, rows - 1], [0, rows - 1]], float)
    accepted = []
    for start in range(4):
        for step in (1, -1):
            order = [(start + step * k) % 4 for k in range(4)]
            labelled = _label(candidates, grid, quad[order], corners4)
            if labelled is None:
                continue
            ex = labelled[1] - labelled[0]
            ey = labelled[columns] - labelled[0]
            if ex[0] * ey[1] - ex[1] * ey[0] > 0:
                accepted.append(labelled)
    if not accepted:
        return None
    smooth = smooth_gaussian(image.astype(np.float64), 1.0)
    # a 180° turn also passes: keep the labelling whose first square is dark
    darkness = [
        _cell_mean(smooth, c, columns, 0, 0) - _cell_mean(smooth, c, columns, columns - 2, rows - 2)
        for c in accepted
    ]
    best = accepted[int(np.argmin(darkness))]
    # the window grows with the squares (0.45 of the spacing), within [3, max_window]
    radius = np.clip(0.45 * grid_spacing(best, columns, rows), 3.0, max_window)
    return refine_corners(image, best, radius)


def grid_spacing(corners: np.ndarray, columns: int, rows: int) -> np.ndarray:
    """Distance from each corner of a labelled grid to its nearest grid neighbour."""
    grid = corners.reshape(rows, columns, 2)
    nearest = np.full((rows, columns), np.inf)
    across = np.linalg.norm(np.diff(grid, axis=1), axis=2)
    down = np.linalg.norm(np.diff(grid, axis=0), axis=2)
    nearest[:, :-1] = np.minimum(nearest[:, :-1], across)
    nearest[:, 1:] = np.minimum(nearest[:, 1:], across)
    nearest[:-1] = np.minimum(nearest[:-1], down)
    nearest[1:] = np.minimum(nearest[1:], down)
    return nearest.ravel()


def refine_corners(
    image: np.ndarray, corners: np.ndarray, radius: np.ndarray, iterations: int = 20
) -> np.ndarray:
    """Förstner's sub-pixel corner (module docstring), all corners at once.

    Corner i uses a square window of half size ``radius[i]`` with Gaussian
    weights of σ = ``radius[i]``, on the gradient of the image smoothed by σ = 1.
    """
    from scipy import ndimage

    from ..shared.separable import smooth_gaussian

    smooth = smooth_gaussian(image.astype(np.float64), 1.0)
    gy, gx = np.gradient(smooth)
    half = int(np.ceil(radius.max()))
    offsets = np.arange(-half, half + 1, dtype=np.float64)
    grid_y, grid_x = np.meshgrid(offsets, offsets, indexing="ij")
    ox, oy = grid_x.ravel(), grid_y.ravel()
    r = radius[:, None]
    inside = (np.abs(ox) <= r) & (np.abs(oy) <= r)
    weight = np.exp(-(ox**2 + oy**2) / (2 * r**2)) * inside
    weight[:, (ox == 0) & (oy == 0)] = 0.0  # the centre's gradient carries no position
    q = corners.astype(np.float64).copy()
    for _ in range(iterations):
        px = q[:, :1] + ox  # N×P sample positions
        py = q[:, 1:] + oy
        sx = ndimage.map_coordinates(gx, [py.ravel(), px.ravel()], order=1).reshape(px.shape)
        sy = ndimage.map_coordinates(gy, [py.ravel(), px.ravel()], order=1).reshape(px.shape)
        axx = (weight * sx * sx).sum(axis=1)
        axy = (weight * sx * sy).sum(axis=1)
        ayy = (weight * sy * sy).sum(axis=1)
        bx = (weight * (sx * sx * px + sx * sy * py)).sum(axis=1)
        by = (weight * (sx * sy * px + sy * sy * py)).sum(axis=1)
        det = axx * ayy - axy * axy
        ok = det > 1e-12
        new = q.copy()
        new[ok, 0] = (ayy[ok] * bx[ok] - axy[ok] * by[ok]) / det[ok]
        new[ok, 1] = (axx[ok] * by[ok] - axy[ok] * bx[ok]) / det[ok]
        shift = np.abs(new - q).max()
        q = new
        if shift < 1e-4:
            break
    return q


class BoardCorners(NamedTuple):
    corners: Array
    found: Array


@node("camera.board_corners", version=1)
def board_corners(
    views: Array,
    *,
    columns: Annotated[int, Field(ge=2, le=40)] = 9,
    rows: Annotated[int, Field(ge=2, le=40)] = 6,
    sigma: Positive = 2.0,
    max_window: Annotated[int, Field(ge=3, le=50)] = 15,
) -> BoardCorners:
    """Inner corners of a checkerboard in each view, sub-pixel, in a fixed order.

    Saddle points of the smoothed image, labelled by a grid homography and
    refined by Förstner's gradient-orthogonality estimate (module
    docstring). Corners are listed row by row, x fastest, starting at the
    corner whose first square is dark, the same order as
    ``synthetic.board_views``' ``object_points``.

    Parameters
    ----------
    views : Array
        One gray image H×W, or a stack N×H×W, of floats in [0, 1].
    columns, rows : int
        Inner corners along the board's x and y.
    sigma : float
        Scale of the saddle detector, pixels (about a sixth of a square).
    max_window : int
        Largest half size of the refinement window, pixels (each corner's
        window is 0.45 of its distance to the nearest corner, at least 3).

    Returns
    -------
    corners : (N, rows·columns, 2) float64, NaN for a view where no board was found
    found : (N,) bool
    """
    stack = views[None] if views.ndim == 2 else views
    if stack.ndim != 3:
        raise ValueError(f"views must be H×W or N×H×W gray images, got shape {views.shape}")
    corners = np.full((len(stack), columns * rows, 2), np.nan)
    for k, image in enumerate(stack):
        found = find_board(np.asarray(image, np.float64), columns, rows, sigma, max_window)
        if found is not None:
            corners[k] = found
    return BoardCorners(corners, np.isfinite(corners).all(axis=(1, 2)))
