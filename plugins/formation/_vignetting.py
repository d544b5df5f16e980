r"""Vignetting: the fall-off of brightness towards the image corners, modelled and undone.

Two models of the relative illumination V at distance r from the image centre:

* natural (cos⁴) vignetting of an ideal lens, f the focal length in pixels:
  :math:`V(r) = \cos^4 \theta = (1 + r^2 / f^2)^{-2}`;
* an even polynomial, r normalised by the half-diagonal:
  :math:`V(r) = 1 + a_1 r^2 + a_2 r^4 + a_3 r^6`.

A flat field (an image of a uniform surface) is :math:`V` times a constant:
the polynomial is estimated from it by linear least squares on
:math:`(r^2, r^4, r^6)` after normalising by the fitted centre value, and an
image is corrected by dividing by V.

References
----------
.. [1] D. B. Goldman, "Vignette and exposure calibration and compensation", IEEE TPAMI
   32(12), 2010.
"""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import Field

from graphvision import Array, ColorImage, GrayImage, ImageT, node

from ..shared.draw import colour_canvas
from ..shared.params import Positive

__all__ = [
    "correct_vignetting",
    "draw_vignetting",
    "estimate_vignetting",
    "vignette",
    "vignetting_field",
]


def _radius(shape: tuple[int, ...], normalised: bool) -> np.ndarray:
    h, w = shape[:2]
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    r = np.hypot(x - (w - 1) / 2, y - (h - 1) / 2)
    return r / np.hypot((w - 1) / 2, (h - 1) / 2) if normalised else r


def vignetting_field(
    shape: tuple[int, ...], model: str, focal: float, coefficients: np.ndarray
) -> np.ndarray:
    """V(r) over an image of ``shape`` (module docstring)."""
    if model == "cos4":
        r = _radius(shape, normalised=False)
        return 1.0 / (1.0 + (r / focal) ** 2) ** 2
    r2 = _radius(shape, normalised=True) ** 2
    a1, a2, a3 = coefficients
    return 1 + r2 * (a1 + r2 * (a2 + r2 * a3))


@node("formation.vignette", version=1)
def vignette(
    image: ImageT,
    *,
    model: Literal["cos4", "polynomial"] = "cos4",
    focal: Positive = 500.0,
    a1: float = -0.3,
    a2: float = 0.0,
    a3: float = 0.0,
) -> ImageT:
    """Darken an image towards its corners by a vignetting model (module docstring).

    Parameters
    ----------
    image : Image
        The evenly lit image.
    model : {"cos4", "polynomial"}
        Natural cos⁴ fall-off, or the even polynomial.
    focal : float
        Focal length in pixels (cos4 model).
    a1, a2, a3 : float
        Polynomial coefficients of r², r⁴, r⁶ (r = 1 at the corners).
    """
    field = vignetting_field(image.shape, model, focal, np.array([a1, a2, a3]))
    if field.min() <= 0:
        raise ValueError(f"the polynomial ({a1}, {a2}, {a3}) reaches {field.min():.3g} ≤ 0")
    shaped = field[..., None] if image.ndim == 3 else field
    return np.clip(image * shaped, 0, 1).astype(np.float32)


@node("formation.estimate_vignetting", version=1)
def estimate_vignetting(flat: GrayImage) -> Array:
    """The polynomial ``(a1, a2, a3)`` of V from a flat-field image (least squares).

    Parameters
    ----------
    flat : GrayImage
        An image of a uniformly lit, uniform surface taken through the lens.

    Raises
    ------
    ValueError
        When the flat field is black at its centre.
    """
    r2 = _radius(flat.shape, normalised=True).ravel() ** 2
    design = np.column_stack([np.ones_like(r2), r2, r2**2, r2**3])
    solution, *_ = np.linalg.lstsq(design, flat.ravel().astype(np.float64), rcond=None)
    if solution[0] <= 0:
        raise ValueError("the flat field is dark at its centre: no vignetting can be fitted")
    return solution[1:] / solution[0]


@node("formation.correct_vignetting", version=1)
def correct_vignetting(image: ImageT, coefficients: Array) -> ImageT:
    """Divide an image by the fitted vignetting polynomial.

    Parameters
    ----------
    image : Image
        An image taken through the vignetting lens.
    coefficients : Array
        ``(a1, a2, a3)`` from ``formation.estimate_vignetting``.

    Raises
    ------
    ValueError
        When the coefficients are not 3 or the polynomial is not positive over the image.
    """
    if coefficients.shape != (3,):
        raise ValueError(f"coefficients must be (a1, a2, a3), got shape {coefficients.shape}")
    field = vignetting_field(image.shape, "polynomial", 1.0, coefficients)
    if field.min() <= 0:
        raise ValueError(f"the vignetting polynomial reaches {field.min():.3g} ≤ 0 in the image")
    shaped = field[..., None] if image.ndim == 3 else field
    return np.clip(image / shaped, 0, 1).astype(np.float32)


@node("formation.draw_vignetting", version=1)
def draw_vignetting(
    flat: GrayImage,
    coefficients: Array,
    *,
    contours: Annotated[int, Field(ge=1, le=20)] = 5,
) -> ColorImage:
    """The flat field with iso-lines of the fitted V drawn over it (0.95, 0.9, … of the centre).

    Parameters
    ----------
    flat : GrayImage
        The flat-field image the coefficients were fitted to.
    coefficients : Array
        ``(a1, a2, a3)`` from ``formation.estimate_vignetting``.
    contours : int
        Number of iso-lines, 5 % apart.
    """
    if coefficients.shape != (3,):
        raise ValueError(f"coefficients must be (a1, a2, a3), got shape {coefficients.shape}")
    field = vignetting_field(flat.shape, "polynomial", 1.0, coefficients)
    canvas = colour_canvas(flat)
    step = np.gradient(field)
    width = np.hypot(*step)  # draw a band about one pixel wide around each level
    for k in range(1, contours + 1):
        band = np.abs(field - (1 - 0.05 * k)) < 0.5 * width + 1e-12
        canvas[band] = (1.0, 0.55, 0.0)
    return canvas
