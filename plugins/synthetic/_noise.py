"""Seeded noise models: Gaussian, salt and pepper, impulse (notes: "Filtering")."""

from __future__ import annotations

import numpy as np

from graphvision import ImageT, node

from ..shared.params import Fraction, Seed

__all__ = ["gaussian_noise", "impulse_noise", "salt_and_pepper"]


def _pixel_mask(image: np.ndarray, amount: float, rng: np.random.Generator) -> np.ndarray:
    """Pixels hit by the noise: the same pixels in every channel of a colour image."""
    return rng.random(image.shape[:2]) < amount


@node("synthetic.gaussian_noise", version=1)
def gaussian_noise(
    image: ImageT,
    *,
    sigma: Fraction = 0.05,
    seed: Seed = 0,
) -> ImageT:
    r"""Add independent Gaussian noise to every pixel.

    :math:`F' = F + n` with :math:`n \sim N(0, \sigma^2)` drawn per pixel and channel.

    The result is clipped to [0, 1] (so near black and white the noise is
    not exactly zero-mean).

    Parameters
    ----------
    image : (H, W) or (H, W, 3) float32 ndarray
    sigma : float
        Standard deviation in intensity units (1 = full range).
    seed : int

    Returns
    -------
    noisy : float32 ndarray, same kind as ``image``
    """
    rng = np.random.default_rng(seed)
    noisy = image + rng.normal(0.0, sigma, image.shape).astype(np.float32)
    return np.clip(noisy, 0.0, 1.0, out=noisy)


@node("synthetic.salt_and_pepper", version=1)
def salt_and_pepper(
    image: ImageT,
    *,
    amount: Fraction = 0.05,
    salt_ratio: Fraction = 0.5,
    seed: Seed = 0,
) -> ImageT:
    """Salt-and-pepper noise: a random ``amount`` of pixels set to white (salt) or black (pepper).

    Each pixel is hit with probability ``amount``; a hit pixel is white with
    probability ``salt_ratio``, else black. In a colour image the whole pixel
    changes.

    Parameters
    ----------
    image : (H, W) or (H, W, 3) float32 ndarray
    amount : float
        Probability that a pixel is replaced.
    salt_ratio : float
        Share of white among replaced pixels.
    seed : int

    Returns
    -------
    noisy : float32 ndarray, same kind as ``image``
    """
    rng = np.random.default_rng(seed)
    hit = _pixel_mask(image, amount, rng)
    salt = rng.random(image.shape[:2]) < salt_ratio
    noisy = image.copy()
    noisy[hit & salt] = 1.0
    noisy[hit & ~salt] = 0.0
    return noisy


@node("synthetic.impulse_noise", version=1)
def impulse_noise(image: ImageT, *, amount: Fraction = 0.05, seed: Seed = 0) -> ImageT:
    """Impulse noise: random white dots, each pixel turned white with probability ``amount``.

    Parameters
    ----------
    image : (H, W) or (H, W, 3) float32 ndarray
    amount : float
    seed : int

    Returns
    -------
    noisy : float32 ndarray, same kind as ``image``
    """
    rng = np.random.default_rng(seed)
    noisy = image.copy()
    noisy[_pixel_mask(image, amount, rng)] = 1.0
    return noisy
