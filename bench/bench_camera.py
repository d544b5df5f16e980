"""Cameras and image formation against OpenCV, on data with known truth, in one run.

* **Corners**: the 10 views of ``pipelines/calibrate.yaml`` (9×6 board, fill 0.8,
  k1 = −0.1, blur 0.7 px, noise 0.02); ``camera.board_corners`` against
  ``cv2.findChessboardCorners`` + ``cv2.cornerSubPix`` (11×11 window,
  30 iterations / 0.001) on the same images (uint8), each compared with the
  projected true corners (OpenCV's order aligned to the truth's by reversal).
* **Planar calibration**: ``camera.calibrate_board`` (k1, k2) against
  ``cv2.calibrateCamera`` (flags: zero tangential, fixed k3) on the same
  corners; focal error, k1 error, reprojection RMS.
* **DLT**: 20 seeded scenes (random cube, 0.2 px noise): plain numpy DLT
  (normalised, no refinement) against ``camera.calibrate_dlt``, median |fx error|.
* **Undistortion**: 100 000 points, ``camera.undistort_points`` against
  ``cv2.undistortPoints`` with its default criteria and run to convergence;
  the image map against ``cv2.initUndistortRectifyMap``; ``cv2.undistort`` time.
* **Demosaic**: astronaut and cat (chelsea), RGGB; PSNR of bilinear and
  Malvar-He-Cutler against ``cv2.cvtColor`` Bayer bilinear and edge-aware (EA).

Times are ratios to OpenCV in the same run (best of 3). Run:
``python bench/bench_camera.py``.
"""

from __future__ import annotations

import numpy as np
from timing import best

import graphvision as gv
from graphvision_plugins import camera, formation, metrics, synthetic
from graphvision_plugins.io import read_sample

K_REF = np.array([[500.0, 0, 320.0], [0, 520.0, 240.0], [0, 0, 1]])
DIST_REF = np.array([-0.3, 0.1, 0.001, -0.002, -0.02])


def _opencv_corners(cv2, views: np.ndarray, truth: np.ndarray) -> np.ndarray:
    out = np.full(truth.shape, np.nan)
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)
    for k, view in enumerate(views):
        image = np.round(view * 255).astype(np.uint8)
        ok, found = cv2.findChessboardCorners(image, (9, 6))
        if not ok:
            continue
        found = cv2.cornerSubPix(image, found, (11, 11), (-1, -1), criteria).reshape(-1, 2)
        found = found.astype(float)
        if np.linalg.norm(found[0] - truth[k, 0]) > np.linalg.norm(found[-1] - truth[k, 0]):
            found = found[::-1]
        out[k] = found
    return out


def _corner_rows(cv2, boards) -> tuple[list[str], np.ndarray, np.ndarray]:
    ours = camera.board_corners(boards.views).corners
    theirs = _opencv_corners(cv2, boards.views, boards.corners)
    t_ours = best(lambda: camera.board_corners(boards.views), 3)
    t_cv = best(lambda: _opencv_corners(cv2, boards.views, boards.corners), 3)
    rows = [
        "| corners (10 views) | found | mean error px | max error px | ms | time ratio |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for name, corners, seconds in (
        ("camera.board_corners", ours, t_ours),
        ("cv2 findChessboardCorners + cornerSubPix", theirs, t_cv),
    ):
        found = np.isfinite(corners).all(axis=(1, 2))
        error = np.linalg.norm(corners[found] - boards.corners[found], axis=2)
        rows.append(
            f"| {name} | {found.sum()}/10 | {error.mean():.4f} | {error.max():.3f} | "
            f"{seconds * 1e3:.0f} | {seconds / t_cv:.2f} |"
        )
    return rows, ours, theirs


