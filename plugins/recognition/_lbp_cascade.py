"""A trained cascade of multi-block LBP stumps read from OpenCV's XML format, evaluated
with graphvision's own integral images (seed: "Efficient computation - integral images",
"cascade of classifiers"; Viola & Jones 2001; Liao et al. 2007).

The file scikit-image ships, ``skimage.data.lbp_frontal_face_cascade_filename()``, is
OpenCV's ``lbpcascade_frontalface`` (20 stages, 139 weak classifiers over 136 MB-LBP
features of a 24 × 24 window, trained on 3,000 faces and 1,500 non-faces). It reaches
a graph through ``recognition.lbp_cascade`` (another file of the same format through
:func:`read_opencv_cascade`, as a graph-input value), parsed with the standard library's
``xml.etree``; the parsed cascade is an :class:`LBPCascadeModel`, a value like any
trained model (named arrays plus a JSON header, never pickle).

How a window is classified (OpenCV's ``LBPEvaluator`` and ``predictCategoricalStump``):

* a feature is a 3 × 3 grid of blocks of w × h pixels at (x, y) in the window; its
  MB-LBP code sets bit 7 … 0 (clockwise from the top-left block to the middle-left
  one) where a block's sum reaches the centre block's;
* weak classifier k adds ``leaves[k, 0]`` when bit ``code`` of its 256-bit subset is
  set, else ``leaves[k, 1]``;
* a stage passes when its sum reaches its threshold; a window is a face when it passes
  every stage, and is dropped at the first stage it fails (early rejection).

Scales (the detector is scaled, not the image, as Viola and Jones do): at scale s the
window covers 24 s × 24 s pixels; the integral image of the image reduced by s is the
exact integral :math:`F(x, y) = \\int_0^y\\int_0^x I` of the piecewise-constant image
sampled every s pixels, and F is bilinear inside each pixel, so bilinear interpolation
of the one integral image gives it exactly (an area-averaged reduction, without a
pyramid of resampled images). The trained features then run unchanged on it.
"""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import Field

from graphvision import Boxes, BoxSet, Conformance, GrayImage, node

from ..shared.checks import ordered
from ..shared.params import MAX_SIDE, Fraction
from ._group_rectangles import group_rectangles
from ._lbp_model import LBPCascade, LBPCascadeModel
from ._lbp_scan import lbp_windows
from ._opencv_cascade import BuiltinCascade, builtin_cascade_file, parse_opencv_cascade

__all__ = [
    "detect_lbp",
    "lbp_cascade",
    "lbp_detect",
]


@node("recognition.lbp_cascade", version=1)
def lbp_cascade(*, name: BuiltinCascade = "skimage_frontal_face") -> LBPCascade:
    """A trained cascade of multi-block LBP stumps shipped with scikit-image, read from
    OpenCV's XML format with the standard library's ``xml.etree``.

    ``skimage_frontal_face`` is ``skimage.data.lbp_frontal_face_cascade_filename()``,
    OpenCV's ``lbpcascade_frontalface.xml``: 20 stages, 139 weak classifiers over 136
    MB-LBP features of a 24 × 24 window, trained on 3,000 faces and 1,500 non-faces
    (GAB boosting, stage hit rate 0.995, false-alarm rate 0.5). scikit-image's copy
    names one section ``featuhreParams`` (sic), for which OpenCV refuses the file; this
    reader does not need that section. Any other OpenCV LBP cascade enters a graph as an
    input value (:func:`read_opencv_cascade`).

    Parameters
    ----------
    name : {'skimage_frontal_face'}
        The built-in cascade.

    Returns
    -------
    cascade : LBPCascade
        Its features, weak classifiers (256-bit subsets, leaf values) and stages.

    References
    ----------
    P. Viola and M. Jones, "Rapid object detection using a boosted cascade of simple
    features", CVPR 2001; S. Liao, X. Zhu, Z. Lei, L. Zhang and S. Z. Li, "Learning
    multi-scale block local binary patterns for face recognition", ICB 2007.
    """
    file = builtin_cascade_file(name)
    return parse_opencv_cascade(file.read_bytes(), f"skimage:{file.name}")


# --- detection -------------------------------------------------------------------------

ScaleStep = Annotated[float, Field(gt=1, le=4)]
WindowSide = Annotated[float, Field(ge=4, le=MAX_SIDE)]
Neighbours = Annotated[int, Field(ge=0, le=10_000)]
ScanStep = Annotated[int, Field(ge=0, le=64)]
"""A window step in reduced pixels, or 0 for OpenCV's rule (:func:`scan_step`)."""


def detect_lbp(
    image: np.ndarray,
    model: LBPCascadeModel,
    *,
    scale_factor: float,
    step: int,
    min_size: float,
    max_size: float,
    min_neighbours: int,
    eps: float,
) -> BoxSet:
    """Grouped detections of a gray image (see :func:`lbp_detect`)."""
    boxes, margins, _ = lbp_windows(
        image,
        model,
        scale_factor=scale_factor,
        step=step,
        min_size=min_size,
        max_size=max_size,
    )
    if min_neighbours == 0:
        return BoxSet(boxes, margins)
    grouped, members = group_rectangles(boxes, min_neighbours, eps)
    return BoxSet(grouped, members)


