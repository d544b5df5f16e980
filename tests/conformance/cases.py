"""Shared inputs of the conformance suite: for each op with more than one implementation,
the cases (inputs by port, parameters) every implementation runs on. Everything is
built here, seeded; the comparison is by the op's declared tolerance."""

from __future__ import annotations

from collections.abc import Callable
from functools import cache
from typing import Any

import numpy as np

import graphvision as gv

Case = tuple[dict[str, Any], dict[str, Any]]


@cache
def scene(rows: int = 72, cols: int = 96) -> np.ndarray:
    """A gray float32 scene: smooth shading, a bright rectangle, a dark disk, mild noise."""
    rng = np.random.default_rng(7)
    y, x = np.mgrid[0:rows, 0:cols]
    image = 0.3 + 0.2 * np.sin(x / 9.0) * np.cos(y / 13.0)
    image[15:40, 10:45] = 0.85
    image[(y - 45) ** 2 + (x - 70) ** 2 < 14**2] = 0.1
    image += rng.normal(0, 0.02, image.shape)
    return np.clip(image, 0, 1).astype(np.float32)


@cache
def colour_scene() -> np.ndarray:
    gray = scene()
    rng = np.random.default_rng(3)
    tint = rng.uniform(0.2, 1.0, (1, 1, 3))
    noise = rng.uniform(0, 1, (*gray.shape, 3))
    return np.clip(gray[..., None] * tint + 0.2 * noise, 0, 1).astype(np.float32)


@cache
def textured(rows: int = 64, cols: int = 64) -> np.ndarray:
    """Blurred noise: a texture with no flat window (well-conditioned correlation)."""
    import scipy.ndimage as ndi

    rng = np.random.default_rng(11)
    texture = ndi.gaussian_filter(rng.uniform(0, 1, (rows, cols)), 1.5)
    texture = (texture - texture.min()) / (texture.max() - texture.min())
    return texture.astype(np.float32)


def _kernel() -> np.ndarray:
    return np.array([[0.0, 1.0, 0.5], [-1.0, 2.0, 0.0], [0.25, 0.0, -0.75], [0.1, 0.2, 0.3]])


_BOUNDARIES = ("mirror", "replicate", "wrap", "zero", "crop")


def _filters() -> dict[str, list[Case]]:
    image, rgb = scene(), colour_scene()
    return {
        "filters.gaussian": [({"image": image}, {"sigma": s, "boundary": b})
                             for s in (0.8, 2.5) for b in _BOUNDARIES]
        + [({"image": rgb}, {"sigma": 1.5})],
        "filters.box": [({"image": image}, {"size": n, "boundary": b})
                        for n in (3, 9) for b in _BOUNDARIES] + [({"image": rgb}, {"size": 5})],
        "filters.median": [({"image": image}, {"size": n, "boundary": b})
                           for n in (1, 3, 5, 7) for b in _BOUNDARIES],
        "filters.correlate": [({"image": image, "kernel": _kernel()}, {"boundary": b})
                              for b in _BOUNDARIES],
        "filters.convolve": [({"image": image, "kernel": _kernel()}, {"boundary": b})
                             for b in _BOUNDARIES],
    }  # fmt: skip


