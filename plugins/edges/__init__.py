"""Edge detection (seed: "Edge detection").

Derivative filters (the course's [−1, 1], central differences, Sobel,
Prewitt, derivative of a Gaussian), gradient magnitude and orientation, and
Canny's detector (non-maximum suppression with interpolation, hysteresis with
absolute or quantile thresholds).
"""

from ._canny import Canny, canny, canny_edges, hysteresis, non_maximum_suppression
from ._derivatives import (
    DERIVATIVES,
    EdgeBoundary,
    Gradient,
    derivative,
    derivative_kernel,
    derivative_taps,
    gradient,
    gradient_images,
)
from ._draw import draw_edges

__all__ = [
    "DERIVATIVES",
    "Canny",
    "EdgeBoundary",
    "Gradient",
    "canny",
    "canny_edges",
    "derivative",
    "derivative_kernel",
    "derivative_taps",
    "draw_edges",
    "gradient",
    "gradient_images",
    "hysteresis",
    "non_maximum_suppression",
]
