r"""Checkerboard inner corners: saddle detection, grid growing, sub-pixel refinement.

1. **Saddles.** The inner corners of a checkerboard are X-junctions, where the
   Gaussian-smoothed intensity is a saddle: the Hessian determinant
   :math:`I_{xx} I_{yy} - I_{xy}^2` is strongly negative. Candidates are the
   local maxima of :math:`-\det H`, strongest first, several times more than
   the board has corners: a corner blurred wider than σ splits into two maxima,
   the response has weaker lobes along a corner's diagonals, and the board's
   outline (where its squares meet the margin) and the background add their own.
2. **Growing the grid.** From one of the strongest candidates, a first cell: two
   neighbours in different directions and the candidate that closes the
   parallelogram, accepted when every side of the cell crosses an edge (the
   gradient at its midpoint is at least a tenth of the local contrast: a cell
   built on a diagonal has a flat square there) and every corner is an
   X-junction (point symmetric: :math:`|I(p + \rho u) - I(p - \rho u)|` below
   half the contrast in 8 directions, where an L or T junction of the outline
   reaches the full contrast). The grid then grows by whole rows or columns:
   a homography fitted to the 3 nearest rows predicts the next one, each
   prediction takes the strongest candidate within 0.3 of the spacing, and the
   row is added when all its corners are found, distinct and X-junctions (the
   extension that fits best first), as long as the grid fits in the board.
   The board is found when the grid is ``columns × rows``. The order is then
   fixed: x along ``columns``, y along ``rows``, handedness of a board seen
   from its front (image cross product of the axes > 0), and the first square
   (between corners (0,0) and (1,1)) dark.
3. **Scale.** With ``sigma=None`` the detector tries σ = 2 px, then larger
   steps of √2 up to a sixth of the largest square the image can hold, then
   1.4 and 1 px: the first scale at which the grid is found; from σ = 2 on, the
   response is computed at half the resolution (``coarse_saddle_candidates``:
   the candidates only seed the grid and the refinement). A corner blurred
   over more than σ has a flat-topped response that noise splits; a sixth of
   the square keeps neighbouring corners apart.
4. **Sub-pixel refinement.** For a corner q and every pixel p around it, the
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
   shot", ICRA 2012 (saddle-based checkerboard corners, growing the grid).
"""

from __future__ import annotations

import functools
import math
import warnings
from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Array, Conformance, node

from ..shared.params import Positive
from ._grid import _Grower, _Photo

__all__ = [
    "BoardCorners",
    "board_corners",
    "coarse_saddle_candidates",
    "find_board",
    "grid_spacing",
    "refine_corners",
    "saddle_candidates",
    "sigma_ladder",
]


def saddle_candidates(image: np.ndarray, count: int, sigma: float) -> np.ndarray:
    """The ``count`` strongest local maxima of :math:`-\\det H` (at scale ``sigma``), ``N×2``,
    strongest first."""
    from ..shared.separable import smooth_gaussian
    from ._corner_kernels import saddle_peaks, saddle_response

    smooth = smooth_gaussian(np.asarray(image, np.float64), sigma)
    response = saddle_response(np.ascontiguousarray(smooth))
    rows, cols = saddle_peaks(response, max(2, int(round(2 * sigma))))
    strength = response[rows, cols]
    order = np.argsort(strength)[::-1][:count]
    return np.column_stack([cols[order], rows[order]]).astype(np.float64)


def coarse_saddle_candidates(smooth: np.ndarray, count: int, sigma: float) -> np.ndarray:
    """:func:`saddle_candidates` at half the resolution, for ``sigma`` at least 2, from the
    image smoothed by σ = 1 (``smooth``): its even pixels (σ = ½ of theirs) smoothed on to
    σ/2, the peaks of that response within ``sigma`` half pixels, each placed by a parabola
    through its 3 samples along each axis; in full-resolution pixels, strongest first."""
    from ._corner_kernels import parabola_peaks, saddle_peaks, saddle_response, smooth_reflect

    half = smooth_reflect(smooth[::2, ::2], math.sqrt((sigma / 2) ** 2 - 0.25))
    response = saddle_response(half)
    rows, cols = saddle_peaks(response, max(1, int(round(sigma))))
    order = np.argsort(response[rows, cols])[::-1][:count]
    return parabola_peaks(response, rows[order], cols[order])


