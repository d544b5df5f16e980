"""A rectified stereo pair of textured fronto-parallel surfaces with its true disparity."""

from __future__ import annotations

from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import BinaryImage, GrayImage, node

from ..shared.params import Seed
from ..stereo._ports import Disparity

__all__ = ["stereo_pair"]


class StereoPair(NamedTuple):
    left: GrayImage
    right: GrayImage
    disparity: Disparity
    visible: BinaryImage


def _texture(rng: np.random.Generator, rows: int, cols: int) -> np.ndarray:
    """Band-limited noise in [0.1, 0.9] (smooth enough to sample between pixels)."""
    from ..shared.separable import smooth_gaussian

    noise = smooth_gaussian(rng.random((rows, cols)), 1.2)
    noise -= noise.min()
    return 0.1 + 0.8 * noise / max(float(noise.max()), 1e-12)


@node("synthetic.stereo_pair", version=1)
def stereo_pair(
    *,
    width: Annotated[int, Field(ge=32, le=4096)] = 160,
    height: Annotated[int, Field(ge=16, le=4096)] = 120,
    background: Annotated[float, Field(ge=0)] = 4.0,
    slope: float = 0.02,
    foreground: Annotated[float, Field(ge=0)] = 12.0,
    noise: Annotated[float, Field(ge=0)] = 0.0,
    seed: Seed = 0,
) -> StereoPair:
    r"""A rectified pair: a textured background whose disparity grows down the image
    (a floor-like slant) and a textured square in front of it, with the truth.

    The left image shows texture :math:`B(x, y)` and, inside the square,
    :math:`F(x, y)`; the right image shows at :math:`x_r` what the left shows at
    :math:`x_r + d`: :math:`F(x_r + d_f)` where that falls in the square,
    :math:`B(x_r + d_b(y))` elsewhere, with :math:`d_b(y) = \text{background} +
    \text{slope}\cdot y`. Textures are sampled between pixels by cubic splines, so
    disparities need not be integers.

    Parameters
    ----------
    width, height : int
        Image size.
    background : float
        Disparity of the background at the top row, pixels.
    slope : float
        Increase of the background's disparity per row.
    foreground : float
        Disparity of the square (a third of the image, centred), pixels.
    noise : float
        σ of Gaussian noise added to both images (seeded), clipped to [0, 1].
    seed : int
        Seed of the textures and the noise.

    Returns
    -------
    left, right : GrayImage
    disparity : Disparity
        The left image's true disparity (every pixel).
    visible : BinaryImage
        Left pixels whose match is seen in the right image (not occluded by
        the square, not outside the image).
    """
    from scipy import ndimage

    rng = np.random.default_rng(seed)
    margin = int(np.ceil(max(background + slope * height, foreground))) + 4
    back = _texture(rng, height, width + margin)
    front = _texture(rng, height, width + margin)
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    top, bottom = height // 3, height - height // 3
    x0, x1 = width // 3, width - width // 3
    d_back = background + slope * y
    in_square = (y >= top) & (y < bottom) & (x >= x0) & (x < x1)
    left = np.where(in_square, front[:, :width], back[:, :width])
    truth = np.where(in_square, foreground, d_back)

    def sample(texture: np.ndarray, columns: np.ndarray) -> np.ndarray:
        return ndimage.map_coordinates(texture, [y, columns], order=3, mode="nearest")

    front_source = x + foreground
    shows_front = (y >= top) & (y < bottom) & (front_source >= x0) & (front_source < x1)
    right = np.where(shows_front, sample(front, front_source), sample(back, x + d_back))
    # a left pixel is visible when its right pixel (x − d) is inside and shows its own surface
    x_right = x - truth
    front_at_right = (y >= top) & (y < bottom) & (x_right + foreground >= x0)
    front_at_right &= x_right + foreground < x1
    visible = (x_right >= 0) & (in_square | ~front_at_right)
    pair = []
    for image in (left, right):
        if noise > 0:
            image = image + rng.normal(0.0, noise, image.shape)
        pair.append(np.clip(image, 0.0, 1.0).astype(np.float32))
    return StereoPair(pair[0], pair[1], truth.astype(np.float32), visible)
