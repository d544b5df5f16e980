"""``method: magsac`` of geometry.homography_ransac: OpenCV's USAC_MAGSAC (MAGSAC++),
compared with the reference's RANSAC by the corner error the op declares; the
reference refuses it at validation, naming the backend that has it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import graphvision as gv
from graphvision_plugins import geometry

from .cases import _homography_case

PIPELINES = Path(__file__).parents[2] / "pipelines"


def _corner_error(h1: np.ndarray, h2: np.ndarray, side: float = 256.0) -> float:
    corners = np.array([[0, 0, 1], [side, 0, 1], [side, side, 1], [0, side, 1]], float)
    p1, p2 = corners @ h1.T, corners @ h2.T
    return float(np.mean(np.linalg.norm(p1[:, :2] / p1[:, 2:] - p2[:, :2] / p2[:, 2:], axis=1)))


def test_opencv_magsac_agrees_with_the_reference_ransac_by_corner_error() -> None:
    pytest.importorskip("cv2", reason="the opencv backend needs opencv-python-headless")
    from graphvision_plugins.opencv_backend import cv_homography_ransac

    inputs, params = _homography_case()  # 80 matches, 20 % outliers, σ = 0.3 px
    truth = np.array([[1.05, 0.04, 6.0], [-0.03, 0.97, -4.0], [2e-4, -1e-4, 1.0]])
    reference = geometry.homography_ransac(**inputs, **params)
    magsac = cv_homography_ransac(**inputs, **params, method="magsac")
    tolerance = gv.discover().node("geometry.homography_ransac").conformance.tolerance
    assert _corner_error(reference.homography, magsac.homography) <= tolerance
    assert _corner_error(truth, magsac.homography) < 0.5  # measured 0.23 (RANSAC: 0.23)
    # the 16 outliers are the first 16 matches: MAGSAC keeps none of them
    assert magsac.inliers.pairs[:, 0].min() >= 16 and magsac.inlier_ratio == pytest.approx(0.8)


def _homography_with(tmp_path: Path, params: str) -> Path:
    text = (PIPELINES / "homography.yaml").read_text()
    text = text.replace("params: {threshold: 3.0, seed: 0}", params)
    path = tmp_path / "homography.yaml"
    path.write_text(text)
    return path


def test_magsac_on_the_reference_is_refused_at_validation_naming_opencv(tmp_path: Path) -> None:
    path = _homography_with(tmp_path, "params: {threshold: 3.0, seed: 0, method: magsac}")
    graph = gv.load_pipeline(path)
    with pytest.raises(
        gv.PipelineError,
        match=r"homography.yaml:\d+.*method: 'magsac' of geometry.homography_ransac is "
        r"implemented by the 'opencv' backend alone, not by 'numpy'",
    ):
        gv.compile_graph(graph, gv.discover(), backends=["numpy"])
    with pytest.raises(ValueError, match=r"method 'magsac' is implemented by the opencv backend"):
        inputs, params = _homography_case()
        geometry.homography_ransac(**inputs, **params, method="magsac")
    if gv.discover().backends_of("geometry.homography_ransac")["opencv"]:
        compiled = gv.compile_graph(graph, gv.discover(), backends=["opencv", "numpy"])
        assert compiled.steps["fit"].spec.backend == "opencv"


def test_opencv_magsac_fundamental_fits_the_reference_inliers_by_sampson_error() -> None:
    pytest.importorskip("cv2", reason="the opencv backend needs opencv-python-headless")
    from graphvision_plugins import epipolar
    from graphvision_plugins.opencv_backend import cv_fundamental

    from .cases import _two_views

    inputs, params = _two_views()["epipolar.fundamental"][0]  # 0.5 px noise, 20 outliers
    reference = epipolar.fundamental(**inputs, **params)
    F = cv_fundamental(**inputs, **params, method="magsac")[0]
    a, b = reference.inliers_a, reference.inliers_b
    ha, hb = np.c_[a, np.ones(len(a))], np.c_[b, np.ones(len(b))]
    fa, fb = ha @ F.T, hb @ F
    sampson = np.einsum("ni,ni->n", hb, fa) ** 2 / (
        fa[:, 0] ** 2 + fa[:, 1] ** 2 + fb[:, 0] ** 2 + fb[:, 1] ** 2
    )
    tolerance = gv.discover().node("epipolar.fundamental").conformance.tolerance
    assert np.sqrt(np.mean(sampson)) <= tolerance  # measured 0.84 px (FM_RANSAC: 1.04)
    with pytest.raises(ValueError, match=r"method 'magsac' is implemented by the opencv backend"):
        epipolar.fundamental(**inputs, **params, method="magsac")


def test_opencv_magsac_essential_gives_the_reference_ransacs_pose() -> None:
    """epipolar.essential_from_points' ``method: magsac`` (``cv2.findEssentialMat(...,
    cv2.USAC_MAGSAC)``) against the reference's RANSAC: E by the op's declared
    tolerance (unit norm, up to sign), and the rotation the reference's relative_pose
    recovers from each by that op's declared rotation error."""
    pytest.importorskip("cv2", reason="the opencv backend needs opencv-python-headless")
    from graphvision_plugins import epipolar
    from graphvision_plugins.opencv_backend import cv_essential_from_points

    from .cases import _two_views

    (inputs, params), *_ = _two_views()["epipolar.essential_from_points"]  # 20 outliers in 150
    reference = epipolar.essential_from_points(**inputs, **params)
    magsac = cv_essential_from_points(**inputs, **params, method="magsac")
    registry = gv.discover()
    rule = registry.node("epipolar.essential_from_points").conformance
    e1, e2 = (e / np.linalg.norm(e) for e in (reference.E, magsac.E))
    apart = min(np.linalg.norm(e1 - e2), np.linalg.norm(e1 + e2))
    assert rule.metric == "up_to_scale" and apart <= rule.tolerance  # measured 0.013 (RANSAC 0.025)
    a, b, camera_a, camera_b = inputs["a"], inputs["b"], inputs["camera_a"], inputs["camera_b"]
    poses = [epipolar.relative_pose(E, a, b, camera_a, camera_b).moved.R for E in (e1, e2)]
    cosine = np.clip((np.trace(poses[0] @ poses[1].T) - 1) / 2, -1.0, 1.0)
    degrees = float(np.degrees(np.arccos(cosine)))
    pose_rule = registry.node("epipolar.relative_pose").conformance
    assert pose_rule.metric == "rotation_error" and degrees <= pose_rule.tolerance  # 0.028°
    assert magsac.inliers_a.shape[0] == magsac.inlier_count >= 0.6 * len(a)  # measured 100


