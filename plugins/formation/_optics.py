r"""Pinhole and thin-lens optics: field of view, focus, depth of field, defocus blur.

From the seed's "Image formation": a thin lens of focal length f brings a point
at distance :math:`z_o` into focus at :math:`z_i` with
:math:`1/f = 1/z_o + 1/z_i`; a point at another distance z spreads into a
circle of confusion of diameter

.. math:: c(z) = A \frac{f}{s - f} \frac{|z - s|}{z}, \qquad A = f / N,

for a lens focused at s with f-number N (aperture diameter A). The depth of
field is the range where :math:`c \le c_{max}`: with the hyperfocal distance
:math:`H = f^2 / (N c_{max}) + f`,

.. math:: z_{near} = \frac{s (H - f)}{H + s - 2f}, \qquad
          z_{far} = \frac{s (H - f)}{H - s} \; (\infty \text{ for } s \ge H).

The field of view of a sensor of size d behind a lens of focal length f is
:math:`2 \arctan(d / 2f)`.

References
----------
.. [1] E. Hecht, *Optics*, 5th ed., 2017, §5.2 (thin lenses), §5.3.3 (depth of field).
.. [2] R. Szeliski, *Computer Vision: Algorithms and Applications*, 2nd ed., 2022, §2.2.3.
"""

from __future__ import annotations

from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Float, FloatImage, ImageT, node

from ..shared.params import Positive

__all__ = ["circle_of_confusion", "defocus", "depth_of_field", "field_of_view", "focus_distance"]

Positive = Positive


@node("formation.field_of_view", version=1)
def field_of_view(*, sensor_size: Positive = 36.0, focal_length: Positive = 50.0) -> Float:
    """The angle of view, degrees: :math:`2 \\arctan(d / 2f)`.

    Parameters
    ----------
    sensor_size : float
        Sensor width, height or diagonal (mm): the angle is along that extent.
    focal_length : float
        Focal length (mm).
    """
    return float(np.degrees(2 * np.arctan(sensor_size / (2 * focal_length))))


@node("formation.focus_distance", version=1)
def focus_distance(*, object_distance: Positive = 2000.0, focal_length: Positive = 50.0) -> Float:
    """Lens-to-sensor distance that focuses an object: :math:`z_i = 1 / (1/f - 1/z_o)`.

    Parameters
    ----------
    object_distance : float
        Distance of the object from the lens (mm), beyond the focal length.
    focal_length : float
        Focal length (mm).

    Raises
    ------
    ValueError
        When the object is at or inside the focal length (no real image).
    """
    if object_distance <= focal_length:
        raise ValueError(
            f"object_distance {object_distance:g} mm is not beyond the focal length "
            f"{focal_length:g} mm: the lens forms no real image"
        )
    return 1.0 / (1.0 / focal_length - 1.0 / object_distance)


class DepthOfField(NamedTuple):
    near: Float
    far: Float
    hyperfocal: Float


@node("formation.depth_of_field", version=1)
def depth_of_field(
    *,
    focal_length: Positive = 50.0,
    f_number: Positive = 2.8,
    focus: Positive = 3000.0,
    circle_of_confusion: Positive = 0.03,
) -> DepthOfField:
    """Near and far limits of acceptable sharpness, and the hyperfocal distance (mm).

    Parameters
    ----------
    focal_length : float
        Focal length f (mm).
    f_number : float
        N = f / aperture diameter.
    focus : float
        Distance s the lens is focused at (mm), beyond f.
    circle_of_confusion : float
        Largest acceptable blur-circle diameter on the sensor (mm; 0.03 for 35 mm film).

    Returns
    -------
    near, far : float, mm (far is inf at or beyond the hyperfocal distance)
    hyperfocal : float, mm
    """
    if focus <= focal_length:
        raise ValueError(f"focus {focus:g} mm must lie beyond the focal length {focal_length:g}")
    f, s = focal_length, focus
    hyperfocal = f * f / (f_number * circle_of_confusion) + f
    near = s * (hyperfocal - f) / (hyperfocal + s - 2 * f)
    far = s * (hyperfocal - f) / (hyperfocal - s) if s < hyperfocal else float("inf")
    return DepthOfField(float(near), float(far), float(hyperfocal))


