"""Fitting parametric models (seed: "Least squares", "Outliers, RANSAC"): least
squares, weighted, constrained (total) least squares, Gauss-Newton
refinement, and one generic RANSAC built from a minimal solver, a residual,
a sample size and a refit.
"""

from ._lines import (
    Line2D,
    Line2DPort,
    fit_line_lstsq,
    fit_line_ransac,
    fit_line_total,
    fit_line_weighted,
    fit_line_weighted_node,
    line_distance,
    line_residuals,
    refine_line,
)
from ._ransac import RansacResult, ransac, ransac_iterations

__all__ = [
    "Line2D",
    "Line2DPort",
    "RansacResult",
    "fit_line_lstsq",
    "fit_line_ransac",
    "fit_line_total",
    "fit_line_weighted",
    "fit_line_weighted_node",
    "line_distance",
    "line_residuals",
    "ransac",
    "ransac_iterations",
    "refine_line",
]
