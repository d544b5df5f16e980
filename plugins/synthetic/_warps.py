"""Seeded random homographies: a warped image, two overlapping views, each with its truth."""

from __future__ import annotations

from typing import Annotated, Generic, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Homography, ImageT, node

from ..geometry import sample_homography
from ..shared.checks import ordered
from ..shared.params import Fraction, Positive, Seed

__all__ = ["random_homography", "random_warp", "two_views"]


def random_homography(
    shape: tuple[int, int],
    rng: np.random.Generator,
    max_rotation: float,
    scale_range: tuple[float, float],
    perspective: float,
) -> np.ndarray:
    rows, cols = shape
    centre = np.array([[1, 0, -(cols - 1) / 2], [0, 1, -(rows - 1) / 2], [0, 0, 1.0]])
    angle = np.deg2rad(rng.uniform(-max_rotation, max_rotation))
    scale = rng.uniform(*scale_range)
    similarity = np.array(
        [
            [scale * np.cos(angle), -scale * np.sin(angle), 0],
            [scale * np.sin(angle), scale * np.cos(angle), 0],
            [0, 0, 1.0],
        ]
    )
    size = max(rows, cols)
    projective = np.eye(3)
    projective[2, :2] = rng.uniform(-perspective, perspective, 2) / size
    h = np.linalg.inv(centre) @ projective @ similarity @ centre
    return h / h[2, 2]


class RandomWarp(NamedTuple, Generic[ImageT]):
    image: ImageT
    homography: Homography


@node("synthetic.random_warp", version=1, check=ordered(("min_scale", "max_scale")))
def random_warp(
    image: ImageT,
    *,
    max_rotation: Annotated[float, Field(ge=0, le=180)] = 30.0,
    min_scale: Positive = 0.7,
    max_scale: Positive = 1.3,
    perspective: Fraction = 0.3,
    seed: Seed = 0,
) -> RandomWarp[ImageT]:
    """Warp the image by a seeded random homography about its centre, same output size.

    The homography is a rotation by up to ``max_rotation`` degrees, a scale
    in ``[min_scale, max_scale]`` and a perspective term of up to
    ``perspective`` (in units of the image size), all about the image centre.

    Parameters
    ----------
    image : Image
        The image to warp.
    max_rotation : float
        Largest rotation, in degrees, either way.
    min_scale, max_scale : float
        Range of the isotropic scale.
    perspective : float
        Largest perspective term, in units of the image size.
    seed : int
        Seed of the random homography.

    Returns
    -------
    image : the warped image
    homography : the true homography, mapping ``image`` coordinates to the warped ones
    """
    rng = np.random.default_rng(seed)
    h = random_homography(image.shape[:2], rng, max_rotation, (min_scale, max_scale), perspective)
    warped, _ = sample_homography(image, np.linalg.inv(h), image.shape[:2])
    return RandomWarp(warped.astype(np.float32), h)


class TwoViews(NamedTuple, Generic[ImageT]):
    left: ImageT
    right: ImageT
    homography: Homography


@node("synthetic.two_views", version=1)
def two_views(
    image: ImageT,
    *,
    overlap: Annotated[float, Field(gt=0.1, lt=1)] = 0.5,
    rotation: Annotated[float, Field(ge=0, le=45)] = 8.0,
    perspective: Annotated[float, Field(ge=0, le=0.5)] = 0.1,
    seed: Seed = 0,
) -> TwoViews[ImageT]:
    """Two overlapping views of one image: the left and right crops, each under its own homography.

    Each view is ``(1 + overlap) / 2`` of the width. The left one is the left
    crop as it is; the right one is the right crop seen through a seeded
    homography (rotation up to ``rotation`` degrees, a perspective term).

    Parameters
    ----------
    image : Image
        The scene both views look at.
    overlap : float
        Fraction of the image width the two crops share.
    rotation : float
        Largest rotation of each view, in degrees.
    perspective : float
        Largest perspective term of each view, in units of the image size.
    seed : int
        Seed of both homographies.

    Returns
    -------
    left, right : the two views
    homography : the true map from ``right`` coordinates to ``left`` coordinates
    """
    rows, cols = image.shape[:2]
    view = int(cols * (1 + overlap) / 2)
    shift = cols - view
    left = np.ascontiguousarray(image[:, :view])
    rng = np.random.default_rng(seed)
    local = random_homography((rows, view), rng, rotation, (0.9, 1.1), perspective)
    # right view pixel -> its crop pixel (inverse of local) -> full image (+shift) -> left view
    crop_to_full = np.array([[1, 0, shift], [0, 1, 0], [0, 0, 1.0]])
    right, _ = sample_homography(image[:, shift:], np.linalg.inv(local), (rows, view))
    to_left = crop_to_full @ np.linalg.inv(local)
    return TwoViews(left, right.astype(np.float32), to_left / to_left[2, 2])