def test_magsac_essential_on_the_reference_is_refused_at_validation_naming_opencv() -> None:
    from graphvision_plugins import epipolar

    from .cases import _two_views

    graph = gv.Graph("pose")
    a, b = graph.input("a", "Points2D"), graph.input("b", "Points2D")
    camera = graph.add("camera", "camera.pinhole", params={"fx": 90.0})
    fit = graph.add(
        "E", "epipolar.essential_from_points", params={"method": "magsac"},
        a=a, b=b, camera_a=camera, camera_b=camera,
    )  # fmt: skip
    graph.output("E", fit["E"])
    registry = gv.discover()
    with pytest.raises(
        gv.PipelineError,
        match=r"method: 'magsac' of epipolar.essential_from_points is implemented by the "
        r"'opencv' backend alone, not by 'numpy'",
    ):
        gv.compile_graph(graph, registry, backends=["numpy"])
    (inputs, params), *_ = _two_views()["epipolar.essential_from_points"]
    with pytest.raises(ValueError, match=r"method 'magsac' is implemented by the opencv backend"):
        epipolar.essential_from_points(**inputs, **params, method="magsac")
    if registry.backends_of("epipolar.essential_from_points")["opencv"]:
        compiled = gv.compile_graph(graph, registry, backends=["opencv"])
        assert compiled.steps["E"].spec.backend == "opencv"