def _pixels() -> dict[str, list[Case]]:
    image, rgb = scene(), colour_scene()
    mask = image > 0.5
    footprints = [np.ones((3, 5), bool), np.array([[1, 1, 0], [0, 1, 0], [0, 1, 1]], bool)]
    morphology = [({"image": i, "footprint": f}, {}) for i in (mask, image) for f in footprints]
    return {
        "colour.to_gray": [({"image": rgb}, {"method": m}) for m in ("mean", "luminance")],
        "colour.from_rgb": [({"image": rgb}, {"space": s}) for s in ("hsv", "lab", "ycbcr")],
        "edges.derivative": [({"image": image}, {"axis": a, "kind": k, "boundary": b})
                             for a in ("x", "y")
                             for k in ("forward", "central", "sobel", "prewitt", "gaussian")
                             for b in ("mirror", "replicate", "wrap", "zero")],
        "edges.canny": [({"image": image}, {"sigma": s}) for s in (1.0, 2.0)]
        + [({"image": image}, {"thresholds": "quantile", "low": 0.8, "high": 0.9})],
        "morphology.erode": morphology,
        "morphology.dilate": morphology,
        "morphology.open": morphology,
        "morphology.close": morphology,
        "threshold.otsu": [({"image": image}, {"foreground": f}) for f in ("bright", "dark")],
        "threshold.adaptive": [({"image": np.rint(image * 255) / np.float32(255)},
                                {"window": w, "c": c, "method": m, "foreground": f})
                               for w, c in ((11, 5 / 255), (25, -3 / 255))
                               for m in ("mean", "gaussian") for f in ("bright", "dark")],
        "regions.label": [({"mask": mask | (textured(72, 96) > 0.7)}, {"connectivity": c})
                          for c in (4, 8)],
    }  # fmt: skip


def _homography_case() -> Case:
    rng = np.random.default_rng(5)
    truth = np.array([[1.05, 0.04, 6.0], [-0.03, 0.97, -4.0], [2e-4, -1e-4, 1.0]])
    src = rng.uniform(0, 256, (80, 2))
    mapped = np.c_[src, np.ones(80)] @ truth.T
    dst = mapped[:, :2] / mapped[:, 2:] + rng.normal(0, 0.3, (80, 2))
    dst[:16] = rng.uniform(0, 256, (16, 2))  # 20 % outliers
    zero = np.zeros(80)
    keys = [gv.KeypointSet(p, zero + 1, zero, zero + 1) for p in (src, dst)]
    matches = gv.MatchSet(np.c_[np.arange(80), np.arange(80)], zero)
    return {"src": keys[0], "dst": keys[1], "matches": matches}, {"threshold": 2.0}


def _descriptors() -> Case:
    rng = np.random.default_rng(9)
    a = rng.normal(size=(120, 128))
    b = np.vstack([a[::-1] + rng.normal(0, 0.3, a.shape), rng.normal(size=(40, 128))])
    unit = lambda d: (d / np.linalg.norm(d, axis=1, keepdims=True)).astype(np.float32)  # noqa: E731
    return {"a": unit(a), "b": unit(b)}, {}


def _geometry() -> dict[str, list[Case]]:
    image = scene()
    tilt = np.array([[0.9, 0.1, 5.0], [-0.05, 1.1, 3.0], [1e-4, 2e-4, 1.0]])
    raw = colour_scene()[..., 1]
    inputs, _ = _descriptors()
    return {
        "pyramids.gaussian": [({"image": image}, {"levels": 4, "sigma": s}) for s in (1.0, 1.6)],
        "pyramids.match_template": [({"image": textured(), "template": textured()[20:35, 12:30]},
                                     {"method": m}) for m in ("correlation", "zero_mean", "ncc")],
        "features.sift": [({"image": scene(144, 192)}, {})],
        "matching.match": [(inputs, {"ratio": r, "symmetric": s})
                           for r in (0.8, 1.0) for s in (True, False)],
        "geometry.homography_ransac": [_homography_case()],
        "geometry.warp": [({"image": image, "homography": tilt}, {}),
                          ({"image": image, "homography": tilt}, {"width": 80, "height": 50})],
        "formation.demosaic": [({"raw": raw}, {"pattern": p, "method": m})
                               for p in ("RGGB", "BGGR", "GRBG", "GBRG")
                               for m in ("bilinear", "malvar")],
    }  # fmt: skip


def _essential(scene_: Any) -> np.ndarray:
    """E of the scene's true cameras, ``[t]× R`` of b relative to a (a at the origin)."""
    ca, cb = scene_.camera_a, scene_.camera_b
    R = cb.R @ ca.R.T
    t = cb.R @ (ca.C - cb.C)
    cross = np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]])
    return cross @ R


