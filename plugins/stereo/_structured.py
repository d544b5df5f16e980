"""Active stereo (notes: "Active stereo"): decode projected Gray-code stripes and
triangulate each camera ray with the plane of its projector column."""

from __future__ import annotations

from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Camera, Int, node

from ._ports import Depth, DisparityPort, Frames

__all__ = [
    "Stripes",
    "StripesPort",
    "decode_gray_code",
    "depth_from_stripes",
    "stripe_middle_column",
    "stripe_planes",
]


class StripesPort(DisparityPort):
    """The projector stripe seen at each camera pixel: ``float32`` ``H×W`` index, NaN where
    it could not be decoded (shadow, too little contrast)."""

    expected = "float32 H×W stripe index, NaN where undecoded"


Stripes = Annotated[np.ndarray, StripesPort]


class Decoded(NamedTuple):
    stripes: Stripes
    bits: Int


@node("stereo.decode_gray_code", version=2)
def decode_gray_code(
    frames: Frames, *, min_contrast: Annotated[float, Field(ge=0)] = 0.05
) -> Decoded:
    r"""The stripe index of every pixel from captures of Gray-code bit planes and their inverses.

    Bit :math:`g_i = [I_{2i} > I_{2i+1}]` (pattern brighter than its
    inverse, so albedo and ambient light cancel); the Gray code becomes the
    binary index by :math:`b_0 = g_0,\ b_i = b_{i-1} \oplus g_i`. A pixel
    whose pattern and inverse differ by less than ``min_contrast`` in any bit
    is not lit by the projector (shadow, outside its field) and is NaN.

    Parameters
    ----------
    frames : Frames
        ``2·bits`` captures, most significant bit first, each followed by its inverse.
    min_contrast : float
        Smallest |pattern − inverse| of a decodable pixel.

    Returns
    -------
    stripes : Stripes
        Index in :math:`[0, 2^{bits})`, float32, NaN where undecoded.
    bits : int
        The bit planes decoded (half the frames), for :func:`depth_from_stripes`.

    References
    ----------
    .. [1] Inokuchi, Sato, Matsuda, "Range imaging system for 3-D object
       recognition", ICPR 1984 (Gray-coded structured light).
    """
    if len(frames) % 2:
        raise ValueError(
            f"expected pairs of frames (each bit plane and its inverse), got {len(frames)} frames"
        )
    bits = len(frames) // 2
    pattern, inverse = frames[0::2], frames[1::2]
    gray = pattern > inverse
    decodable = (np.abs(pattern - inverse) >= min_contrast).all(axis=0)
    binary = np.logical_xor.accumulate(gray, axis=0)
    weights = (1 << np.arange(bits - 1, -1, -1)).astype(np.int64)
    index = np.tensordot(weights, binary.astype(np.int64), axes=1)
    return Decoded(np.where(decodable, index, np.nan).astype(np.float32), bits)


def stripe_middle_column(stripes: np.ndarray, width: int, bits: int) -> np.ndarray:
    r"""The projector column at the middle of each stripe, in the pixel-centre convention.

    Stripe :math:`s` lights the projector pixels :math:`j` with
    :math:`\lfloor j\, 2^{bits} / W \rfloor = s`, from :math:`a_s = \lceil s W / 2^{bits} \rceil`
    to :math:`a_{s+1} - 1`; pixel :math:`j` covers the columns :math:`[j - \tfrac12, j + \tfrac12)`
    about its centre (the convention of a principal point at :math:`(W - 1)/2`), so the
    stripe covers :math:`[a_s - \tfrac12, a_{s+1} - \tfrac12)` and its middle is
    :math:`u_s = (a_s + a_{s+1} - 1) / 2` (:math:`(s + \tfrac12) W / 2^{bits} - \tfrac12`
    when :math:`2^{bits}` divides :math:`W`). A fractional index ``s`` is interpolated
    linearly between the middles of its neighbours.
    """
    index = stripes.astype(np.float64)
    low = np.floor(np.where(np.isfinite(index), index, 0.0))
    step = 1 << bits

    def first_pixel(s: np.ndarray) -> np.ndarray:
        return -np.floor_divide(-s * width, step)  # ⌈s W / 2^bits⌉, exact in integers

    def middle(s: np.ndarray) -> np.ndarray:
        return (first_pixel(s) + first_pixel(s + 1) - 1) / 2

    fraction = index - low
    return (1 - fraction) * middle(low) + fraction * middle(low + 1)


