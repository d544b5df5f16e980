"""OpenCV implementations of pyramids, template matching, SIFT, brute-force matching,
RANSAC homographies, perspective warps and Bayer demosaicing."""

from __future__ import annotations

import numpy as np

from graphvision import KeypointSet, MatchSet, implements

from .convert import (
    EXTRA,
    REQUIRES,
    cv,
    keypoints_from_cv,
    matches_from_cv,
    points_to_cv,
    significance,
    to_u8,
)

__all__ = [
    "cv_demosaic",
    "cv_gaussian_pyramid",
    "cv_homography_ransac",
    "cv_match",
    "cv_match_template",
    "cv_sift",
    "cv_warp",
]


@implements("pyramids.gaussian", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_gaussian_pyramid(image: np.ndarray, *, levels: int = 4, sigma: float = 1.0) -> object:
    """``cv2.sepFilter2D`` with ``cv2.getGaussianKernel(2r + 1, σ)``, ``r = ⌊3σ + ½⌋``
    (``BORDER_REFLECT_101``, scipy's ``mirror``), then every second row and column. Not
    ``cv2.pyrDown``: its fixed 5-tap kernel has no σ parameter."""
    from ..pyramids import ImagePyramid

    cv2 = cv()
    taps = cv2.getGaussianKernel(2 * int(3.0 * sigma + 0.5) + 1, sigma, cv2.CV_32F)
    result = [np.ascontiguousarray(image, dtype=np.float32)]
    for _ in range(levels - 1):
        if min(result[-1].shape[:2]) < 2:
            break
        level = result[-1]
        smooth = cv2.sepFilter2D(level, cv2.CV_32F, taps, taps, borderType=cv2.BORDER_REFLECT_101)
        result.append(np.ascontiguousarray(smooth[::2, ::2]))
    return ImagePyramid(tuple(result), "gaussian")


_TEMPLATE_METHODS = {"correlation": "TM_CCORR", "zero_mean": "TM_CCOEFF", "ncc": "TM_CCOEFF_NORMED"}


@implements("pyramids.match_template", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_match_template(
    image: np.ndarray, template: np.ndarray, *, method: str = "ncc"
) -> np.ndarray:
    """``cv2.matchTemplate``: TM_CCORR, TM_CCOEFF (equal to correlating with the
    zero-mean template) or TM_CCOEFF_NORMED."""
    cv2 = cv()
    if template.shape[0] > image.shape[0] or template.shape[1] > image.shape[1]:
        raise ValueError(
            f"template {template.shape[0]}×{template.shape[1]} is larger than the image "
            f"{image.shape[0]}×{image.shape[1]}"
        )
    flag = getattr(cv2, _TEMPLATE_METHODS[method])
    out = cv2.matchTemplate(image.astype(np.float32), template.astype(np.float32), flag)
    return np.nan_to_num(out, nan=0.0, posinf=0.0, neginf=0.0)


@implements("features.sift", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_sift(
    image: np.ndarray,
    *,
    intervals: int = 3,
    sigma: float = 1.6,
    contrast_threshold: float = 0.04,
    edge_ratio: float = 10.0,
    upsample: bool = True,
    max_keypoints: int = 0,
) -> tuple[KeypointSet, np.ndarray]:
    """``cv2.SIFT`` on the 8-bit image. OpenCV always doubles the image first
    (``upsample``), scales its contrast threshold as ``t / s`` on 8-bit levels, and
    returns descriptors scaled to bytes: they are renormalised to unit length here,
    and responses divided by 255, as the reference gives them."""
    from ..features._sift import SiftFeatures

    cv2 = cv()
    detector = cv2.SIFT_create(
        nfeatures=max_keypoints,
        nOctaveLayers=intervals,
        contrastThreshold=contrast_threshold,
        edgeThreshold=edge_ratio,
        sigma=sigma,
    )
    points, descriptors = detector.detectAndCompute(to_u8(image), None)
    keypoints = keypoints_from_cv(points)
    if descriptors is None or len(points) == 0:
        return SiftFeatures(KeypointSet.empty(), np.zeros((0, 128), dtype=np.float32))
    keypoints = KeypointSet(
        keypoints.xy, keypoints.scale, keypoints.orientation, keypoints.response / 255.0
    )
    norms = np.linalg.norm(descriptors, axis=1, keepdims=True)
    unit = (descriptors / np.maximum(norms, 1e-12)).astype(np.float32)
    return SiftFeatures(keypoints, unit)


@implements("matching.match", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_match(
    a: np.ndarray,
    b: np.ndarray,
    *,
    ratio: float = 0.8,
    symmetric: bool = True,
    method: str = "brute",
) -> MatchSet:
    """``cv2.BFMatcher(NORM_L2).knnMatch(k=2)`` with Lowe's ratio test and, with
    ``symmetric``, the mutual check by a second search from ``b`` (``method`` is the
    reference's alone: OpenCV's search here is always exhaustive)."""
    cv2 = cv()
    if a.shape[1:] != b.shape[1:]:
        raise ValueError(f"descriptors have different lengths: {a.shape[1]} and {b.shape[1]}")
    if len(a) == 0 or len(b) == 0:
        return MatchSet(np.zeros((0, 2), np.int64), np.zeros(0))
    matcher = cv2.BFMatcher(cv2.NORM_L2)
    da, db = a.astype(np.float32), b.astype(np.float32)
    pairs = matcher.knnMatch(da, db, k=min(2, len(b)))
    kept = [
        p[0]
        for p in pairs
        if p and (ratio >= 1 or len(p) < 2 or p[0].distance < ratio * p[1].distance)
    ]
    if symmetric:
        back = {m.queryIdx: m.trainIdx for m in matcher.match(db, da)}
        kept = [m for m in kept if back.get(m.trainIdx) == m.queryIdx]
    kept.sort(key=lambda m: m.distance)
    return matches_from_cv(kept)


@implements(
    "geometry.homography_ransac",
    backend="opencv",
    requires=REQUIRES,
    extra=EXTRA,
    exclusive={"method": ("magsac",)},
)
def cv_homography_ransac(
    src: KeypointSet,
    dst: KeypointSet,
    matches: MatchSet,
    *,
    threshold: float = 3.0,
    confidence: float = 0.995,
    max_iterations: int = 5000,
    refine: bool = True,
    max_nfa: float | None = 1.0,
    seed: int = 0,
    method: str = "ransac",
) -> tuple[np.ndarray, MatchSet, float, float]:
    """``cv2.findHomography(RANSAC)`` on the matched points, OpenCV's random generator
    seeded with ``seed``; ``method: magsac`` is ``cv2.USAC_MAGSAC`` (MAGSAC++, with
    ``threshold`` its largest noise σ; USAC seeds its own generator, so ``seed`` changes
    only the significance draws). OpenCV measures the forward error ``‖dst − H src‖``
    and always refines the inliers' fit (``refine`` is the reference's). The
    significance (``log_nfa``, ``max_nfa``) is the reference's test on OpenCV's inliers."""
    from ..geometry._homography import HomographyFit, transfer_error

    cv2 = cv()
    if len(matches) < 4:
        raise ValueError(f"need at least 4 matches to estimate a homography, got {len(matches)}")
    a = points_to_cv(src.xy[matches.pairs[:, 0]])
    b = points_to_cv(dst.xy[matches.pairs[:, 1]])
    cv2.setRNGSeed(seed)
    flag = cv2.USAC_MAGSAC if method == "magsac" else cv2.RANSAC
    homography, mask = cv2.findHomography(
        a, b, flag, threshold, maxIters=max_iterations, confidence=confidence
    )
    if homography is None:
        raise ValueError("no homography: OpenCV found no consensus of 4 or more matches")
    inliers = mask.ravel().astype(bool)
    model = homography / homography[2, 2]
    pa, pb = src.xy[matches.pairs[:, 0]], dst.xy[matches.pairs[:, 1]]

    def fits(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return transfer_error(model, x, y) < threshold

    log_nfa = significance(inliers, pa, pb, fits, 4, max_nfa, "the homography", seed)
    return HomographyFit(model, matches.take(inliers), float(inliers.mean()), log_nfa)


@implements("geometry.warp", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_warp(
    image: np.ndarray, homography: np.ndarray, *, width: int = 0, height: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """``cv2.warpPerspective`` (bilinear, black outside) with the inverse map; ``valid``
    from the same inverse map, as the reference defines it (source inside the input's
    pixel area, ``[-0.5, W - 0.5] × [-0.5, H - 0.5]``)."""
    from ..geometry._warp import Warped

    cv2 = cv()
    rows, cols = height or image.shape[0], width or image.shape[1]
    try:
        inverse = np.linalg.inv(homography)
    except np.linalg.LinAlgError:
        raise ValueError("the homography is singular: it has no inverse to warp with") from None
    flags = cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP
    data = np.ascontiguousarray(image, dtype=np.float32)
    warped = cv2.warpPerspective(
        data, inverse, (cols, rows), flags=flags, borderMode=cv2.BORDER_REPLICATE
    )
    grid = np.stack(np.meshgrid(np.arange(cols), np.arange(rows)), axis=-1).reshape(-1, 1, 2)
    source = cv2.perspectiveTransform(grid.astype(np.float64), inverse).reshape(rows, cols, 2)
    sx, sy = source[..., 0], source[..., 1]
    valid = (
        (sx >= -0.5) & (sx <= image.shape[1] - 0.5) & (sy >= -0.5) & (sy <= image.shape[0] - 0.5)
    )
    valid &= np.isfinite(sx) & np.isfinite(sy)
    warped[~valid] = 0.0
    return Warped(np.clip(warped, 0.0, 1.0), valid)


_BAYER = {"RGGB": "BG", "BGGR": "RG", "GRBG": "GB", "GBRG": "GR"}


@implements("formation.demosaic", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_demosaic(raw: np.ndarray, *, pattern: str = "RGGB", method: str = "malvar") -> np.ndarray:
    """``cv2.cvtColor(COLOR_Bayer??2RGB)`` (bilinear) on 16-bit samples; OpenCV names a
    pattern by the tile at row 1, column 1 (``RGGB`` is its ``BayerBG``). OpenCV has no
    Malvar-He-Cutler filter: ``malvar`` runs the reference."""
    if min(raw.shape) < 5:
        raise ValueError(f"raw must be at least 5×5 to demosaic, got {raw.shape}")
    if method == "malvar":
        from ..formation import demosaic

        return demosaic.__wrapped__(raw, pattern=pattern, method=method)  # type: ignore[attr-defined]
    cv2 = cv()
    samples = np.clip(np.rint(raw * 65535.0), 0, 65535).astype(np.uint16)
    rgb = cv2.cvtColor(samples, getattr(cv2, f"COLOR_Bayer{_BAYER[pattern]}2RGB"))
    return rgb.astype(np.float32) / np.float32(65535.0)