def _two_views() -> dict[str, list[Case]]:
    from graphvision_plugins.synthetic import two_view_scene

    scene_ = two_view_scene(count=150, noise=0.5, seed=4)
    a, b = scene_.a.copy(), scene_.b.copy()
    rng = np.random.default_rng(6)
    b[:20] = rng.uniform([0, 0], [640, 480], (20, 2))  # outliers
    K = np.array([[90.0, 0.0, 47.5], [0.0, 90.0, 35.5], [0.0, 0.0, 1.0]])
    lens = gv.PinholeCamera(K, distortion=np.array([-0.25, 0.06, 0.002, -0.001, 0.0]))
    return {
        "epipolar.fundamental": [({"a": a, "b": b}, {"threshold": 1.5})],
        "epipolar.essential_from_points": [({"a": a, "b": b, "camera_a": scene_.camera_a,
                                             "camera_b": scene_.camera_b}, {})],
        "epipolar.triangulate": [({"a": scene_.a, "b": scene_.b, "camera_a": scene_.camera_a,
                                   "camera_b": scene_.camera_b}, {"method": m})
                                 for m in ("linear", "nonlinear")],
        "epipolar.relative_pose": [({"E": _essential(scene_), "a": scene_.a, "b": scene_.b,
                                     "camera_a": scene_.camera_a, "camera_b": scene_.camera_b},
                                    {})],
        "camera.undistort_image": [({"image": scene(), "camera": lens}, {}),
                                   ({"image": colour_scene(), "camera": lens}, {})],
    }  # fmt: skip


def _segments(rows: int = 90, cols: int = 120) -> np.ndarray:
    """An edge mask of four 1-px segments at different angles (rasterised by hand)."""
    edges = np.zeros((rows, cols), bool)
    for (x0, y0), (x1, y1) in [((5, 10), (110, 30)), ((20, 80), (100, 60)),
                               ((60, 5), (60, 85)), ((10, 50), (115, 52))]:  # fmt: skip
        steps = max(abs(x1 - x0), abs(y1 - y0)) + 1
        xs = np.rint(np.linspace(x0, x1, steps)).astype(int)
        ys = np.rint(np.linspace(y0, y1, steps)).astype(int)
        edges[ys, xs] = True
    return edges


def _disks(rows: int = 100, cols: int = 140) -> tuple[np.ndarray, np.ndarray]:
    """Two bright disks and a dark one on gray, mild noise, and their rims as edges."""
    y, x = np.mgrid[0:rows, 0:cols]
    image = np.full((rows, cols), 0.45)
    edges = np.zeros((rows, cols), bool)
    for cx, cy, r, value in [(30, 30, 14.3, 0.95), (100, 45, 12.6, 0.05), (60, 72, 18.4, 0.9)]:
        d = np.hypot(x - cx, y - cy)
        image[d < r] = value
        edges |= np.abs(d - r) < 0.5
    image += np.random.default_rng(2).normal(0, 0.02, image.shape)
    return edges, np.clip(image, 0, 1).astype(np.float32)


@cache
def _stereo_pair(rows: int = 128, cols: int = 256) -> tuple[np.ndarray, np.ndarray]:
    """A rectified pair of blurred noise: disparity 8 with a rectangle at 14 in front,
    ``left(x) = right(x - d)``."""
    import scipy.ndimage as ndi

    rng = np.random.default_rng(12)
    texture = ndi.gaussian_filter(rng.uniform(0, 1, (rows, cols + 40)), 1.2)
    texture = (texture - texture.min()) / (texture.max() - texture.min())
    disparity = np.full((rows, cols), 8.0)
    disparity[40:100, 100:180] = 14.0
    x, grid = np.arange(cols), np.arange(-20, cols + 20)
    left = np.stack([np.interp(x - disparity[r], grid, texture[r]) for r in range(rows)])
    return left.astype(np.float32), texture[:, 20 : 20 + cols].astype(np.float32)


