"""Dense stereo on scenes nobody tuned for (issue 24, item 1): rendered piecewise-planar
scenes textured with photographs, exact disparity and occlusions, against the figures
OpenCV's StereoSGBM and StereoBM reach on the same scenes.

The SGM and block-matching defaults were chosen on other scenes of
``synthetic.planar_stereo_scene`` (camera, clock, coins, grass, moon, page and text
textures, seeds 100–105; the default textures with seeds 0–3); seed 20 here was never
used to choose anything. bad2 counts the non-occluded pixels at x ≥ 64 (away from the
left border, where no method sees the match) whose estimate is invalid or off by more
than 2 px.

The OpenCV figures were recorded with opencv-python-headless 5.0.0 by (``bench/bench_stereo.py``)::

    scene = synthetic.planar_stereo_scene(gain=gain, offset=offset, seed=20)
    left8, right8 = (np.round(255 * im).astype(np.uint8) for im in (scene.left, scene.right))
    sgbm = cv2.StereoSGBM_create(minDisparity=0, numDisparities=64, blockSize=5,
        P1=8 * 25, P2=32 * 25, disp12MaxDiff=1, uniquenessRatio=10,
        speckleWindowSize=100, speckleRange=2, mode=cv2.STEREO_SGBM_MODE_HH)
    bm = cv2.StereoBM_create(numDisparities=64, blockSize=15)
    raw = matcher.compute(left8, right8) / 16.0   # invalid where < 0
    stereo.disparity_error(raw, truth)            # truth: visible, x >= 64
"""

from __future__ import annotations

import numpy as np
import pytest

from graphvision_plugins import stereo, synthetic

BORDER = 64

# (gain, offset) of the right camera -> OpenCV's figures on seed 20 (recorded as above):
# bad2 %, bad2 % over pixels valid in both, density %, mean |error| px over valid in both
SGBM = {(1.0, 0.0): (6.339, 2.449, 82.063, 0.5510), (0.7, 0.12): (13.069, 3.847, 77.447, 0.7241)}
BM = {(1.0, 0.0): (26.961, 3.084, 64.805, 0.6421), (0.7, 0.12): (34.874, 3.915, 58.312, 0.7507)}
EXPOSURES = list(SGBM)


@pytest.fixture(scope="module", params=EXPOSURES, ids=["same exposure", "gain 0.7 offset 0.12"])
def scene(request):
    gain, offset = request.param
    rendered = synthetic.planar_stereo_scene(gain=gain, offset=offset, seed=20)
    truth = np.where(rendered.visible, rendered.disparity, np.nan).astype(np.float32)
    truth[:, :BORDER] = np.nan
    return request.param, rendered, truth


def test_sgm_on_a_held_out_scene_keeps_more_and_better_pixels_than_sgbm(scene):
    """Before issue 24 SGM's defaults reached bad2 18.5 % (same exposure) and 23.4 % (gain
    0.7, offset 0.12): its map was full of holes, its left-right check refusing correct
    sub-pixel disparities, and of speckles. Now it beats StereoSGBM over the pixels both
    keep and in sub-pixel error, keeping more pixels; over all pixels it beats SGBM with
    another exposure (census ignores gain and offset) and trails it by 1.9 points with the
    same one (8.2 % against 6.3 %; the mean of six held-out scenes in the bench is 9.1 %
    against 11.1 %)."""
    exposure, rendered, truth = scene
    error = stereo.disparity_error(stereo.sgm(rendered.left, rendered.right), truth)
    bad, bad_valid, density, mean_abs = SGBM[exposure]
    assert error.bad <= (9.0 if exposure == (1.0, 0.0) else bad)
    assert error.bad_valid <= bad_valid
    assert error.mean_abs <= mean_abs  # sub-pixel parabola over the aggregated cost
    assert error.density >= density


def test_block_matching_on_a_held_out_scene_is_more_accurate_than_stereo_bm(scene):
    """Before issue 24 block matching (ZNCC 9 × 9) had 5.6 % and 6.2 % bad2 over the pixels
    it kept, StereoBM 3.1 % and 3.9 %; census summed over 9 × 9 with the speckle filter
    halves StereoBM's figure and keeps at least as many pixels."""
    exposure, rendered, truth = scene
    error = stereo.disparity_error(stereo.block_match(rendered.left, rendered.right), truth)
    _, bad_valid, density, mean_abs = BM[exposure]
    assert error.bad_valid <= bad_valid / 1.5
    assert error.mean_abs <= mean_abs
    assert error.density >= density


def test_the_planar_scene_shows_each_visible_point_at_x_minus_d_in_the_right_image():
    rendered = synthetic.planar_stereo_scene(width=240, height=180, noise=0.0, seed=5)
    rows, cols = rendered.disparity.shape
    assert rendered.disparity.min() >= 10.0 and rendered.disparity.max() <= 45.0
    # inside planes (no depth edge within 2 px), the right image at x − d is the left at x
    truth = rendered.disparity
    steady = np.ones_like(rendered.visible)
    for dy in range(-2, 3):
        for dx in range(-2, 3):
            moved = np.roll(truth, (dy, dx), axis=(0, 1))
            steady &= np.abs(moved - truth) < 0.5 * (abs(dy) + abs(dx)) + 0.01
    y, x = np.nonzero(steady & rendered.visible)
    keep = (x - truth[y, x] >= 1) & (x > 2) & (y > 2) & (y < rows - 3) & (x < cols - 3)
    y, x = y[keep], x[keep]

    def right_at(columns: np.ndarray) -> np.ndarray:
        low = np.floor(columns).astype(int)
        weight = columns - low
        return (1 - weight) * rendered.right[y, low] + weight * rendered.right[y, low + 1]

    matched = np.abs(rendered.left[y, x] - right_at(x - truth[y, x]))
    shifted = np.abs(rendered.left[y, x] - right_at(np.maximum(x - truth[y, x] - 3, 0)))
    assert np.median(matched) < 0.01 < 0.3 * np.median(shifted)
    # occluded: the left border, and a band beside every nearer surface
    assert not rendered.visible[:, :10].any()
    assert 0.02 < 1 - rendered.visible[:, 50:].mean() < 0.2


def test_the_right_cameras_exposure_is_gain_times_the_image_plus_offset():
    plain = synthetic.planar_stereo_scene(width=160, height=120, noise=0.0, seed=6)
    exposed = synthetic.planar_stereo_scene(
        width=160, height=120, gain=0.7, offset=0.12, noise=0.0, seed=6
    )
    np.testing.assert_array_equal(plain.left, exposed.left)
    unclipped = (plain.right > 0) & (plain.right < 1)  # 0 and 1 may stand for beyond
    assert unclipped.mean() > 0.99
    np.testing.assert_allclose(
        exposed.right[unclipped], 0.7 * plain.right[unclipped] + 0.12, atol=1.01 / 255
    )
    assert np.array_equal(np.round(255 * exposed.right) / 255, exposed.right)  # 8-bit


def test_bad_planar_scene_parameters_are_refused_by_name():
    with pytest.raises(ValueError, match=r"min_disparity \(40\) must be below max_disparity"):
        synthetic.planar_stereo_scene(min_disparity=40, max_disparity=20)
    with pytest.raises(ValueError, match="textures"):
        synthetic.planar_stereo_scene(textures=())
    with pytest.raises(ValueError, match="textures"):
        synthetic.planar_stereo_scene(textures=("motorcycle_left",))