def stripe_planes(stripes: np.ndarray, camera: Camera, projector: Camera, bits: int) -> np.ndarray:
    """Depth of each camera ray where it meets the plane through the projector's centre and
    the middle column of its stripe (see :func:`depth_from_stripes`)."""
    columns = stripe_middle_column(stripes, int(projector.size[0]), bits)
    rows, cols = stripes.shape
    y, x = np.mgrid[0:rows, 0:cols].astype(np.float64)
    pixels = np.stack([x, y, np.ones_like(x)], axis=-1)
    rays = pixels @ np.linalg.inv(camera.K).T  # camera frame, z = 1
    K_p = projector.K
    # the plane x_p / z_p = (u − cx) / fx in the projector frame, normal n_p
    normal_p = np.stack(
        [np.full_like(columns, K_p[0, 0]), np.zeros_like(columns), -(columns - K_p[0, 2])], -1
    )
    normal_world = normal_p @ projector.R  # n_w = R_pᵀ n_p, row-wise
    rays_world = rays @ camera.R  # R_cᵀ r
    through = camera.C - projector.C
    numerator = -(normal_world @ through)
    denominator = np.einsum("...i,...i->...", normal_world, rays_world)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = numerator / denominator
    return np.where(np.isfinite(t) & (t > 0), t, np.nan)


@node("stereo.depth_from_stripes", version=2)
def depth_from_stripes(stripes: Stripes, bits: Int, camera: Camera, projector: Camera) -> Depth:
    r"""Depth by ray-plane intersection: each camera ray meets the plane of light of its stripe.

    A stripe :math:`s` lights the projector pixels :math:`j` with
    :math:`\lfloor j\, 2^{bits} / W \rfloor = s`, from :math:`a_s = \lceil s W / 2^{bits} \rceil`
    to :math:`a_{s+1} - 1`. Pixel :math:`j` covers the columns :math:`[j - \tfrac12, j + \tfrac12)`
    about its centre (pixel centres are integers, as a principal point at
    :math:`(W - 1)/2` says), so the stripe's middle column is
    :math:`u = (a_s + a_{s+1} - 1)/2`, i.e. :math:`(s + \tfrac12)\,W / 2^{bits} - \tfrac12` when
    :math:`2^{bits}` divides :math:`W`. That column spans, with the projector's centre, the plane
    :math:`n_p \cdot X_p = 0`, :math:`n_p = (f_x, 0, -(u - c_x))` in the
    projector's frame :math:`X_p = R_p (X - \tilde C_p)`. The camera ray
    :math:`X = \tilde C_c + t\, R_c^T K_c^{-1} (x, y, 1)^T` meets it at

    .. math:: t = -\frac{n \cdot (\tilde C_c - \tilde C_p)}{n \cdot R_c^T K_c^{-1} (x, y, 1)^T},
        \qquad n = R_p^T n_p,

    and :math:`t` is the depth along the camera's axis. With the column known
    only to its stripe, the depth error is uniform over a stripe: RMSE
    :math:`\approx |\partial Z / \partial u| \cdot (W / 2^{bits}) / \sqrt{12}`.

    Parameters
    ----------
    stripes : Stripes
        Decoded stripe index per camera pixel (NaN where undecoded).
    bits : Int
        Bit planes projected (:math:`2^{bits}` stripes): the decoder's ``bits``
        output, so that the count cannot disagree with the captures.
    camera : Camera
        The camera (K, pose).
    projector : Camera
        The projector as an inverse camera (K, pose, size: its columns).
    """
    if not 1 <= bits <= 16:
        raise ValueError(f"bits must be 1 to 16, got {bits}")
    if not np.isfinite(stripes).any():
        raise ValueError("no pixel was decoded: is the projector lighting the scene?")
    high = float(np.nanmax(stripes))
    if high >= 1 << bits:
        raise ValueError(f"stripe index {high:g} does not fit in {bits} bits: is bits right?")
    return stripe_planes(stripes, camera, projector, bits).astype(np.float32)
