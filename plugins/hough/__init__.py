"""The Hough transform (seed: "Edge detection by parametric models").

Lines in (ρ, θ) with the course's improvements (votes near the gradient
orientation, weighted by magnitude, spread by a Gaussian; peaks kept by the
length of line their edge points cover and refitted to them), circles of a
known radius or a radius range voting along the gradient, the generalised
transform, and drawings. Results travel as the ``Lines`` and ``Circles``
port types.
"""

from ._circles import HoughCircles, circle_accumulator, hough_circles
from ._draw import draw_circles, draw_lines
from ._generalized import GeneralizedHough, draw_instances, generalized_hough
from ._generalized_votes import build_r_table
from ._lines import HoughLines, hough_lines, line_accumulator
from ._peaks import local_maxima, parabolic_offset, quadratic_peak_2d, suppress_close
from ._ports import Circles, CirclesPort, Lines, LinesPort

__all__ = [
    "Circles",
    "CirclesPort",
    "GeneralizedHough",
    "HoughCircles",
    "HoughLines",
    "Lines",
    "LinesPort",
    "build_r_table",
    "circle_accumulator",
    "draw_circles",
    "draw_instances",
    "draw_lines",
    "generalized_hough",
    "hough_circles",
    "hough_lines",
    "line_accumulator",
    "local_maxima",
    "parabolic_offset",
    "quadratic_peak_2d",
    "suppress_close",
]
