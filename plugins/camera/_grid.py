r"""Growing a checkerboard's grid of saddle candidates (``_corners``' module docstring,
step 2), with the image smoothed by σ = 1 it checks the candidates in.

A first cell is two neighbours of a seed in different directions and the candidate that
closes the parallelogram, each side crossing an edge and every corner an X-junction
(:class:`_Grower`; the rows it then adds are grown in one compiled call,
``_grid_kernels.grow``). :class:`_Photo` samples the smoothed image and its gradient.

References
----------
.. [1] A. Geiger et al., "Automatic camera and range sensor calibration using a single
   shot", ICRA 2012 (saddle-based checkerboard corners, growing the grid).
"""

from __future__ import annotations

import numpy as np

__all__ = ["MAX_ASYMMETRY", "MIN_EDGE", "SEEDS", "TOLERANCE"]

SEEDS = 8
"""Strongest candidates tried as the first corner of the grid."""
TOLERANCE = 0.3
"""Farthest a candidate may lie from its predicted place, as a fraction of the spacing."""
MIN_EDGE = 0.1
"""Least gradient at a cell side's midpoint, as a fraction of the local contrast."""
MAX_ASYMMETRY = 0.5
"""Largest :math:`|I(p + \\rho u) - I(p - \\rho u)|` of an X-junction, as a fraction of
the contrast around it."""
_ANGLES = np.linspace(0.0, np.pi, 8, endpoint=False)
_COS, _SIN = np.cos(_ANGLES), np.sin(_ANGLES)  # the 8 directions u, made once


class _Photo:
    """The image smoothed by σ = 1, sampled (and its gradient) at sub-pixel points."""

    def __init__(self, image: np.ndarray) -> None:
        from ._corner_kernels import smooth_unit

        self.smooth = smooth_unit(np.asarray(image))  # a float32 image is not copied

    def x_junctions(self, points: np.ndarray, radius: np.ndarray) -> bool:
        """Every point is point-symmetric at ``radius`` (an X-junction, not an L or T):
        :math:`|I(p + \\rho u) - I(p - \\rho u)|` at most ``MAX_ASYMMETRY`` of the contrast
        of those 16 samples, for 8 directions u."""
        from ._grid_kernels import x_junctions

        return bool(
            x_junctions(
                self.smooth,
                np.ascontiguousarray(points, dtype=np.float64),
                np.asarray(radius, np.float64),
                _COS,
                _SIN,
                MAX_ASYMMETRY,
            )
        )

    def on_edges(self, a: np.ndarray, b: np.ndarray, contrast: float) -> bool:
        """Every segment a–b crosses an edge at its midpoint (two neighbouring corners)."""
        from ._corner_kernels import gradient_samples

        middle = np.ascontiguousarray(((a + b) / 2).reshape(-1, 2))
        gradient = np.hypot(
            *gradient_samples(self.smooth, middle[:, 0].copy(), middle[:, 1].copy())
        )
        return bool((gradient >= MIN_EDGE * contrast).all())

    def contrast(self, point: np.ndarray) -> float:
        x, y = int(round(point[0])), int(round(point[1]))
        window = self.smooth[max(y - 3, 0) : y + 4, max(x - 3, 0) : x + 4]
        return float(np.ptp(window)) if window.size else 0.0


class _Grower:
    """Growing a grid of candidates (module docstring, step 2)."""

    def __init__(self, candidates: np.ndarray, photo: _Photo, columns: int, rows: int) -> None:
        from scipy.spatial import cKDTree

        self.candidates = candidates
        self.photo = photo
        self.shapes = {(rows, columns), (columns, rows)}
        self.rows, self.columns = rows, columns
        self.tree = cKDTree(candidates)
        self.strong = cKDTree(candidates[: columns * rows])

    def strongest_near(self, point: np.ndarray, radius: float) -> int | None:
        near = self.tree.query_ball_point(point, radius)
        return min(near) if near else None  # candidates are sorted strongest first

    def grid(self) -> np.ndarray | None:
        """Candidate indices ``rows × columns`` (or transposed), or None."""
        for seed in range(min(SEEDS, len(self.candidates))):
            cell = self._first_cell(seed)
            if cell is None:
                continue
            grid = self._grow(cell)
            if grid.shape in self.shapes:
                return grid if grid.shape == (self.rows, self.columns) else grid.T
        return None

    def _first_cell(self, seed: int) -> np.ndarray | None:
        p = self.candidates[seed]
        _, index = self.strong.query(p, k=min(9, self.strong.n))
        index = np.atleast_1d(index)[1:]
        step = self.candidates[index] - p
        length = np.linalg.norm(step, axis=1)
        pairs = [
            (length[i] + length[j], i, j)
            for i in range(len(index))
            for j in range(i + 1, len(index))
            if abs(step[i] @ step[j]) < 0.8 * length[i] * length[j]
        ]
        contrast = self.photo.contrast(p)
        for _, i, j in sorted(pairs):
            shortest = min(length[i], length[j])
            diagonal = self.strongest_near(p + step[i] + step[j], TOLERANCE * shortest)
            cell = np.array([[seed, index[i]], [index[j], diagonal]])
            if diagonal is None or len(set(cell.ravel().tolist())) != 4:
                continue
            quad = self.candidates[[seed, index[i], diagonal, index[j]]]
            if self.photo.on_edges(
                quad, np.roll(quad, -1, axis=0), contrast
            ) and self.photo.x_junctions(quad, np.full(4, TOLERANCE * shortest)):
                return cell
        return None

    def _grow(self, grid: np.ndarray) -> np.ndarray:
        """Add whole rows or columns (module docstring, step 2; one compiled call): a
        homography fitted to the 3 nearest rows predicts the next one, each prediction
        takes the strongest candidate within ``TOLERANCE`` of the spacing, and the row
        must be distinct, new and of X-junctions; the extension that fits best first."""
        from ._grid_kernels import grow

        return grow(
            self.candidates,
            np.ascontiguousarray(grid, dtype=np.int64),
            self.photo.smooth,
            self.columns,
            self.rows,
            TOLERANCE,
            _COS,
            _SIN,
            MAX_ASYMMETRY,
        )
