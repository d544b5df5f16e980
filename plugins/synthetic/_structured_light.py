"""A structured-light capture: Gray-code stripes projected on a scene of known depth."""

from __future__ import annotations

from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Camera, PinholeCamera, node

from ..shared.params import Positive, Seed
from ..stereo._ports import Depth, Frames

__all__ = ["gray_code_stripes", "structured_light_scene"]

_SPHERE_CENTRE = np.array([0.05, 0.0, 1.5])
_SPHERE_RADIUS = 0.3


class StructuredLightScene(NamedTuple):
    frames: Frames
    depth: Depth
    camera: Camera
    projector: Camera


def gray_code_stripes(columns: np.ndarray, bits: int, width: int) -> np.ndarray:
    """Bit planes ``(bits, ...)`` of the reflected Gray code of each projector pixel's
    stripe, most significant first: pixel ``j`` (an integer column index) is in stripe
    ``s = ⌊j · 2^bits / width⌋``, whose code is ``s ⊕ (s ≫ 1)``."""
    stripe = np.clip((columns * (1 << bits)) // width, 0, (1 << bits) - 1).astype(np.int64)
    code = stripe ^ (stripe >> 1)
    return np.stack([(code >> (bits - 1 - i)) & 1 for i in range(bits)]).astype(bool)


def _sphere_hit(origin: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Ray parameter of the first hit of ``origin + t·direction`` with the sphere (inf if none)."""
    offset = origin - _SPHERE_CENTRE
    b = directions @ offset
    c = float(offset @ offset) - _SPHERE_RADIUS**2
    a = np.einsum("...i,...i->...", directions, directions)
    disc = b * b - a * c
    t = np.where(disc >= 0, (-b - np.sqrt(np.maximum(disc, 0))) / a, np.inf)
    return np.where(t > 1e-9, t, np.inf)


@node("synthetic.structured_light_scene", version=1)
def structured_light_scene(
    *,
    bits: Annotated[int, Field(ge=1, le=12)] = 8,
    width: Annotated[int, Field(ge=16, le=2048)] = 320,
    height: Annotated[int, Field(ge=16, le=2048)] = 240,
    projector_width: Annotated[int, Field(ge=2, le=8192)] = 1024,
    baseline: Positive = 0.25,
    noise: Annotated[float, Field(ge=0)] = 0.01,
    seed: Seed = 0,
) -> StructuredLightScene:
    r"""A camera and a projector beside it looking at a sphere before a slanted wall; the
    projector shows each Gray-code bit plane and its inverse, the camera captures them.

    The camera sits at the origin looking down +z (f = width, principal point at
    the centre); the projector, a pinhole of ``projector_width`` columns, sits
    ``baseline`` metres to its right with the same orientation. The wall's depth
    goes from 2.0 m (left edge) to 2.7 m (right edge); a sphere of radius 0.3 m sits
    1.5 m ahead. Each scene point shows albedo × (0.1 + 0.9 × pattern) of the
    projector pixel it lies in (points the sphere hides from the projector
    stay dark), plus Gaussian noise. Pixel centres are integers in the camera
    and the projector alike (principal points at :math:`(W - 1)/2`): projector
    pixel :math:`j` lights the columns :math:`[j - \tfrac12, j + \tfrac12)`.

    Parameters
    ----------
    bits : int
        Bit planes: :math:`2^{bits}` stripes across the projector.
    width, height : int
        Camera image size.
    projector_width : int
        Projector columns.
    baseline : float
        Camera-projector distance, metres.
    noise : float
        σ of the sensor noise (seeded).
    seed : int
        Seed of the albedo texture and the noise.

    Returns
    -------
    frames : Frames
        ``2·bits`` captures: bit plane i at ``2i``, its inverse at ``2i + 1``.
    depth : Depth
        The true depth of every camera pixel.
    camera, projector : Camera
    """
    rng = np.random.default_rng(seed)
    focal = float(width)
    K = np.array([[focal, 0, (width - 1) / 2], [0, focal, (height - 1) / 2], [0, 0, 1.0]])
    projector_height = int(round(projector_width * height / width))
    K_p = np.array(
        [
            [float(projector_width), 0, (projector_width - 1) / 2],
            [0, float(projector_width), (projector_height - 1) / 2],
            [0, 0, 1.0],
        ]
    )
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    rays = np.stack([(x - K[0, 2]) / focal, (y - K[1, 2]) / focal, np.ones_like(x)], axis=-1)
    # the wall z = 2.0 + 0.3 · (X + 1): along a ray X = z · rx, so z = (2.3) / (1 − 0.3 rx)
    wall = 2.3 / (1.0 - 0.3 * rays[..., 0])
    sphere = _sphere_hit(np.zeros(3), rays)
    depth = np.minimum(wall, sphere)
    points = rays * depth[..., None]
    centre_p = np.array([baseline, 0.0, 0.0])
    towards = points - centre_p
    lit = _sphere_hit(centre_p, towards) >= 1.0 - 1e-9  # nothing between projector and point
    columns = K_p[0, 0] * towards[..., 0] / towards[..., 2] + K_p[0, 2]
    pixel = np.floor(columns + 0.5)  # projector pixel j lights [j − ½, j + ½) about its centre
    lit &= (pixel >= 0) & (pixel < projector_width)
    planes = gray_code_stripes(np.where(lit, pixel, 0), bits, projector_width)
    from ..shared.separable import smooth_gaussian

    albedo = 0.35 + 0.6 * smooth_gaussian(rng.random((height, width)), 2.0)
    albedo = np.clip(albedo, 0.2, 1.0)
    frames = np.empty((2 * bits, height, width), np.float32)
    for i, plane in enumerate(planes):
        for j, shown in enumerate((plane, ~plane)):
            light = np.where(lit, 0.1 + 0.9 * shown, 0.1)
            captured = albedo * light + rng.normal(0.0, noise, light.shape)
            frames[2 * i + j] = np.clip(captured, 0.0, 1.0)
    size = np.array([width, height], np.int64)
    camera = PinholeCamera(K, size=size)
    projector = PinholeCamera(
        K_p, C=centre_p, size=np.array([projector_width, projector_height], np.int64)
    )
    return StructuredLightScene(frames, depth.astype(np.float32), camera, projector)