def circle_of_confusion(
    depth: np.ndarray, focal_length: float, f_number: float, focus: float
) -> np.ndarray:
    """Blur-circle diameter on the sensor (units of ``focal_length``) for points at ``depth``."""
    aperture = focal_length / f_number
    return aperture * focal_length / (focus - focal_length) * np.abs(depth - focus) / depth


def _disc(radius: float) -> np.ndarray:
    size = int(np.ceil(radius))
    y, x = np.mgrid[-size : size + 1, -size : size + 1]
    # anti-aliased disc: coverage falls linearly over the last pixel
    kernel = np.clip(radius + 0.5 - np.hypot(x, y), 0, 1)
    return kernel / kernel.sum()


@node("formation.defocus", version=1)
def defocus(
    image: ImageT,
    depth: FloatImage,
    *,
    focal_length: Positive = 50.0,
    f_number: Positive = 1.8,
    focus: Positive = 2000.0,
    pixel_pitch: Positive = 0.01,
    levels: Annotated[int, Field(ge=2, le=64)] = 12,
) -> ImageT:
    """Blur each pixel by the circle of confusion of its depth (thin lens, module docstring).

    The blur radii are quantised to ``levels`` values; the image is filtered
    once per level with an anti-aliased disc (FFT convolution, borders
    mirrored) and each pixel takes the result at its level (linear between
    the two nearest levels). Occlusion at depth edges is not modelled.

    Parameters
    ----------
    image : Image
        The all-in-focus image.
    depth : FloatImage
        Distance of each pixel's scene point from the lens (mm), same H×W.
    focal_length : float
        Focal length (mm).
    f_number : float
        N = f / aperture diameter.
    focus : float
        Distance the lens is focused at (mm).
    pixel_pitch : float
        Size of a sensor pixel (mm).
    levels : int
        Number of blur radii the depth range is quantised to.

    Raises
    ------
    ValueError
        When ``depth`` has another size than the image or is not > focal_length.
    """
    from scipy import fft

    if depth.shape != image.shape[:2]:
        raise ValueError(f"depth must be {image.shape[:2]} like the image, got {depth.shape}")
    if not (depth > focal_length).all():
        raise ValueError(f"depth must exceed the focal length {focal_length:g} mm everywhere")
    radius = 0.5 * circle_of_confusion(depth, focal_length, f_number, focus) / pixel_pitch
    steps = np.linspace(0.0, float(radius.max()), levels)
    position = np.interp(radius, steps, np.arange(levels)) if steps[-1] > 0 else radius * 0
    pad = int(np.ceil(steps[-1])) + 1
    layers = image[..., None] if image.ndim == 2 else image
    padded = np.pad(layers.astype(np.float64), ((pad, pad), (pad, pad), (0, 0)), mode="symmetric")
    shape = padded.shape[:2]
    spectrum = fft.rfft2(padded, axes=(0, 1))  # once; each level multiplies by its disc
    rows, cols = layers.shape[:2]
    out = np.zeros(layers.shape, np.float64)
    for level, r in enumerate(steps):
        weight = np.clip(1 - np.abs(position - level), 0, 1)
        if not weight.any():
            continue
        if r > 0.5:
            disc = _disc(r)
            half = disc.shape[0] // 2
            kernel = np.zeros(shape)
            kernel[: disc.shape[0], : disc.shape[1]] = disc
            kernel = np.roll(kernel, (-half, -half), axis=(0, 1))  # centred at (0, 0)
            response = fft.rfft2(kernel)[..., None] * spectrum
            blurred = fft.irfft2(response, s=shape, axes=(0, 1))[pad : pad + rows, pad : pad + cols]
        else:
            blurred = layers
        out += weight[..., None] * blurred
    out = out[..., 0] if image.ndim == 2 else out
    return np.clip(out, 0, 1).astype(np.float32)