def sigma_ladder(shape: tuple[int, ...], columns: int, rows: int) -> list[float]:
    """The scales tried with ``sigma=None`` (module docstring): 2 px, then ×√2 while σ is
    at most a sixth of the largest square (the image's smaller side over the squares
    along the board's longer side), then 1.4 and 1 px."""
    largest_square = min(shape[:2]) / (max(columns, rows) + 1)
    ladder = [2.0]
    while ladder[-1] * math.sqrt(2) <= largest_square / 6:
        ladder.append(ladder[-1] * math.sqrt(2))
    return [*ladder, 1.4, 1.0]


def _cell_means(image: np.ndarray, corners: np.ndarray, columns: int, a: int, b: int) -> np.ndarray:
    """Intensity (interpolated linearly) at the centre of the cell between corners (a, b)
    and (a+1, b+1) of each labelling in ``corners`` (``labellings × rows·columns × 2``)."""
    from ._corner_kernels import sample

    idx = [b * columns + a, b * columns + a + 1, (b + 1) * columns + a, (b + 1) * columns + a + 1]
    centres = corners[:, idx].mean(axis=1)
    return sample(image, np.ascontiguousarray(centres[:, 0]), np.ascontiguousarray(centres[:, 1]))


def _oriented(grid: np.ndarray, smooth: np.ndarray) -> np.ndarray | None:
    """The grid's corners (``rows × columns × 2``) in the fixed order (module docstring)."""
    rows, columns = grid.shape[:2]
    variants = [grid, grid[::-1], grid[:, ::-1], grid[::-1, ::-1]]
    if rows == columns:
        variants += [v.transpose(1, 0, 2) for v in variants]
    accepted = []
    for v in variants:
        ex, ey = v[0, 1] - v[0, 0], v[1, 0] - v[0, 0]
        if ex[0] * ey[1] - ex[1] * ey[0] > 0:
            accepted.append(v.reshape(-1, 2))
    if not accepted:
        return None
    # a 180° turn also passes: keep the labelling whose first square is dark
    labellings = np.stack(accepted)
    darkness = _cell_means(smooth, labellings, columns, 0, 0) - _cell_means(
        smooth, labellings, columns, columns - 2, rows - 2
    )
    return accepted[int(np.argmin(darkness))]


def find_board(
    image: np.ndarray,
    columns: int,
    rows: int,
    sigma: float | None = None,
    max_window: int = 15,
) -> np.ndarray | None:
    """The ``rows·columns`` inner corners in fixed order (module docstring), or None.

    ``sigma`` None tries the scales of :func:`sigma_ladder` in turn.
    """
    image = np.asarray(image)  # float32 stays float32: _Photo widens it as it reads it
    photo = _Photo(image)
    count = columns * rows
    scales = sigma_ladder(image.shape, columns, rows) if sigma is None else [sigma]
    for scale in scales:
        if scale >= 2:  # a quarter of the pixels: the refinement places the corners
            candidates = coarse_saddle_candidates(photo.smooth, 6 * count + 50, scale)
        else:
            candidates = saddle_candidates(image, 6 * count + 50, scale)
        if len(candidates) < count:
            continue
        grid = _Grower(candidates, photo, columns, rows).grid()
        if grid is None:
            continue
        best = _oriented(candidates[grid], photo.smooth)
        if best is None:
            continue
        # the window grows with the squares (0.45 of the spacing), within [3, max_window]
        radius = np.clip(0.45 * grid_spacing(best, columns, rows), 3.0, max_window)
        return _refine(photo.smooth, best, radius, 20)
    return None


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
    from ..shared.separable import smooth_gaussian

    smooth = np.ascontiguousarray(smooth_gaussian(image.astype(np.float64), 1.0))
    return _refine(smooth, corners, radius, iterations)


def _refine(
    smooth: np.ndarray, corners: np.ndarray, radius: np.ndarray, iterations: int
) -> np.ndarray:
    """:func:`refine_corners` on the image smoothed by σ = 1 (its gradient by
    ``np.gradient``, computed where the windows read it)."""
    from ._forstner_kernels import forstner

    half = int(np.ceil(radius.max()))
    radii, which = np.unique(radius, return_inverse=True)  # clipped: often one radius
    weight = _window_weights(half, radii.tobytes())
    q = np.ascontiguousarray(corners, dtype=np.float64)
    return forstner(smooth, q, half, weight, which.ravel().astype(np.int64), iterations)