def _calibration_rows(cv2, boards, corner_sets: dict[str, np.ndarray]) -> list[str]:
    truth = boards.camera
    rows = [
        "| calibration | corners | focal error % | k1 error | RMS px | ms | time ratio |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    flags = cv2.CALIB_ZERO_TANGENT_DIST | cv2.CALIB_FIX_K3
    objects = boards.object_points.astype(np.float32)
    for source, corners in corner_sets.items():
        usable = np.isfinite(corners).all(axis=(1, 2))

        def opencv(corners=corners, usable=usable):
            return cv2.calibrateCamera(
                [objects] * int(usable.sum()),
                [c.astype(np.float32)[:, None] for c in corners[usable]],
                (640, 480), None, None, flags=flags,
            )  # fmt: skip

        def ours(corners=corners):
            return camera.calibrate_board(corners, boards.object_points)

        rms, K, dist, _, _ = opencv()
        mine = ours()
        t_cv, t_ours = best(opencv, 3), best(ours, 3)
        for name, k, k1, r, seconds in (
            ("camera.calibrate_board", mine.camera.K, mine.camera.distortion[0],
             mine.reprojection_rms, t_ours),
            ("cv2.calibrateCamera", K, dist.ravel()[0], rms, t_cv),
        ):  # fmt: skip
            focal = 100 * max(abs(k[0, 0] / truth.K[0, 0] - 1), abs(k[1, 1] / truth.K[1, 1] - 1))
            rows.append(
                f"| {name} | {source} | {focal:.3f} | {abs(k1 + 0.1):.4f} | {r:.3f} | "
                f"{seconds * 1e3:.0f} | {seconds / t_cv:.2f} |"
            )
    return rows


def _dlt_rows() -> list[str]:
    rows = ["| DLT (20 scenes, 0.2 px) | N | median \\|fx error\\| px |", "| --- | --- | --- |"]
    for count in (6, 100):
        plain, refined = [], []
        for seed in range(20):
            rng = np.random.default_rng(seed)
            truth = camera.pinhole(
                fx=800, fy=780, cx=330, cy=245, rotation=(0.1, -0.2, 0.05), centre=(1, 2, -8)
            )
            world = rng.uniform(-3, 3, (count, 3)) + np.array([1, 2, 0])
            image = camera.project(truth, world) + rng.normal(0, 0.2, (count, 2))
            K, _, _ = camera.decompose_projection(camera.dlt_projection(world, image))
            plain.append(abs(K[0, 0] - 800))
            refined.append(abs(camera.calibrate_dlt(world, image).camera.K[0, 0] - 800))
        rows.append(f"| numpy DLT, no refinement | {count} | {np.median(plain):.2f} |")
        rows.append(f"| camera.calibrate_dlt | {count} | {np.median(refined):.2f} |")
    return rows


def _undistort_rows(cv2) -> list[str]:
    rng = np.random.default_rng(0)
    points = rng.uniform([0, 0], [640, 480], (100_000, 2))
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)

    def cv_default():
        return cv2.undistortPoints(points[:, None], K_REF, DIST_REF, None, K_REF)[:, 0]

    def cv_converged():
        return cv2.undistortPoints(
            points[:, None], K_REF, DIST_REF, R=None, P=K_REF, criteria=criteria
        )[:, 0]

    def ours():
        return camera.undistort_pixels(points, K_REF, DIST_REF)

    mine = ours()
    t_ours, t_default, t_conv = best(ours, 3), best(cv_default, 3), best(cv_converged, 3)
    m1, m2 = cv2.initUndistortRectifyMap(K_REF, DIST_REF, None, K_REF, (640, 480), cv2.CV_32FC1)
    v, u = np.mgrid[0:480, 0:640].astype(float)
    src = camera.distort_pixels(np.column_stack([u.ravel(), v.ravel()]), K_REF, DIST_REF)
    map_diff = max(np.abs(src[:, 0] - m1.ravel()).max(), np.abs(src[:, 1] - m2.ravel()).max())
    image = read_sample("astronaut")[..., 1]
    lens = gv.PinholeCamera(K_REF.copy(), distortion=DIST_REF.copy())
    t_img = best(lambda: camera.undistort_image(image, lens), 3)
    t_cv_img = best(lambda: cv2.undistort(image, K_REF, DIST_REF), 3)
    return [
        "| undistortion | max difference from ours px | time ratio (ours / theirs) |",
        "| --- | --- | --- |",
        f"| cv2.undistortPoints, default criteria (5 iterations) | "
        f"{np.abs(mine - cv_default()).max():.3g} | {t_ours / t_default:.2f} |",
        f"| cv2.undistortPoints, 100 iterations / 1e-12 | "
        f"{np.abs(mine - cv_converged()).max():.3g} | {t_ours / t_conv:.2f} |",
        f"| cv2.initUndistortRectifyMap (float32 map) | {map_diff:.3g} | – |",
        f"| cv2.undistort (512×512 image) | – | {t_img / t_cv_img:.2f} |",
    ]


def _demosaic_rows(cv2) -> list[str]:
    rows = [
        "| demosaic (RGGB) | image | PSNR dB | time / cv2.cvtColor bilinear (uint16) |",
        "| --- | --- | --- | --- |",
    ]
    for sample in ("astronaut", "cat"):
        image = read_sample(sample)
        raw = formation.mosaic(image, pattern="RGGB")
        raw16 = np.round(raw * 65535).astype(np.uint16)
        # OpenCV names a pattern by its second row: an RGGB sensor is COLOR_BayerBG
        t_ref = best(lambda raw16=raw16: cv2.cvtColor(raw16, cv2.COLOR_BayerBG2RGB), 3)
        for name, run in (
            ("formation.demosaic bilinear",
             lambda raw=raw: formation.demosaic(raw, method="bilinear")),
            ("formation.demosaic malvar", lambda raw=raw: formation.demosaic(raw, method="malvar")),
            ("cv2 Bayer bilinear",
             lambda raw16=raw16: (cv2.cvtColor(raw16, cv2.COLOR_BayerBG2RGB) / 65535)),
            ("cv2 Bayer EA",
             lambda raw16=raw16: (cv2.cvtColor(raw16, cv2.COLOR_BayerBG2RGB_EA) / 65535)),
        ):  # fmt: skip
            out = np.clip(run(), 0, 1).astype(np.float32)
            psnr = metrics.psnr(image, out)
            rows.append(f"| {name} | {sample} | {psnr:.2f} | {best(run, 3) / t_ref:.2f} |")
    return rows


def main() -> list[str]:
    try:
        import cv2
    except ImportError:
        return ["OpenCV is not installed (`pip install -e .[bench]`): camera benchmark skipped"]
    boards = synthetic.board_views(views=10, k1=-0.1, fill=0.8, blur=0.7, noise=0.02, seed=0)
    rows, ours, theirs = _corner_rows(cv2, boards)
    corner_sets = {"ours": ours, "OpenCV's": theirs, "true + 0.2 px noise": _noisy(boards)}
    for section in (
        _calibration_rows(cv2, boards, corner_sets),
        _dlt_rows(),
        _undistort_rows(cv2),
        _demosaic_rows(cv2),
    ):
        rows += ["", *section]
    return rows


def _noisy(boards) -> np.ndarray:
    return boards.corners + np.random.default_rng(1).normal(0, 0.2, boards.corners.shape)


if __name__ == "__main__":
    print("\n".join(main()))
