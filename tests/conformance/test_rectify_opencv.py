"""OpenCV's calibrated rectification against Fusiello's, by what rectification is for:
corresponding points on one row, and the same epipolar geometry (both rectified cameras
turned alike, the baseline along x); the remaining difference, a rotation about the
baseline, is bounded as the op's note states."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("cv2", reason="the opencv backend needs opencv-python-headless (dev extra)")

from graphvision_plugins import geometry, stereo, synthetic
from graphvision_plugins.opencv_backend import cv_rectify_calibrated


@pytest.mark.parametrize("seed", range(6))
def test_opencv_rectification_aligns_rows_and_turns_about_the_baseline_alone(seed: int) -> None:
    scene = synthetic.two_view_scene(noise=0.0, seed=seed)  # the true cameras and matches
    ours = stereo.rectify_calibrated(scene.camera_a, scene.camera_b)
    theirs = cv_rectify_calibrated(scene.camera_a, scene.camera_b)
    # rows aligned: measured below 6e-13 px on seeds 0-5 (double precision of a 640 px
    # image through two 3×3 products), bound 1e-9 px
    assert stereo.rectification_dy(scene.a, scene.b, theirs.H_a, theirs.H_b) < 1e-9
    left = geometry.apply_homography(theirs.H_a, scene.a)
    right = geometry.apply_homography(theirs.H_b, scene.b)
    # the same epipolar geometry: one K and one rotation, the baseline along +x
    np.testing.assert_allclose(theirs.camera_a.R, theirs.camera_b.R, atol=1e-12)
    np.testing.assert_allclose(theirs.camera_a.K, theirs.camera_b.K, atol=1e-9)
    along = theirs.camera_a.R @ (scene.camera_b.C - scene.camera_a.C)
    np.testing.assert_allclose(along, [theirs.baseline, 0.0, 0.0], atol=1e-12)
    depth = (scene.points - scene.camera_a.C) @ theirs.camera_a.R[2]
    focal = theirs.camera_a.K[0, 0]
    np.testing.assert_allclose(left[:, 0] - right[:, 0], focal * theirs.baseline / depth)
    # the difference from Fusiello's: a rotation about the baseline (x) alone, at most
    # the angle between the two optical axes about it
    turn = theirs.camera_a.R @ ours.camera_a.R.T
    np.testing.assert_allclose(turn[0], [1.0, 0.0, 0.0], atol=1e-12)
    angle = abs(np.degrees(np.arctan2(turn[2, 1], turn[1, 1])))
    x = ours.camera_a.R[0]
    za, zb = (z - (z @ x) * x for z in (scene.camera_a.R[2], scene.camera_b.R[2]))
    between = np.degrees(np.arccos(za @ zb / np.linalg.norm(za) / np.linalg.norm(zb)))
    assert angle <= between


def test_opencv_rectification_refuses_what_the_reference_refuses() -> None:
    scene = synthetic.two_view_scene(noise=0.0, seed=0)
    with pytest.raises(ValueError, match="same centre: a zero baseline"):
        cv_rectify_calibrated(scene.camera_a, scene.camera_a)
    from graphvision_plugins import camera

    forward = camera.pinhole(centre=(0.0, 0.0, 1.0))
    with pytest.raises(ValueError, match="along the left camera's optical axis"):
        cv_rectify_calibrated(camera.pinhole(), forward)
