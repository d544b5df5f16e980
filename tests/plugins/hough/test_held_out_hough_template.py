"""Hough lines, the generalised Hough transform and multi-scale template matching on scenes
unlike the shipped ones (issue 24, items 3, 6 and 8).

Every scene is drawn here from a seed, with its truth: a texture that is a sum of random
sinusoids evaluated at any scale, polygons of random contrast on a textured ground, a
shape with occluded and with look-alike copies.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
import pytest
import skimage.data
import skimage.draw

from graphvision_plugins import edges, hough, pyramids
from graphvision_plugins.shared.separable import smooth_gaussian

# --- multi-scale template matching (item 6) ---------------------------------------------


def sinusoid_texture(seed: int, waves: int = 48) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """A smooth random texture ``f(x, y)`` defined at every real point: a sum of sinusoids of
    random direction, 9 to 67 pixels a period, so that any scale of it can be sampled exactly."""
    rng = np.random.default_rng(seed)
    frequency = rng.uniform(0.015, 0.11, waves)
    direction = rng.uniform(0.0, 2 * math.pi, waves)
    u, v = frequency * np.cos(direction), frequency * np.sin(direction)
    amplitude = rng.uniform(0.3, 1.0, waves) * 0.16 / math.sqrt(waves)
    phase = rng.uniform(0.0, 2 * math.pi, waves)

    def texture(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        out = np.full(np.broadcast(x, y).shape, 0.5)
        for k in range(waves):
            out += amplitude[k] * np.cos(2 * math.pi * (u[k] * x + v[k] * y) + phase[k])
        return np.clip(out, 0.0, 1.0)

    return texture


class ScaledScene(NamedTuple):
    image: np.ndarray
    template: np.ndarray
    centre: np.ndarray  # the template's centre in the image, (x, y)
    scale: float


def scaled_scene(scale: float, seed: int = 5, shape: tuple[int, int] = (311, 427)) -> ScaledScene:
    """The texture at scale 1 cut to a 33×41 template, and an image of the texture magnified by
    ``scale``: pixel ``X`` of the image samples the texture at ``(X + ½) / scale − ½`` (pixel
    centres at integers, pixels of side ``scale``), so the template's centre
    ``c`` is at ``(c + ½) · scale − ½``. The template is cut near the bottom-right corner,
    where a wrong factor moves the mapped peak the most."""
    texture = sinusoid_texture(seed)
    h, w = 33, 41
    height, width = shape
    x0 = int((width + 0.5) / scale - 0.5) - w - 12
    y0 = int((height + 0.5) / scale - 0.5) - h - 9
    rows, cols = np.mgrid[0:h, 0:w].astype(np.float64)
    template = texture(cols + x0, rows + y0)
    rows, cols = np.mgrid[0:height, 0:width].astype(np.float64)
    image = texture((cols + 0.5) / scale - 0.5, (rows + 0.5) / scale - 0.5)
    centre = (np.array([x0 + (w - 1) / 2, y0 + (h - 1) / 2]) + 0.5) * scale - 0.5
    return ScaledScene(image.astype(np.float32), template.astype(np.float32), centre, scale)


MULTISCALE_GRID = {"min_scale": 0.6, "max_scale": 1.8, "steps": 13}


@pytest.mark.parametrize("index", [2, 9])
def test_multiscale_match_maps_its_peak_back_with_the_factor_the_image_was_resized_by(index):
    """311×427 resized by 1/0.7206 is 432×593 (not 431.6×592.6): mapping the peak back with
    the nominal 0.7206 misplaced it by 0.31 px (0.46 px at 1.368); with 311/432 and 427/593,
    by 0.01 px."""
    scale = float(np.geomspace(0.6, 1.8, 13)[index])  # a scale the search tries exactly
    scene = scaled_scene(scale)
    found = pyramids.match_multiscale(scene.image, scene.template, **MULTISCALE_GRID)
    assert found.score > 0.98
    assert abs(found.scale / scale - 1) < 0.01
    assert np.linalg.norm(found.location[0] - scene.centre) < 0.05


# --- Hough lines (item 8) -----------------------------------------------------------------


def rectangles_scene(
    seed: int, count: int = 27, shape: tuple[int, int] = (440, 600)
) -> tuple[np.ndarray, np.ndarray]:
    """Turned rectangles (sides 44–60 px) of random grey, brighter or darker than a faintly
    textured ground by 0.1–0.42, blurred (σ 0.7) with noise (σ 0.01); and the true sides as
    ``(ρ, θ, x, y)`` rows, ``(x, y)`` the side's middle. No two sides of different rectangles
    lie near one line (a line through both middles within 10° of both), so every true line
    is one side."""
    rng = np.random.default_rng(seed)
    height, width = shape
    image = 0.5 + 0.3 * (smooth_gaussian(rng.random(shape), 3.0) - 0.5)
    sides: list[tuple[float, float, float, float]] = []
    placed: list[tuple[np.ndarray, float]] = []
    for _ in range(5000):
        if len(placed) == count:
            break
        a, b = rng.uniform(44, 60, 2)
        turn = rng.uniform(0, math.pi)
        centre = rng.uniform([40, 40], [width - 40, height - 40])
        radius = 0.5 * math.hypot(a, b)
        if any(np.hypot(*(centre - c)) < radius + r + 3 for c, r in placed):
            continue
        rotation = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
        half = np.array([[-a, -b], [a, -b], [a, b], [-a, b]]) / 2
        corners = half @ rotation.T + centre
        if (
            corners.min() < 3
            or (corners[:, 0] > width - 4).any()
            or (corners[:, 1] > height - 4).any()
        ):
            continue
        new = []
        for k in range(4):
            p, q = corners[k], corners[(k + 1) % 4]
            theta = math.atan2(q[0] - p[0], -(q[1] - p[1]))  # the normal (dy, -dx) of p → q
            theta %= math.pi
            rho = p[0] * math.cos(theta) + p[1] * math.sin(theta)
            new.append((rho, theta, *(0.5 * (p + q))))
        if any(_bridged(s, t) for s in new for t in sides):
            continue
        placed.append((centre, radius))
        sides += new
        level = rng.choice([-1.0, 1.0]) * rng.uniform(0.1, 0.42)
        rows, cols = skimage.draw.polygon(corners[:, 1], corners[:, 0], shape)
        image[rows, cols] += level
    image = smooth_gaussian(image, 0.7) + rng.normal(0, 0.01, shape)
    return np.clip(image, 0, 1).astype(np.float32), np.array(sides)


def _bridged(a: tuple[float, ...], b: tuple[float, ...]) -> bool:
    """Whether one line could pass near both sides: their directions and the direction
    between their middles all within 10°."""
    joint = math.atan2(b[3] - a[3], b[2] - a[2]) + math.pi / 2  # normal of the joining line
    gaps = [
        abs(math.remainder(a[1] - b[1], math.pi)),
        abs(math.remainder(joint - a[1], math.pi)),
        abs(math.remainder(joint - b[1], math.pi)),
    ]
    return max(gaps) < math.radians(10)


def matched_lines(found: np.ndarray, truth: np.ndarray, degrees: float = 2.0, pixels: float = 2.0):
    """How many true sides a found line matches (within ``degrees`` of the side and passing
    within ``pixels`` of its middle; each found line used once), and how many found lines
    match none."""
    used = np.zeros(len(found), dtype=bool)
    for _, theta, mx, my in truth:
        gap = np.abs(found[:, 1] - theta)
        gap = np.minimum(gap, math.pi - gap)
        off = np.abs(mx * np.cos(found[:, 1]) + my * np.sin(found[:, 1]) - found[:, 0])
        fits = (gap <= math.radians(degrees)) & (off <= pixels) & ~used
        if fits.any():
            used[np.argmax(fits)] = True
    return int(used.sum()), int((~used).sum())


@pytest.mark.parametrize("seed", [3, 5])
def test_hough_lines_defaults_find_the_sides_of_rectangles_of_any_contrast(seed):
    """The old default (half the strongest smoothed, magnitude-weighted peak) kept 26 of 96
    and 9 of 92 sides: votes grow with contrast, and a short side far from the foot of its
    normal has a sheared, low peak. scikit-image's defaults keep 91 and 63 (with 23 and 12
    false lines)."""
    image, truth = rectangles_scene(seed)
    found = edges.canny(image, sigma=1.0, low=0.02, high=0.04).edges
    lines = hough.hough_lines(found, image)
    hits, false = matched_lines(lines.lines, truth)
    assert hits >= 0.9 * len(truth)
    assert false <= 0.08 * len(truth)


# --- generalised Hough transform (item 3) -----------------------------------------------

ARROW = np.array([[0, 12], [30, 12], [30, 0], [52, 22], [30, 44], [30, 32], [0, 32]], float)
STAIRS = np.array([[0, 0], [14, 0], [14, 12], [28, 12], [28, 24], [42, 24], [42, 36], [0, 36]])


def fill(image: np.ndarray, polygon: np.ndarray, value: float) -> None:
    rows, cols = skimage.draw.polygon(polygon[:, 1], polygon[:, 0], image.shape)
    image[rows, cols] = value


def shape_model(polygon: np.ndarray, blur: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """The polygon, bright on dark, 10 px from the top-left of its picture; its Canny edges."""
    image = np.full((int(polygon[:, 1].max()) + 21, int(polygon[:, 0].max()) + 21), 0.25)
    fill(image, polygon.astype(np.float64) + 10, 0.75)
    if blur:
        image = smooth_gaussian(image, blur)
    image = image.astype(np.float32)
    return image, edges.canny(image, sigma=1.0).edges


@pytest.mark.parametrize("vote_sigma", [0.0, 1.0, 2.5])
def test_a_copy_of_the_model_scores_one_whatever_the_vote_spread(vote_sigma):
    """The old score was the peak of the spread votes over the model's point count: 1.0,
    2.9 and 7.4 for the same copy (neighbours' votes along an edge land beside each other)."""
    model, model_edges = shape_model(ARROW, blur=0.6)
    scene = np.full((110, 150), 0.25, np.float32)
    scene[30 : 30 + model.shape[0], 55 : 55 + model.shape[1]] = model
    found = hough.generalized_hough(
        edges.canny(scene, sigma=1.0).edges, scene, model_edges, model, vote_sigma=vote_sigma
    )
    assert found.count == 1
    assert found.scores[0] == pytest.approx(1.0)
    rows, cols = np.nonzero(model_edges)
    assert np.linalg.norm(found.locations[0] - (cols.mean() + 55, rows.mean() + 30)) < 0.5


@pytest.mark.parametrize(("polygon", "vote_sigma"), [(STAIRS, 1.0), (STAIRS, 2.0), (ARROW, 2.0)])
def test_a_copy_shifted_along_its_own_edges_is_not_a_second_instance(polygon, vote_sigma):
    """Sharp (unblurred) shapes at a fractional offset: the old scores of the shifted copies
    on the ridges of the votes were 0.87 (stairs, σ 1), 1.76 (σ 2) and 0.40 (arrow, σ 2),
    above its threshold 0.3. A stair shifted by one step finds 28 % of the stairs again."""
    model, model_edges = shape_model(polygon)
    scene = np.full((160, 200), 0.25)
    fill(scene, polygon + np.array([83.3, 61.7]), 0.75)
    scene = scene.astype(np.float32)
    found = hough.generalized_hough(
        edges.canny(scene, sigma=1.0).edges, scene, model_edges, model, vote_sigma=vote_sigma
    )
    assert found.count == 1
    assert found.scores[0] > 0.95


class ArrowScene(NamedTuple):
    image: np.ndarray
    references: np.ndarray  # (2, 2): the true reference point of the full and the partial arrow
    visible: np.ndarray  # (2,): the fraction of the model's edge points not hidden


GROUNDS = ("gravel", "brick", "grass")


def arrow_scene(seed: int, ground: str) -> ArrowScene:
    """A 240×320 crop of a photographed texture (``skimage.data``) at 0.5 ± 0.15, 12 random
    polygons, a whole arrow turned by 10° and an arrow (unturned) whose head a flat patch
    hides; blurred (σ 0.6) with noise (σ 0.015)."""
    rng = np.random.default_rng(seed)
    height, width = 240, 320
    texture = getattr(skimage.data, ground)().astype(np.float64)
    texture = (texture.mean(axis=2) if texture.ndim == 3 else texture) / 255
    top = rng.integers(0, texture.shape[0] - height)
    left = rng.integers(0, texture.shape[1] - width)
    crop = texture[top : top + height, left : left + width]
    image = 0.5 + 0.3 * (crop - crop.mean()) / max(float(np.ptp(crop)), 1e-6)
    for _ in range(12):
        centre = rng.uniform([20, 20], [width - 20, height - 20])
        corners = int(rng.integers(3, 6))
        angles = np.sort(rng.uniform(0, 2 * math.pi, corners))
        radius = rng.uniform(8, 20, corners)
        fill(
            image,
            centre + radius[:, None] * np.column_stack([np.cos(angles), np.sin(angles)]),
            rng.uniform(0.1, 0.9),
        )
    _, model_edges = shape_model(ARROW, blur=0.6)
    rows, cols = np.nonzero(model_edges)
    model_points = np.column_stack([cols, rows]).astype(np.float64)
    pivot = ARROW.mean(axis=0) + 10  # the polygon's centre in the model picture
    references, visible = [], []
    for turn, offset, hidden in ((10.0, (60.0, 150.0), None), (0.0, (205.0, 45.0), (236.0, 277.0))):
        a = math.radians(turn)
        rotation = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
        centre = ARROW.mean(axis=0) + offset
        fill(image, (ARROW - ARROW.mean(axis=0)) @ rotation.T + centre, 0.85)
        placed = (model_points - pivot) @ rotation.T + centre
        references.append(placed.mean(axis=0))
        if hidden is None:
            visible.append(1.0)
            continue
        fill(
            image,
            np.array([[hidden[0], 20], [hidden[1], 20], [hidden[1], 110], [hidden[0], 110]]),
            0.5,
        )
        visible.append(float(np.mean(placed[:, 0] < hidden[0] - 1.5)))
    image = smooth_gaussian(image, 0.6) + rng.normal(0, 0.015, image.shape)
    return ArrowScene(
        np.clip(image, 0, 1).astype(np.float32), np.array(references), np.array(visible)
    )


@pytest.mark.parametrize("ground", GROUNDS)
def test_whole_and_partly_hidden_arrows_are_found_with_the_fraction_seen(ground):
    """Over 24 such scenes (seeds 0–7 a ground, bench/bench_held_out_geometry.py) clutter
    scores at most 0.25, the partly hidden arrow (63 % of its outline visible) 0.48 to 0.63
    and the whole one 0.87 to 1: the default threshold 0.4 lies between."""
    scene = arrow_scene(7, ground)
    model, model_edges = shape_model(ARROW, blur=0.6)
    found = hough.generalized_hough(
        edges.canny(scene.image, sigma=1.0).edges,
        scene.image,
        model_edges,
        model,
        rotations=[-20.0, -10.0, 0.0, 10.0, 20.0],
    )
    assert found.count == 2
    gaps = np.linalg.norm(found.locations[:, None] - scene.references[None], axis=2)
    order = gaps.argmin(axis=0)
    assert sorted(order.tolist()) == [0, 1] and gaps.min(axis=0).max() < 1.0
    np.testing.assert_array_equal(found.angles[order], [10.0, 0.0])
    whole, hidden = found.scores[order]
    assert 0.85 <= whole <= 1.0
    assert 0.4 <= hidden <= scene.visible[1] + 0.05
