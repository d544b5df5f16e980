"""Camera model nodes: build a camera, project, decompose P, distort and undistort."""

from __future__ import annotations

import numpy as np

from graphvision import Array, Camera, Conformance, ImageT, PinholeCamera, Points2D, Points3D, node

from ..shared.params import ImageSide, Positive
from ._projection import (
    decompose_projection,
    distort_pixels,
    project_points,
    rotation_from_vector,
    undistort_pixels,
)

__all__ = [
    "check_intrinsics",
    "decompose",
    "distort_image",
    "distort_points",
    "pinhole",
    "project",
    "projection",
    "remap",
    "undistort_image",
    "undistort_points",
]

Vector3 = tuple[float, float, float]


def check_intrinsics(camera: PinholeCamera, what: str = "camera") -> None:
    """Raise ValueError unless K is invertible with positive focal lengths."""
    fx, fy = camera.K[0, 0], camera.K[1, 1]
    if fx == 0 or fy == 0:
        raise ValueError(f"{what}: K is singular (fx = {fx:g}, fy = {fy:g})")
    if fx < 0 or fy < 0:
        raise ValueError(f"{what}: focal lengths must be positive, got fx = {fx:g}, fy = {fy:g}")


@node("camera.pinhole", version=1)
def pinhole(
    *,
    fx: Positive = 800.0,
    fy: Positive = 800.0,
    cx: float = 319.5,
    cy: float = 239.5,
    skew: float = 0.0,
    k1: float = 0.0,
    k2: float = 0.0,
    p1: float = 0.0,
    p2: float = 0.0,
    k3: float = 0.0,
    rotation: Vector3 = (0.0, 0.0, 0.0),
    centre: Vector3 = (0.0, 0.0, 0.0),
    width: ImageSide = 640,
    height: ImageSide = 480,
) -> Camera:
    r"""A pinhole camera from its 11 degrees of freedom and its lens distortion.

    .. math::

        K = \begin{pmatrix} f_x & s & c_x \\ 0 & f_y & c_y \\ 0 & 0 & 1 \end{pmatrix},
        \qquad P = K [R \mid -R \tilde C]

    5 intrinsic (fx, fy, cx, cy, s) + 3 for R + 3 for C̃ = 11, the degrees
    of freedom of a 3×4 matrix up to scale.

    Parameters
    ----------
    fx, fy : float
        Focal lengths in pixels (> 0).
    cx, cy : float
        Principal point in pixels.
    skew : float
        Skew s (0 for square-pixel sensors).
    k1, k2, k3 : float
        Radial distortion coefficients.
    p1, p2 : float
        Tangential distortion coefficients.
    rotation : (float, float, float)
        World-to-camera rotation as an axis-angle vector (radians).
    centre : (float, float, float)
        Camera centre C̃ in world coordinates.
    width, height : int
        Image size in pixels.

    References
    ----------
    .. [1] Hartley & Zisserman, *Multiple View Geometry*, 2nd ed., 2004, §6.1.
    """
    K = np.array([[fx, skew, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
    return PinholeCamera(
        K,
        R=rotation_from_vector(np.asarray(rotation, dtype=np.float64)),
        C=np.asarray(centre, dtype=np.float64),
        distortion=np.array([k1, k2, p1, p2, k3], dtype=np.float64),
        size=np.array([width, height], dtype=np.int64),
    )


@node("camera.project", version=1)
def project(camera: Camera, points: Points3D, *, distort: bool = True) -> Points2D:
    r"""Project world points to pixels: :math:`x = K\, d(\pi(R(X - \tilde C)))`.

    Parameters
    ----------
    camera : Camera
        The camera.
    points : Points3D
        World points, N×3.
    distort : bool
        Apply the camera's lens distortion (False: the ideal pinhole image).

    Raises
    ------
    ValueError
        When a point lies behind the camera (or on its principal plane).

    References
    ----------
    .. [1] Hartley & Zisserman, *Multiple View Geometry*, 2nd ed., 2004, §6.1.
    """
    check_intrinsics(camera)
    pixels = project_points(
        points, camera.K, camera.R, camera.C, camera.distortion if distort else None
    )
    behind = ~np.isfinite(pixels).all(axis=1)
    if behind.any():
        raise ValueError(
            f"{int(behind.sum())} of {len(points)} points lie behind the camera "
            f"(first: index {int(np.flatnonzero(behind)[0])})"
        )
    return pixels


@node("camera.projection", version=1)
def projection(camera: Camera) -> Array:
    r"""The 3×4 camera matrix :math:`P = K [R \mid -R \tilde C]` (distortion not included).

    Parameters
    ----------
    camera : Camera
        The camera.
    """
    return camera.P


@node("camera.decompose", version=1)
def decompose(P: Array) -> Camera:
    r"""Recover K, R and C̃ from a finite camera matrix P (RQ decomposition of its 3×3 block).

    :math:`P = [M \mid p_4]`, :math:`M = KR` with K upper triangular of
    positive diagonal and R a proper rotation; :math:`\tilde C = -M^{-1} p_4`.
    P is known up to scale (and sign): K is returned with :math:`K_{33} = 1`.

    Parameters
    ----------
    P : Array
        A 3×4 camera matrix.

    Raises
    ------
    ValueError
        For a matrix that is not 3×4 or whose 3×3 block is singular.

    References
    ----------
    .. [1] Hartley & Zisserman, *Multiple View Geometry*, 2nd ed., 2004, §6.2.4.
    """
    if P.shape != (3, 4) or not np.isfinite(P).all():
        raise ValueError(f"P must be a finite 3×4 matrix, got shape {P.shape}")
    K, R, C = decompose_projection(P.astype(np.float64))
    K[1, 0] = K[2, 0] = K[2, 1] = 0.0
    return PinholeCamera(K, R, C)


@node("camera.distort_points", version=1)
def distort_points(camera: Camera, points: Points2D) -> Points2D:
    """Ideal pinhole pixels to the pixels the camera's lens records (module ``_projection``).

    Parameters
    ----------
    camera : Camera
        K and distortion ``(k1, k2, p1, p2, k3)``.
    points : Points2D
        Undistorted pixel positions.
    """
    check_intrinsics(camera)
    return distort_pixels(points, camera.K, camera.distortion)


@node("camera.undistort_points", version=1)
def undistort_points(camera: Camera, points: Points2D) -> Points2D:
    """Recorded pixels to ideal pinhole pixels: the distortion inverted by Newton's method.

    Converged to 1e-12 in normalised units (about 1e-9 px); equal to
    ``cv2.undistortPoints(pts, K, dist, P=K)`` run to convergence.

    Parameters
    ----------
    camera : Camera
        K and distortion ``(k1, k2, p1, p2, k3)``.
    points : Points2D
        Distorted pixel positions.

    Raises
    ------
    ValueError
        When the distortion cannot be inverted at some point (beyond its fold).
    """
    check_intrinsics(camera)
    return undistort_pixels(points, camera.K, camera.distortion)


def remap(image: np.ndarray, source: np.ndarray) -> np.ndarray:
    """Sample ``image`` bilinearly at ``source`` (H×W×2, (x, y)); outside is 0."""
    from scipy import ndimage

    coords = [source[..., 1], source[..., 0]]
    if image.ndim == 2:
        out = ndimage.map_coordinates(image, coords, order=1, mode="constant", cval=0.0)
    else:
        out = np.stack(
            [
                ndimage.map_coordinates(image[..., c], coords, order=1, mode="constant", cval=0.0)
                for c in range(image.shape[2])
            ],
            axis=-1,
        )
    return np.clip(out, 0.0, 1.0).astype(np.float32)


def _pixel_grid(shape: tuple[int, ...]) -> np.ndarray:
    v, u = np.mgrid[0 : shape[0], 0 : shape[1]].astype(np.float64)
    return np.column_stack([u.ravel(), v.ravel()])


@node("camera.undistort_image", version=1, conformance=Conformance("max_abs", 1e-4))
def undistort_image(image: ImageT, camera: Camera) -> ImageT:
    """The image an ideal pinhole with the same K would have taken (cf. ``cv2.undistort``).

    Each output pixel p is read at its distorted position :math:`K d(K^{-1} p)`
    by bilinear interpolation; pixels whose source falls outside are 0.

    Parameters
    ----------
    image : Image
        An image taken by ``camera``.
    camera : Camera
        K and the distortion to remove.
    """
    check_intrinsics(camera)
    source = distort_pixels(_pixel_grid(image.shape), camera.K, camera.distortion)
    return remap(image, source.reshape((*image.shape[:2], 2)))


@node("camera.distort_image", version=1)
def distort_image(image: ImageT, camera: Camera) -> ImageT:
    """The image the camera's lens would record of an ideal pinhole image with the same K.

    Each output pixel is read at its undistorted position (Newton inversion,
    :func:`undistort_points`) by bilinear interpolation.

    Parameters
    ----------
    image : Image
        An undistorted image.
    camera : Camera
        K and the distortion to apply.

    Raises
    ------
    ValueError
        When the distortion cannot be inverted over the image.
    """
    check_intrinsics(camera)
    source = undistort_pixels(_pixel_grid(image.shape), camera.K, camera.distortion)
    return remap(image, source.reshape((*image.shape[:2], 2)))
