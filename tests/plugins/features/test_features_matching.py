"""Detectors, descriptors and matching against synthetic truth and known warps."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.ndimage as ndi
import skimage.data

import graphvision as gv
from graphvision_plugins import features, geometry, matching, synthetic


@pytest.fixture(scope="module")
def astronaut():
    return (skimage.data.astronaut().mean(axis=2) / 255).astype(np.float32)


@pytest.fixture(scope="module")
def astronaut_features(astronaut):
    return features.sift(astronaut)


def square_image(size=64, lo=16, hi=48):
    image = np.zeros((size, size), np.float32)
    image[lo:hi, lo:hi] = 1.0
    return ndi.gaussian_filter(image, 1.0)


def test_harris_finds_the_four_corners_of_a_square():
    found = features.harris(square_image(), max_keypoints=4)
    expected = np.array([[16, 16], [47, 16], [16, 47], [47, 47]], float)
    for corner in expected:
        assert np.linalg.norm(found.xy - corner, axis=1).min() <= 2.0
    edges = features.harris(square_image(), threshold_rel=0.1)
    assert len(edges) == 4  # edges and flat areas give no corner


def test_hessian_and_log_find_a_blob_and_its_scale():
    yy, xx = np.mgrid[:80, :80]
    radius = 8.0
    blob = (((yy - 40) ** 2 + (xx - 30) ** 2) <= radius**2).astype(np.float32)
    strongest = features.hessian(ndi.gaussian_filter(blob, 1.0), sigma=4.0, max_keypoints=1)
    np.testing.assert_allclose(strongest.xy[0], [30, 40], atol=1.0)
    blobs = features.log_blobs(blob, min_sigma=2, max_sigma=12, scales=21, max_keypoints=1)
    np.testing.assert_allclose(blobs.xy[0], [30, 40], atol=1.0)
    # a disk of radius r responds most at sigma = r / sqrt(2) (Lindeberg)
    assert blobs.scale[0] == pytest.approx(radius / np.sqrt(2), rel=0.15)


def test_sift_features_are_well_formed(astronaut_features):
    kp, desc = astronaut_features
    assert len(kp) > 500 and desc.shape == (len(kp), 128) and desc.dtype == np.float32
    np.testing.assert_allclose(np.linalg.norm(desc, axis=1), 1.0, atol=1e-5)
    assert desc.min() >= 0 and desc.max() < 0.5  # clipped at 0.2 before renormalising
    assert (kp.scale > 0.5).all() and ((kp.orientation >= 0) & (kp.orientation < 2 * np.pi)).all()
    gv.KeypointsPort.validate(kp)


@pytest.mark.parametrize("seed", [0, 5])
def test_sift_recovers_a_known_homography(astronaut, astronaut_features, seed):
    warped = synthetic.random_warp(astronaut, seed=seed)
    other = features.sift(warped.image)
    found = matching.match(astronaut_features.descriptors, other.descriptors, ratio=0.8)
    fit = geometry.homography_ransac(astronaut_features.keypoints, other.keypoints, found)
    assert geometry.corner_error(fit.homography, warped.homography, astronaut) < 1.0
    assert len(fit.inliers) > 200


def test_orientation_follows_a_rotation(astronaut):
    crop = astronaut[100:356, 100:356]
    a = features.sift(crop)
    b = features.sift(np.ascontiguousarray(np.rot90(crop)))  # 90° counter-clockwise
    found = matching.match(a.descriptors, b.descriptors, ratio=0.7)
    i, j = found.pairs[:50].T
    # rot90: (x, y) -> (y, W - 1 - x); in image coordinates (y down) angles drop by 90°
    expected = np.column_stack([a.keypoints.xy[i, 1], 255 - a.keypoints.xy[i, 0]])
    assert np.median(np.linalg.norm(b.keypoints.xy[j] - expected, axis=1)) < 0.5
    turn = np.mod(b.keypoints.orientation[j] - a.keypoints.orientation[i], 2 * np.pi)
    assert np.median(np.abs(turn - 1.5 * np.pi)) < 0.1


def test_no_keypoints_on_a_flat_image():
    flat = np.full((64, 64), 0.5, np.float32)
    result = features.sift(flat)
    assert len(result.keypoints) == 0 and result.descriptors.shape == (0, 128)
    assert len(matching.match(result.descriptors, result.descriptors)) == 0
    assert len(features.harris(flat)) == 0
    assert features.patch_descriptor(flat, result.keypoints).shape == (0, 64)


def test_matching_recovers_a_permutation_and_rejects_ambiguity():
    rng = np.random.default_rng(0)
    a = rng.random((100, 16)).astype(np.float32)
    order = rng.permutation(100)
    b = a[order] + rng.normal(0, 0.01, (100, 16)).astype(np.float32)
    found = matching.match(a, b)
    assert len(found) == 100
    np.testing.assert_array_equal(order[found.pairs[:, 1]], found.pairs[:, 0])
    assert (np.diff(found.distance) >= 0).all()
    kd = matching.match(a, b, method="kdtree")
    np.testing.assert_array_equal(np.sort(kd.pairs, axis=0), np.sort(found.pairs, axis=0))
    twins = np.vstack([a[:1], a[:1] + 1e-4]).astype(np.float32)
    assert len(matching.match(a[:1], twins, ratio=0.8)) == 0  # two equally good candidates
    assert len(matching.match(a[:1], twins, ratio=1.0, symmetric=False)) == 1
    with pytest.raises(ValueError, match="different lengths: 16 and 8"):
        matching.match(a, a[:, :8])


def test_symmetric_matching_drops_one_sided_matches():
    a = np.array([[0.0], [1.0]], np.float32)
    b = np.array([[0.1], [0.2]], np.float32)
    one_sided = matching.match(a, b, ratio=1.0, symmetric=False)
    both = matching.match(a, b, ratio=1.0, symmetric=True)
    assert len(one_sided) == 2 and both.pairs.tolist() == [[0, 0]]


def test_patch_descriptor_is_invariant_to_brightness_and_contrast(astronaut):
    kp = features.harris(astronaut, max_keypoints=50)
    a = features.patch_descriptor(astronaut, kp)
    b = features.patch_descriptor((0.5 * astronaut + 0.2).astype(np.float32), kp)
    np.testing.assert_allclose(a, b, atol=1e-4)
    np.testing.assert_allclose(np.linalg.norm(a, axis=1), 1.0, atol=1e-5)


def test_drawings_have_the_expected_shapes(astronaut, astronaut_features):
    kp = astronaut_features.keypoints.take(np.arange(20))
    drawn = features.draw_keypoints(astronaut, kp)
    assert drawn.shape == (*astronaut.shape, 3) and drawn.dtype == np.float32
    pairs = gv.MatchSet(np.column_stack([np.arange(5), np.arange(5)]).astype(np.int64), np.zeros(5))
    both = features.draw_matches(astronaut, astronaut[:200], kp, kp, pairs, pairs.take([0, 1]))
    assert both.shape == (512, 1024, 3)
    assert (both == np.float32(0.95)).any()  # red outliers drawn


@pytest.mark.parametrize(("a", "b", "angle"), [(8, 4, 0.0), (8, 4, 0.6), (6, 6, 0.0)])
def test_affine_adaptation_recovers_an_elliptical_blob(a, b, angle):
    yy, xx = np.mgrid[:128, :128].astype(float)
    u = (xx - 64) * np.cos(angle) + (yy - 64) * np.sin(angle)
    v = -(xx - 64) * np.sin(angle) + (yy - 64) * np.cos(angle)
    blob = np.exp(-(u**2 / (2 * a * a) + v**2 / (2 * b * b))).astype(np.float32)
    kp = gv.KeypointSet(
        np.array([[64.0, 64.0]]), np.array([np.sqrt(a * b)]), np.zeros(1), np.ones(1)
    )
    shape = features.affine_adapt(blob, kp).affine[0]
    left, singular, _ = np.linalg.svd(shape)
    # the adapted region is the blob's own ellipse: axes ratio a / b, major axis at `angle`
    assert singular[0] / singular[1] == pytest.approx(a / b, rel=0.05)
    assert abs(np.linalg.det(shape)) == pytest.approx(1.0)
    if a != b:
        turn = np.mod(np.arctan2(left[1, 0], left[0, 0]) - angle, np.pi)
        assert min(turn, np.pi - turn) < 0.05


def test_describe_sift_reproduces_sift_and_describes_other_detectors(astronaut, astronaut_features):
    again = features.describe_sift(astronaut, astronaut_features.keypoints)
    same = np.abs(again - astronaut_features.descriptors).max(axis=1) < 1e-4
    # keypoints whose scale lies between two levels may be described in the other one
    assert same.mean() > 0.85
    corners = features.harris(astronaut, max_keypoints=100)
    assert features.describe_sift(astronaut, corners).shape == (100, 128)
