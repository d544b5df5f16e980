"""Colour histograms and the distances that compare them."""

from __future__ import annotations

from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from graphvision import ArrayPort, Float, Image, PortValueError, node

__all__ = [
    "METRICS",
    "Histogram",
    "HistogramPort",
    "Metric",
    "colour_histogram",
    "histogram",
    "histogram_distance",
    "histogram_distances",
]

Metric = Literal["euclidean", "chi2", "hellinger", "intersection"]
METRICS: tuple[str, ...] = ("euclidean", "chi2", "hellinger", "intersection")
Bins = Annotated[int, Field(ge=1, le=256, description="Bins per channel.")]


class HistogramPort(ArrayPort):
    """A histogram: ``float64`` counts or frequencies ≥ 0, 1-D (gray, or channels side by
    side) or 3-D (a joint colour histogram, one axis per channel)."""

    ndims = (1, 3)
    dtypes = (np.float64,)
    expected = "float64 1-D or 3-D, values >= 0"

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if not np.isfinite(value).all() or (value < 0).any():
            raise PortValueError(f"expected Histogram ({cls.expected}), got negative or NaN")
        return value


Histogram = Annotated[NDArray[np.float64], HistogramPort]


def colour_histogram(image: np.ndarray, bins: int, kind: str = "joint") -> np.ndarray:
    """Normalised histogram of an image in [0, 1]: joint 3-D, per channel (concatenated),
    or 1-D for gray. Bin ``k`` of ``n`` holds values in ``[k/n, (k+1)/n)``, 1 in the last."""
    index = np.minimum((image * bins).astype(np.intp), bins - 1)
    if image.ndim == 2:
        counts = np.bincount(index.ravel(), minlength=bins).astype(np.float64)
    elif kind == "joint":
        flat = (index[..., 0] * bins + index[..., 1]) * bins + index[..., 2]
        counts = np.bincount(flat.ravel(), minlength=bins**3).astype(np.float64)
        counts = counts.reshape(bins, bins, bins)
    else:
        counts = np.concatenate(
            [np.bincount(index[..., c].ravel(), minlength=bins) for c in range(3)]
        ).astype(np.float64)
        counts /= 3.0
    return counts / (image.shape[0] * image.shape[1])


@node("colour.histogram", version=1)
def histogram(
    image: Image, *, bins: Bins = 8, kind: Literal["joint", "channels"] = "joint"
) -> Histogram:
    r"""Colour histogram :math:`H(R, G, B)`: the fraction of pixels of each colour cell.

    Each pixel is a point in the RGB cube; with ``kind="joint"`` the cube is
    cut into :math:`b^3` cells and :math:`H` counts the pixels in each
    (the course's colour histogram), with ``kind="channels"`` each channel
    gets its own :math:`b` bins, side by side. A gray image gives a 1-D
    histogram of :math:`b` bins. Histograms sum to one, so images of
    different sizes compare.

    Parameters
    ----------
    image : Image
        Gray or RGB in [0, 1].
    bins : int
        Bins per channel (at least 1).
    kind : {"joint", "channels"}
        One 3-D histogram or three 1-D ones concatenated (colour only).

    Returns
    -------
    histogram : float64 ndarray, (b, b, b) or (3b,) or (b,), summing to 1

    References
    ----------
    .. [1] M. J. Swain, D. H. Ballard, "Color indexing", IJCV 7(1), 1991.
    """
    return colour_histogram(image, bins, kind)


def histogram_distances(query: np.ndarray, gallery: np.ndarray, metric: str) -> np.ndarray:
    """Distance from one flattened histogram ``query (D,)`` to each row of ``gallery (N, D)``.

    ``intersection`` returns :math:`1 - \\sum \\min`, so that smaller is closer for all.
    """
    if metric == "euclidean":
        return np.sqrt(((gallery - query) ** 2).sum(axis=1))
    if metric == "chi2":
        total = gallery + query
        safe = np.where(total > 0, total, 1.0)
        return 0.5 * np.where(total > 0, (gallery - query) ** 2 / safe, 0.0).sum(axis=1)
    if metric == "hellinger":
        overlap = np.sqrt(gallery * query).sum(axis=1)
        return np.sqrt(np.clip(1.0 - overlap, 0.0, None))
    if metric == "intersection":
        return 1.0 - np.minimum(gallery, query).sum(axis=1)
    raise ValueError(f"unknown metric {metric!r}; expected one of {METRICS}")


@node("colour.distance", version=1)
def histogram_distance(a: Histogram, b: Histogram, *, metric: Metric = "chi2") -> Float:
    r"""Distance between two normalised histograms (0 for equal ones).

    .. math::
        d_\text{Euclid} = \sqrt{\textstyle\sum_i (a_i - b_i)^2}, \quad
        \chi^2 = \tfrac12 \sum_i \frac{(a_i - b_i)^2}{a_i + b_i}, \quad
        d_\text{Hellinger} = \sqrt{1 - \textstyle\sum_i \sqrt{a_i b_i}}, \quad
        d_\cap = 1 - \textstyle\sum_i \min(a_i, b_i)

    :math:`\sum_i \sqrt{a_i b_i}` is the Bhattacharyya coefficient. All lie
    in [0, 1] for histograms summing to one except the Euclidean one
    (at most :math:`\sqrt 2`).

    Parameters
    ----------
    a, b : Histogram
        Histograms of the same shape, each summing to one.
    metric : {"euclidean", "chi2", "hellinger", "intersection"}
        Which distance.

    Returns
    -------
    distance : float

    References
    ----------
    .. [1] Swain & Ballard (1991) for the intersection; Szeliski (2022),
       section 7.1.3.
    """
    if a.shape != b.shape:
        raise ValueError(
            f"histograms a and b must have the same shape, got {a.shape} and {b.shape}"
        )
    return float(histogram_distances(a.ravel(), b.ravel()[None, :], metric)[0])