_OPENCV = (
    "OpenCV (cv2.CascadeClassifier, in OpenCV 4.x only) scans every second reduced pixel "
    "up to scale 2 on integer window sizes: a group's count is about a quarter of the "
    "reference's, its boxes differ by up to about 10 px (x0, y0, x1 of 40-120 px faces) "
    "and it may keep a group the reference drops; boxes are compared by position"
)


@node(
    "recognition.lbp_detect",
    version=1,
    check=ordered(("min_size", "max_size")),
    conformance=Conformance("recall", 0.6, radius=12.0, note=_OPENCV),
)
def lbp_detect(
    image: GrayImage,
    cascade: LBPCascade,
    *,
    scale_factor: ScaleStep = 1.1,
    step: ScanStep = 1,
    min_size: WindowSide = 24.0,
    max_size: WindowSide = float(MAX_SIDE),
    min_neighbours: Neighbours = 8,
    eps: Fraction = 0.2,
) -> Boxes:
    r"""Faces (or whatever the cascade was trained on) found by a boosted cascade of
    multi-block LBP stumps, over positions and scales, grouped as OpenCV groups them.

    The window's scale runs from ``min_size`` to ``max_size`` pixels (its larger side) in
    steps of ``scale_factor``; at scale s the integral image of the image reduced by s
    (exact area averages, see the module) is scanned every ``step`` reduced pixels
    (``step`` 0: OpenCV's rule, every second one while s ≤ 2, every one above). A
    multi-block LBP feature compares the sums of 3 × 3 blocks with the centre block's,

    .. math:: \mathrm{code} = \sum_{i=0}^{7} 2^{7-i}\,[\,S_i \ge S_c\,]

    (:math:`S_i` clockwise from the top-left block), each four look-ups in the integral
    image; weak classifier k adds :math:`\ell_{k,0}` when the code is in its trained
    subset, else :math:`\ell_{k,1}`; a stage passes when its sum reaches its threshold,
    and a window is dropped at the first stage it fails (early rejection: the first
    stage's 3 features reject most windows). Windows passing every stage are grouped:
    boxes whose four sides agree within ``eps`` × their mean size fall into one class
    (transitively), each class of more than ``min_neighbours`` boxes becomes its mean
    box, scored by its number of boxes, and a class inside a stronger one is dropped
    (OpenCV's ``groupRectangles``). ``min_neighbours`` 0 returns every window, scored
    by its last stage's margin.

    Parameters
    ----------
    image : (H, W) gray image
    cascade : LBPCascade
        A trained cascade (``recognition.lbp_cascade``).
    scale_factor : float
        Ratio between successive window sizes.
    step : int
        Window step in pixels of the reduced image (s pixels of the input at scale s);
        0 scans as OpenCV's ``detectMultiScale`` does: every second reduced pixel while
        s ≤ 2, every pixel above (about 2.6 times fewer windows than step 1 from 24 px
        on a 512² image, most of them small ones). OpenCV's own call uses 3
        ``min_neighbours``; on ``face_detect.yaml``'s scenes the default 8 keeps fewer
        false positives at step 0 too.
    min_size, max_size : float
        Smallest and largest window (its larger side, in input pixels).
    min_neighbours : int
        A group needs more windows than this. With ``step`` 1 a face gathers about
        four times as many windows as with OpenCV's step 2 (its step up to scale 2);
        8 was chosen on the tuning scenes of ``synthetic.face_scenes`` (seeds 0–7),
        not on the scenes measured.
    eps : float
        Relative tolerance of the grouping.

    Returns
    -------
    boxes : Boxes (x0, y0, x1, y1), scored by their number of windows, most first

    References
    ----------
    P. Viola and M. Jones, "Rapid object detection using a boosted cascade of simple
    features", CVPR 2001; S. Liao, X. Zhu, Z. Lei, L. Zhang and S. Z. Li, "Learning
    multi-scale block local binary patterns for face recognition", ICB 2007
    (L. Zhang et al., "Face detection based on multi-block LBP representation", ICB
    2007); T. Ahonen, A. Hadid and M. Pietikäinen, "Face description with local binary
    patterns", PAMI 28(12), 2006.

    Examples
    --------
    >>> import skimage.data
    >>> gray = skimage.data.astronaut().mean(axis=2).astype(np.float32) / 255
    >>> faces = lbp_detect(gray, lbp_cascade())
    >>> np.round(faces.xyxy).astype(int).tolist()
    [[177, 67, 273, 163]]
    """
    return detect_lbp(
        image,
        cascade,
        scale_factor=scale_factor,
        step=step,
        min_size=min_size,
        max_size=max_size,
        min_neighbours=min_neighbours,
        eps=eps,
    )
