"""Drawing helpers shared by the built-in plugins' drawing nodes.

Every drawing node starts from :func:`colour_canvas` (a writable RGB float32 copy,
gray shown as gray) and marks it in place with clipped primitives: what falls
outside the canvas is left out, never wrapped around by negative indices.
"""

from __future__ import annotations

import numpy as np

__all__ = ["colour_canvas", "draw_circle", "draw_segment", "draw_segments", "plot_points"]


def colour_canvas(image: np.ndarray) -> np.ndarray:
    """A writable float32 H×W×3 copy of ``image``: a gray image repeated in R, G and B."""
    rgb = np.repeat(image[..., None], 3, axis=2) if image.ndim == 2 else image
    return np.array(rgb, dtype=np.float32, copy=True)


def plot_points(canvas: np.ndarray, x: np.ndarray, y: np.ndarray, colour: object) -> None:
    """Set the pixels nearest to ``(x, y)`` to ``colour``, those inside the canvas only."""
    cols = np.rint(np.asarray(x, dtype=np.float64)).astype(np.intp)
    rows = np.rint(np.asarray(y, dtype=np.float64)).astype(np.intp)
    inside = (rows >= 0) & (rows < canvas.shape[0]) & (cols >= 0) & (cols < canvas.shape[1])
    canvas[rows[inside], cols[inside]] = colour


def draw_segment(canvas: np.ndarray, p: np.ndarray, q: np.ndarray, colour: object) -> None:
    """The segment from ``p`` to ``q`` (x, y), Bresenham's pixels, clipped to the canvas."""
    from skimage.draw import line

    rr, cc = line(int(round(p[1])), int(round(p[0])), int(round(q[1])), int(round(q[0])))
    inside = (rr >= 0) & (rr < canvas.shape[0]) & (cc >= 0) & (cc < canvas.shape[1])
    canvas[rr[inside], cc[inside]] = colour


def draw_segments(
    canvas: np.ndarray, starts: np.ndarray, ends: np.ndarray, colours: np.ndarray
) -> None:
    """Segments ``starts[k]`` to ``ends[k]`` (N × 2, x, y) in ``colours[k]`` (N × 3), drawn in
    order with the pixels :func:`draw_segment` gives each, in one compiled pass.

    Raises
    ------
    ValueError
        When an end point is not finite.
    """
    from .draw_kernels import segments

    points = np.concatenate([np.asarray(starts, np.float64), np.asarray(ends, np.float64)], 1)
    if not np.isfinite(points).all():
        raise ValueError("a segment's end point is not finite")
    rows_cols = np.rint(points[:, [1, 0, 3, 2]]).astype(np.int64)  # as round(): half to even
    colours = np.broadcast_to(np.asarray(colours, canvas.dtype), (len(points), canvas.shape[2]))
    segments(canvas, rows_cols, np.ascontiguousarray(colours))


def draw_circle(canvas: np.ndarray, x: float, y: float, radius: int, colour: object) -> None:
    """The circle of ``radius`` pixels about ``(x, y)``, its outline only, clipped."""
    from skimage.draw import circle_perimeter

    rr, cc = circle_perimeter(int(round(y)), int(round(x)), radius, shape=canvas.shape[:2])
    canvas[rr, cc] = colour