@functools.lru_cache(maxsize=16)
def _window_weights(half: int, radii: bytes) -> np.ndarray:
    """The Gaussian weights (σ = the radius, 0 outside the square of that half size and at
    the centre) of the ``(2 half + 1)²`` window offsets, row-major, one row per radius
    (``radii``: the distinct radii's float64 bytes); made once per set of radii (the
    windows are clipped to ``max_window``: every view's set is often the same)."""
    offsets = np.arange(-half, half + 1, dtype=np.float64)
    grid_y, grid_x = np.meshgrid(offsets, offsets, indexing="ij")
    ox, oy = grid_x.ravel(), grid_y.ravel()
    r = np.frombuffer(radii, dtype=np.float64)[:, None]
    inside = (np.abs(ox) <= r) & (np.abs(oy) <= r)
    weight = np.exp(-(ox**2 + oy**2) / (2 * r**2)) * inside  # one row per radius
    weight[:, (ox == 0) & (oy == 0)] = 0.0  # the centre's gradient carries no position
    weight.flags.writeable = False
    return weight


class BoardCorners(NamedTuple):
    corners: Array
    found: Array


@node(
    "camera.board_corners",
    version=2,
    conformance=Conformance(
        "max_abs",
        0.15,
        note=(
            "OpenCV finds the board on the 8-bit image and refines every corner in one "
            "window (0.45 of the least corner spacing; sigma is the reference's); its "
            "corners are put in the reference's order (first square dark, board seen from "
            "its front), within 0.15 px of the reference's"
        ),
    ),
)
def board_corners(
    views: Array,
    *,
    columns: Annotated[int, Field(ge=2, le=40)] = 9,
    rows: Annotated[int, Field(ge=2, le=40)] = 6,
    sigma: Positive | None = None,
    max_window: Annotated[int, Field(ge=3, le=50)] = 15,
) -> BoardCorners:
    r"""Inner corners of a checkerboard in each view, sub-pixel, in a fixed order.

    Saddle points of the smoothed image (local maxima of
    :math:`-(I_{xx} I_{yy} - I_{xy}^2)`, several per corner kept), a grid grown
    from a first cell by rows and columns that a homography predicts, each
    corner checked to be an X-junction, and Förstner's gradient-orthogonality
    estimate :math:`q = (\sum_p w_p g_p g_p^T)^{-1} \sum_p w_p g_p g_p^T p`
    (module docstring). Corners are listed row by row, x fastest, starting at
    the corner whose first square is dark, the same order as
    ``synthetic.board_views``' ``object_points``. Views without a board are
    named in a warning.

    Parameters
    ----------
    views : Array
        One gray image H×W, or a stack N×H×W, of floats in [0, 1].
    columns, rows : int
        Inner corners along the board's x and y.
    sigma : float, optional
        Scale of the saddle detector, pixels (about a sixth of a square). None:
        2 px, then larger scales up to a sixth of the largest square the image
        can hold, then 1.4 and 1 px, until the board is found.
    max_window : int
        Largest half size of the refinement window, pixels (each corner's
        window is 0.45 of its distance to the nearest corner, at least 3).

    Returns
    -------
    corners : (N, rows·columns, 2) float64, NaN for a view where no board was found
    found : (N,) bool

    Warns
    -----
    UserWarning
        Naming the views where no board was found.

    References
    ----------
    .. [1] A. Geiger et al., "Automatic camera and range sensor calibration using a
       single shot", ICRA 2012.
    .. [2] W. Förstner, E. Gülch, "A fast operator for detection and precise location of
       distinct points, corners and centres of circular features", ISPRS 1987.
    """
    stack = views[None] if views.ndim == 2 else views
    if stack.ndim != 3:
        raise ValueError(f"views must be H×W or N×H×W gray images, got shape {views.shape}")
    corners = np.full((len(stack), columns * rows, 2), np.nan)
    for k, image in enumerate(stack):
        found = find_board(image, columns, rows, sigma, max_window)
        if found is not None:
            corners[k] = found
    found_views = np.isfinite(corners).all(axis=(1, 2))
    missing = np.flatnonzero(~found_views).tolist()
    if missing:
        warnings.warn(
            f"no board of {columns}×{rows} inner corners found in {len(missing)} of "
            f"{len(stack)} views: {missing} (their corners are NaN)",
            stacklevel=2,
        )
    return BoardCorners(corners, found_views)
