"""Structured light on a scene the decoder was never tuned on (issue 24, item 2).

The projector sits on the camera's *left*, turned 8° towards the scene; the scene is a
plane slanted in x and y with a vertical cylinder before it; every camera pixel integrates
the light over its area (4×4 sub-rays), and projector pixel ``j`` lights the columns
``[j − ½, j + ½)`` about its centre, as its calibration matrix (principal point at
``(W − 1) / 2``) says. The renderer is written here, independently of
``synthetic.structured_light_scene``, so the two cannot share a convention by accident.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import pytest

from graphvision import PinholeCamera
from graphvision_plugins import stereo, synthetic

SUPERSAMPLE = 4
_CYLINDER = (0.06, 1.32, 0.17)  # axis x, axis z (vertical axis), radius, metres


class HeldOutScene(NamedTuple):
    frames: np.ndarray
    depth: np.ndarray
    camera: PinholeCamera
    projector: PinholeCamera
    bits: int


def _turn_y(degrees: float) -> np.ndarray:
    """World-to-device rotation of a device whose optical axis is turned ``degrees`` about
    the vertical axis, towards +x (rows: the device's x, y, z axes in world coordinates)."""
    a = math.radians(degrees)
    return np.array(
        [[math.cos(a), 0.0, -math.sin(a)], [0.0, 1.0, 0.0], [math.sin(a), 0.0, math.cos(a)]]
    )


def _surface_hit(origin: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Ray parameter of the first hit of ``origin + t·d`` with the plane
    ``z = 1.85 + 0.12 x + 0.3 y`` or the vertical cylinder (inf if none)."""
    d = directions
    # plane: o_z + t d_z = 1.85 + 0.12 (o_x + t d_x) + 0.3 (o_y + t d_y)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_plane = (1.85 + 0.12 * origin[0] + 0.3 * origin[1] - origin[2]) / (
            d[..., 2] - 0.12 * d[..., 0] - 0.3 * d[..., 1]
        )
    t_plane = np.where(t_plane > 1e-9, t_plane, np.inf)
    cx, cz, radius = _CYLINDER
    ox, oz = origin[0] - cx, origin[2] - cz
    a = d[..., 0] ** 2 + d[..., 2] ** 2
    b = d[..., 0] * ox + d[..., 2] * oz
    c = ox * ox + oz * oz - radius**2
    disc = b * b - a * c
    t_cyl = np.where(disc >= 0, (-b - np.sqrt(np.maximum(disc, 0.0))) / a, np.inf)
    t_cyl = np.where(t_cyl > 1e-9, t_cyl, np.inf)
    return np.minimum(t_plane, t_cyl)


def held_out_scene(
    *, bits: int = 8, projector_width: int = 768, noise: float = 0.012, seed: int = 11
) -> HeldOutScene:
    """Render the captures of the Gray-code planes and their inverses, with area integration."""
    rng = np.random.default_rng(seed)
    width, height = 224, 168
    focal = 1.3 * width
    K = np.array([[focal, 0, (width - 1) / 2 + 3.0], [0, focal, (height - 1) / 2 - 2.0], [0, 0, 1]])
    projector_height = 600
    K_p = np.array(
        [
            [1.4 * projector_width, 0, (projector_width - 1) / 2],
            [0, 1.4 * projector_width, (projector_height - 1) / 2],
            [0, 0, 1],
        ]
    )
    centre_p = np.array([-0.22, 0.015, 0.0])
    R_p = _turn_y(8.0)
    # sub-ray offsets within a pixel: the centres of an S×S grid over [−½, ½)²
    sub = (np.arange(SUPERSAMPLE) + 0.5) / SUPERSAMPLE - 0.5
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    sx, sy = np.broadcast_arrays(
        x[..., None, None] + sub[None, None, None, :], y[..., None, None] + sub[:, None]
    )
    rays = np.stack([(sx - K[0, 2]) / focal, (sy - K[1, 2]) / focal, np.ones_like(sx)], axis=-1)
    t = _surface_hit(np.zeros(3), rays)
    points = rays * t[..., None]
    towards = points - centre_p
    lit = _surface_hit(centre_p, towards) >= 1.0 - 1e-6  # nothing between projector and point
    in_projector = towards @ R_p.T
    u = K_p[0, 0] * in_projector[..., 0] / in_projector[..., 2] + K_p[0, 2]
    column = np.floor(u + 0.5)  # projector pixel j covers [j − ½, j + ½)
    lit &= (column >= 0) & (column < projector_width) & (in_projector[..., 2] > 0)
    planes = synthetic.gray_code_stripes(np.where(lit, column, 0), bits, projector_width)
    centre_rays = np.stack([(x - K[0, 2]) / focal, (y - K[1, 2]) / focal, np.ones_like(x)], axis=-1)
    depth = _surface_hit(np.zeros(3), centre_rays)  # ray z = 1: t is the depth
    texture = rng.random((height // 6 + 2, width // 6 + 2))
    albedo = 0.3 + 0.6 * np.kron(texture, np.ones((6, 6)))[:height, :width]  # blocky albedo
    frames = np.empty((2 * bits, height, width), np.float32)
    for i, plane in enumerate(planes):
        for j, shown in enumerate((plane, ~plane)):
            light = np.where(lit, 0.08 + 0.92 * shown, 0.08).mean(axis=(-2, -1))
            captured = albedo * light + rng.normal(0.0, noise, light.shape)
            frames[2 * i + j] = np.clip(captured, 0.0, 1.0)
    camera = PinholeCamera(K, size=np.array([width, height]))
    projector = PinholeCamera(
        K_p, R=R_p, C=centre_p, size=np.array([projector_width, projector_height])
    )
    return HeldOutScene(frames, depth.astype(np.float32), camera, projector, bits)


def half_pixel_depth(scene: HeldOutScene, stripes: np.ndarray) -> float:
    """Mean |Z(u + ½) − Z(u)| over the decoded pixels: the depth a half-pixel error in the
    projector column makes, through the decoder's own ray-plane geometry."""
    per_stripe = scene.projector.size[0] / 2**scene.bits
    at = stereo.depth_from_stripes(stripes, scene.bits, scene.camera, scene.projector)
    moved = stereo.depth_from_stripes(
        stripes + np.float32(0.5 / per_stripe), scene.bits, scene.camera, scene.projector
    )
    return float(np.nanmean(np.abs(moved - at)))


def depth_errors(scene: HeldOutScene) -> tuple[np.ndarray, float]:
    """Decoded minus true depth where decoded, away from occlusion edges (5 cm gate), and
    the depth of half a projector pixel there."""
    decoded = stereo.decode_gray_code(scene.frames)
    depth = stereo.depth_from_stripes(decoded.stripes, decoded.bits, scene.camera, scene.projector)
    error = (depth - scene.depth)[np.isfinite(depth)]
    return error[np.abs(error) < 0.05], half_pixel_depth(scene, decoded.stripes)


@pytest.mark.parametrize(("bits", "projector_width"), [(8, 768), (7, 912)])
def test_structured_light_has_no_half_pixel_bias_with_the_projector_turned_on_the_left(
    bits, projector_width
):
    """912 columns over 128 stripes is 7.125 columns a stripe: the stripe's middle column
    must come from the columns it really holds, not from ``(s + ½) · W / 2^bits``."""
    scene = held_out_scene(bits=bits, projector_width=projector_width)
    errors, half = depth_errors(scene)
    assert errors.size > 0.5 * scene.depth.size  # the cylinder's shadow and the sides are dark
    assert half > 4e-3  # half a projector pixel is about 5 mm of depth here
    # the old decoder's mean error: −0.99 (768) and −0.12 (912) of half a pixel's depth
    assert abs(float(np.mean(errors))) < 0.1 * half
    # the rest is the quantisation of the column to its stripe: uniform, σ = w / √12
    stripe = scene.projector.size[0] / 2**bits
    assert float(np.sqrt(np.mean(errors**2))) < 1.2 * 2 * half * stripe / math.sqrt(12)


def test_the_synthetic_scene_lights_each_projector_pixel_about_its_centre():
    """``synthetic.structured_light_scene`` and this renderer agree: decoding its captures
    has no bias either (the decoder and the generator once shared the corner convention)."""
    scene = synthetic.structured_light_scene(bits=9, width=200, height=150, seed=4)
    decoded = stereo.decode_gray_code(scene.frames)
    depth = stereo.depth_from_stripes(decoded.stripes, decoded.bits, scene.camera, scene.projector)
    error = (depth - scene.depth)[np.isfinite(depth)]
    error = error[np.abs(error) < 0.05]
    # |∂Z/∂u| = Z² / (b f): half a pixel is ≥ 0.5 · 2.0² / (0.25 · 1024) = 7.8 mm on the wall
    assert abs(float(np.mean(error))) < 1e-3