def _stereo() -> dict[str, list[Case]]:
    left, right = _stereo_pair()
    pair = {"left": left, "right": right}
    return {
        "stereo.block_match": [(pair, {"num_disparities": 24, **p})
                               for p in ({}, {"cost": "sad", "window": 9},
                                         {"cost": "sad", "window": 9, "subpixel": False},
                                         {"min_disparity": 4, "num_disparities": 20})],
        "stereo.sgm": [(pair, {"num_disparities": 24, **p})
                       for p in ({}, {"paths": 4}, {"min_disparity": 4, "num_disparities": 20},
                                 {"subpixel": False, "lr_tolerance": None})],
    }  # fmt: skip


def _rectification() -> dict[str, list[Case]]:
    from graphvision_plugins.synthetic import stereo_pair, two_view_scene

    pairs = [two_view_scene(noise=0.0, seed=seed) for seed in range(3)]
    image = stereo_pair(width=64, height=48).left
    turn = np.array([[0.98, 0.05, 3.0], [-0.04, 1.02, 2.0], [1e-4, -2e-4, 1.0]])
    shift = np.array([[1.0, 0.0, 3.0], [0.0, 1.0, 2.0], [0.0, 0.0, 1.0]])
    return {
        "stereo.rectify_calibrated": [({"camera_a": p.camera_a, "camera_b": p.camera_b}, {})
                                      for p in pairs],
        "stereo.rectify_pair": [({"left": image, "right": image, "H_a": turn, "H_b": shift}, {})],
    }  # fmt: skip


def _boards() -> dict[str, list[Case]]:
    from graphvision_plugins.synthetic import board_views

    views = board_views(views=3, width=320, height=240, focal=400.0, seed=1).views
    square = board_views(views=1, columns=5, rows=5, width=240, height=240, seed=2).views
    board = board_views(views=6, width=320, height=240, focal=400.0, noise=0.0, seed=3)
    corners = board.corners + np.random.default_rng(1).normal(0, 0.1, board.corners.shape)
    calibration = {"corners": corners, "object_points": board.object_points}
    return {
        "camera.calibrate_board": [(calibration, p) for p in ({}, {"radial": 1},
                                                               {"tangential": True})],
        "camera.board_corners": [({"views": views}, {}),
                                 ({"views": square}, {"columns": 5, "rows": 5})],
    }  # fmt: skip


def _hough() -> dict[str, list[Case]]:
    edges, disks = _disks()
    circles = {"min_radius": 8.0, "max_radius": 25.0}
    return {
        "hough.circles": [({"edges": edges, "image": disks}, {**circles, "polarity": p})
                          for p in ("both", "bright", "dark")],
        "hough.lines": [({"edges": _segments()}, {}),
                        ({"edges": _segments()}, {"theta_bins": 360, "rho_step": 0.5,
                                                  "min_distance": 10})],
    }  # fmt: skip


def _faces() -> dict[str, list[Case]]:
    from graphvision_plugins.recognition import lbp_cascade
    from graphvision_plugins.synthetic import face_scenes

    images = face_scenes(seed=0).images[1:4]  # 2, 3 and 3 faces (lfw and the astronaut)
    cascade = lbp_cascade()
    return {"recognition.lbp_detect": [({"image": i, "cascade": cascade}, {}) for i in images]}


Builder = Callable[[], dict[str, list[Case]]]
CASE_BUILDERS: list[Builder] = [
    _filters, _pixels, _geometry, _two_views, _hough, _stereo, _rectification, _boards, _faces,
]  # fmt: skip


def all_cases() -> dict[str, list[Case]]:
    cases: dict[str, list[Case]] = {}
    for builder in CASE_BUILDERS:
        cases.update(builder())
    return cases
