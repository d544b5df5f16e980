"""Points on a known line, with noise and outliers: ground truth for line fitting."""

from __future__ import annotations

from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Points2D, node

from ..fitting import Line2D
from ..shared.params import Seed

__all__ = ["line_points"]


class LineSample(NamedTuple):
    points: Points2D
    truth: Line2D


@node("synthetic.line_points", version=1)
def line_points(
    *,
    count: Annotated[int, Field(ge=2, le=100_000)] = 100,
    outlier_ratio: Annotated[float, Field(ge=0, lt=1)] = 0.3,
    noise: Annotated[float, Field(ge=0)] = 1.0,
    angle: float = 0.5,
    seed: Seed = 0,
) -> LineSample:
    """Points on a known line with Gaussian noise, plus uniform outliers (seeded).

    The line passes through (50, 50) at ``angle`` radians from +x; inliers
    lie along a 100-pixel stretch, outliers anywhere in the 100×100 square.

    Parameters
    ----------
    count : int
        Number of points, inliers and outliers together.
    outlier_ratio : float
        Fraction of the points drawn uniformly instead of on the line.
    noise : float
        σ of the Gaussian noise added to the inliers, perpendicular and along.
    angle : float
        Angle of the line in radians.
    seed : int
        Seed of every draw.

    Returns
    -------
    points : (count, 2) float64
    truth : (3,) float64, the line the inliers were drawn from
    """
    rng = np.random.default_rng(seed)
    outliers = int(round(count * outlier_ratio))
    t = rng.uniform(-50, 50, count - outliers)
    direction = np.array([np.cos(angle), np.sin(angle)])
    normal = np.array([-direction[1], direction[0]])
    inliers = 50 + t[:, None] * direction + rng.normal(0, noise, (len(t), 1)) * normal
    points = np.vstack([inliers, rng.uniform(0, 100, (outliers, 2))])
    return LineSample(points[rng.permutation(count)], np.array([*normal, -normal @ [50, 50]]))
