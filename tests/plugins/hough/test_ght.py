"""The generalised Hough transform finds a drawn shape in clutter, also rotated."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.ndimage as ndi
import skimage.draw

from graphvision_plugins import edges, hough

L_SHAPE = np.array([[0, 0], [40, 0], [40, 12], [14, 12], [14, 30], [0, 30]], dtype=np.float64)


def draw_shape(shape: tuple[int, int], offset: tuple[float, float], angle: float = 0.0):
    """The L polygon, turned by ``angle`` degrees about its vertices' mean, then shifted."""
    image = np.full(shape, 0.2)
    centre = L_SHAPE.mean(axis=0)
    a = math.radians(angle)
    turn = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    polygon = (L_SHAPE - centre) @ turn.T + centre + offset
    rows, cols = skimage.draw.polygon(polygon[:, 1], polygon[:, 0], shape)
    image[rows, cols] = 0.8
    return image, turn, centre + np.asarray(offset)


def cluttered_scene(offset, angle, seed):
    scene, turn, pivot = draw_shape((160, 200), offset, angle)
    rng = np.random.default_rng(seed)
    for _ in range(12):  # discs that must not be taken for the L
        centre = (rng.integers(0, 150), rng.integers(0, 190))
        rows, cols = skimage.draw.disk(centre, rng.integers(4, 12), shape=scene.shape)
        scene[rows, cols] = rng.uniform(0.3, 1.0)
    noisy = np.clip(scene + rng.normal(0, 0.03, scene.shape), 0, 1).astype(np.float32)
    return noisy, turn, pivot


@pytest.mark.parametrize(("angle", "seed"), [(0.0, 0), (0.0, 1), (20.0, 2)])
def test_shape_found_within_one_pixel(angle, seed):
    model, _, model_pivot = draw_shape((50, 60), (10, 10))
    model = model.astype(np.float32)
    model_edges = edges.canny(model, sigma=1.0).edges
    scene, turn, pivot = cluttered_scene((120, 70), angle, seed)
    found = hough.generalized_hough(
        edges.canny(scene, sigma=1.0).edges,
        scene,
        model_edges,
        model,
        rotations=[-30.0, -20.0, -10.0, 0.0, 10.0, 20.0, 30.0] if angle else [0.0],
    )
    # truth: the model's reference point (centroid of its edge points) carried by the same
    # rotation about the polygon's centre and the same shift as the drawn shape
    rows, cols = np.nonzero(model_edges)
    reference = np.array([cols.mean(), rows.mean()])
    truth = (reference - model_pivot) @ turn.T + pivot
    assert found.count == 1
    assert np.linalg.norm(found.locations[0] - truth) <= 1.0
    assert found.angles[0] == angle
    drawing = hough.draw_instances(
        scene, found.locations, model_edges, model, found.angles, found.scales
    )
    # the model's edge points land on (within 2 px of) the scene's edges of the shape
    green = (drawing[..., 1] > 0.9) & (drawing[..., 0] < 0.2)
    scene_edges = edges.canny(scene, sigma=1.0).edges
    near = ndi.binary_dilation(scene_edges, np.ones((5, 5), bool))  # within 2 px
    assert green.sum() > 50 and (green & near).sum() >= 0.9 * green.sum()


def test_empty_model_is_refused():
    image = np.zeros((20, 20), np.float32)
    mask = np.zeros((20, 20), bool)
    with pytest.raises(ValueError, match="model_edges has no edge point"):
        hough.generalized_hough(mask, image, mask, image)


def test_no_edges_no_instance():
    model, _, _ = draw_shape((50, 60), (10, 10))
    model = model.astype(np.float32)
    flat = np.full((40, 40), 0.5, np.float32)
    found = hough.generalized_hough(np.zeros((40, 40), bool), flat, edges.canny(model).edges, model)
    assert found.count == 0 and found.locations.shape == (0, 2)
