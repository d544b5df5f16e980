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

import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Field

from graphvision import Boxes, BoxSet, Conformance, GrayImage, PortValueError, RecordPort, node

from ..shared.checks import ordered
from ..shared.params import MAX_SIDE, Fraction

__all__ = [
    "BuiltinCascade",
    "LBPCascade",
    "LBPCascadeModel",
    "LBPCascadePort",
    "builtin_cascade_file",
    "detect_lbp",
    "group_rectangles",
    "lbp_cascade",
    "lbp_detect",
    "lbp_windows",
    "parse_opencv_cascade",
    "read_opencv_cascade",
    "resampled_integral",
    "scan_step",
    "window_scales",
]


@dataclass(frozen=True, eq=False)
class LBPCascadeModel:
    """A boosted cascade of MB-LBP stumps (see the module).

    ``rects`` (F, 4) int64: each feature's (x, y, block width, block height) in the
    window; ``feature`` (K,) int64: the feature of each weak classifier; ``subsets``
    (K, 8) uint32: the 256-bit set of codes that choose ``leaves[k, 0]`` over
    ``leaves[k, 1]``; ``leaves`` (K, 2) float64; ``stage`` (K,) int64: the stage of each
    weak classifier, non-decreasing from 0; ``stage_threshold`` (S,) float64;
    ``height``, ``width``: the window; ``source``: where it was read from.
    """

    rects: np.ndarray
    feature: np.ndarray
    subsets: np.ndarray
    leaves: np.ndarray
    stage: np.ndarray
    stage_threshold: np.ndarray
    height: int = 24
    width: int = 24
    source: str = ""

    @property
    def stage_end(self) -> np.ndarray:
        """One past the last weak classifier of each stage, int64 (S,)."""
        counts = np.bincount(self.stage, minlength=len(self.stage_threshold))
        return np.cumsum(counts).astype(np.int64)


def _typed(name: str, value: Any, dtype: type, ndim: int) -> np.ndarray:
    if not isinstance(value, np.ndarray) or value.dtype != dtype or value.ndim != ndim:
        got = f"{value.dtype} {value.shape}" if isinstance(value, np.ndarray) else type(value)
        raise PortValueError(
            f"LBPCascade '{name}' must be a {ndim}-D {np.dtype(dtype).name}, got {got}"
        )
    return value


class LBPCascadePort(RecordPort):
    """An :class:`LBPCascadeModel` whose parts fit together: every feature's 3 × 3 blocks
    inside the window, feature indices in range, stages numbered 0 … S − 1 in order with
    at least one weak classifier each, finite leaves and thresholds."""

    value_class = LBPCascadeModel

    @classmethod
    def validate(cls, value: Any) -> LBPCascadeModel:
        value = super().validate(value)
        rects = _typed("rects", value.rects, np.int64, 2)
        feature = _typed("feature", value.feature, np.int64, 1)
        subsets = _typed("subsets", value.subsets, np.uint32, 2)
        leaves = _typed("leaves", value.leaves, np.float64, 2)
        stage = _typed("stage", value.stage, np.int64, 1)
        thresholds = _typed("stage_threshold", value.stage_threshold, np.float64, 1)
        if not isinstance(value.height, int) or not isinstance(value.width, int):
            raise PortValueError("LBPCascade 'height' and 'width' must be integers")
        if not 3 <= value.height <= 1024 or not 3 <= value.width <= 1024:
            raise PortValueError(
                f"LBPCascade window must be 3 to 1024 pixels a side, got "
                f"{value.height}×{value.width}"
            )
        count = len(feature)
        if rects.shape[1:] != (4,) or len(rects) == 0:
            raise PortValueError(f"LBPCascade 'rects' must be (F, 4) with F ≥ 1, got {rects.shape}")
        if subsets.shape != (count, 8) or leaves.shape != (count, 2) or stage.shape != (count,):
            raise PortValueError(
                f"LBPCascade needs subsets (K, 8), leaves (K, 2) and stage (K,) for its K = "
                f"{count} weak classifiers, got {subsets.shape}, {leaves.shape}, {stage.shape}"
            )
        if count == 0 or len(thresholds) == 0:
            raise PortValueError("LBPCascade needs at least one stage and one weak classifier")
        if not (np.isfinite(leaves).all() and np.isfinite(thresholds).all()):
            raise PortValueError("LBPCascade leaves and stage thresholds must be finite")
        if feature.min() < 0 or feature.max() >= len(rects):
            raise PortValueError(f"LBPCascade 'feature' must index the {len(rects)} features")
        x, y, w, h = rects.T
        outside = (x < 0) | (y < 0) | (w < 1) | (h < 1)
        outside |= (x + 3 * w > value.width) | (y + 3 * h > value.height)
        if outside.any():
            row = int(np.flatnonzero(outside)[0])
            raise PortValueError(
                f"LBPCascade feature {row} (x, y, w, h) = {rects[row].tolist()}: its 3 × 3 "
                f"blocks must lie inside the {value.width}×{value.height} window"
            )
        stages = len(thresholds)
        if (np.diff(stage) < 0).any() or stage[0] != 0 or stage[-1] != stages - 1:
            raise PortValueError(
                f"LBPCascade 'stage' must number the weak classifiers' stages 0 … {stages - 1} "
                "in order"
            )
        if (np.bincount(stage, minlength=stages) == 0).any():
            raise PortValueError("LBPCascade has a stage without a weak classifier")
        return value

    @classmethod
    def preview(cls, value: LBPCascadeModel) -> np.ndarray | None:
        """Where the cascade looks: how many weak classifiers cover each window pixel,
        earlier stages counting more (a stage-s classifier weighs 1 / (s + 1)),
        stretched to [0, 1] and enlarged 8 times."""
        return feature_map(value)

    @classmethod
    def summary(cls, value: LBPCascadeModel) -> str:
        return (
            f"LBPCascade {len(value.stage_threshold)} stages, {len(value.feature)} weak "
            f"classifiers, {value.width}×{value.height} window"
        )


LBPCascade = Annotated[LBPCascadeModel, LBPCascadePort]


def feature_map(model: LBPCascadeModel, zoom: int = 8) -> np.ndarray:
    """The cascade's attention over its window (see :meth:`LBPCascadePort.preview`)."""
    weight = np.zeros((model.height, model.width))
    for k, index in enumerate(model.feature):
        x, y, w, h = (int(v) for v in model.rects[index])
        weight[y : y + 3 * h, x : x + 3 * w] += 1.0 / (model.stage[k] + 1)
    weight /= max(float(weight.max()), 1e-12)
    return np.kron(weight, np.ones((zoom, zoom))).astype(np.float32)


# --- reading OpenCV's XML --------------------------------------------------------------


def _text(parent: ElementTree.Element, tag: str, where: str) -> str:
    child = parent.find(tag)
    if child is None or child.text is None:
        raise ValueError(f"{where} has no <{tag}>")
    return child.text


def _numbers(text: str, kind: type, where: str) -> list:
    try:
        return [kind(item) for item in text.split()]
    except ValueError:
        raise ValueError(
            f"{where}: expected {kind.__name__} values, got '{text.strip()[:60]}'"
        ) from None


def parse_opencv_cascade(text: str | bytes, source: str = "") -> LBPCascadeModel:
    """An :class:`LBPCascadeModel` from the text of an OpenCV cascade file (the format
    ``opencv_traincascade`` writes: ``<cascade>`` with ``<featureType>LBP``, ``<stages>``
    of ``<weakClassifiers>`` whose ``<internalNodes>`` are ``left right feature`` and
    eight 32-bit subset words, ``<leafValues>``, and ``<features>`` of ``<rect>x y w
    h``).

    Raises
    ------
    ValueError
        Naming what is missing or wrong: not XML, not a cascade, not LBP (a Haar cascade),
        not stumps (trees of depth > 1), a malformed classifier.
    """
    where = source or "the cascade file"
    try:
        root = ElementTree.fromstring(text)
    except ElementTree.ParseError as error:
        raise ValueError(f"{where} is not XML ({error})") from None
    cascade = root if root.tag == "cascade" else root.find("cascade")
    if cascade is None:
        raise ValueError(f"{where} holds no <cascade> (is it an OpenCV cascade file?)")
    kind = _text(cascade, "featureType", where).strip()
    if kind.upper() != "LBP":
        raise ValueError(
            f"{where} is a {kind} cascade; graphvision reads LBP cascades "
            "(recognition.cascade trains Haar-like ones)"
        )
    height = int(_text(cascade, "height", where))
    width = int(_text(cascade, "width", where))
    stages = cascade.find("stages")
    features = cascade.find("features")
    if stages is None or features is None or len(stages) == 0 or len(features) == 0:
        raise ValueError(f"{where} has no <stages> or no <features>")
    rects = []
    for index, item in enumerate(features):
        numbers = _numbers(_text(item, "rect", f"{where} feature {index}"), int, where)
        if len(numbers) != 4:
            raise ValueError(f"{where} feature {index}: <rect> needs x y w h, got {numbers}")
        rects.append(numbers)
    feature, subsets, leaves, stage_of, thresholds = [], [], [], [], []
    for s, stage in enumerate(stages):
        place = f"{where} stage {s}"
        thresholds.append(float(_text(stage, "stageThreshold", place)))
        weak = stage.find("weakClassifiers")
        if weak is None or len(weak) == 0:
            raise ValueError(f"{place} has no weak classifier")
        for k, classifier in enumerate(weak):
            at = f"{place} weak classifier {k}"
            nodes = _numbers(_text(classifier, "internalNodes", at), int, at)
            values = _numbers(_text(classifier, "leafValues", at), float, at)
            if len(nodes) != 11 or len(values) != 2:
                raise ValueError(
                    f"{at}: expected a stump (11 internal-node numbers: left, right, feature "
                    f"and 8 subset words; 2 leaf values), got {len(nodes)} and {len(values)} "
                    "(trees deeper than one split are not read)"
                )
            feature.append(nodes[2])
            subsets.append(nodes[3:])
            leaves.append(values)
            stage_of.append(s)
    model = LBPCascadeModel(
        rects=np.array(rects, np.int64),
        feature=np.array(feature, np.int64),
        subsets=np.array(subsets, np.int64).astype(np.uint32),  # two's complement words
        leaves=np.array(leaves, np.float64),
        stage=np.array(stage_of, np.int64),
        stage_threshold=np.array(thresholds, np.float64),
        height=height,
        width=width,
        source=source,
    )
    try:
        return LBPCascadePort.validate(model)
    except PortValueError as error:
        raise ValueError(f"{where}: {error}") from None


MAX_CASCADE_BYTES = 64 * 2**20
"""Largest cascade file read (OpenCV's biggest shipped cascade is under 2 MB)."""

BuiltinCascade = Literal["skimage_frontal_face"]
"""The cascades shipped with the libraries graphvision depends on: scikit-image's copy of
OpenCV's ``lbpcascade_frontalface.xml``."""


def builtin_cascade_file(name: str) -> Path:
    """The file of a built-in cascade (see :data:`BuiltinCascade`)."""
    from skimage.data import lbp_frontal_face_cascade_filename

    if name != "skimage_frontal_face":
        raise ValueError(f"unknown built-in cascade '{name}'; built in: skimage_frontal_face")
    return Path(lbp_frontal_face_cascade_filename())


def read_opencv_cascade(path: str | Path) -> LBPCascadeModel:
    """The LBP cascade in an OpenCV XML file (see :func:`parse_opencv_cascade`).

    A cascade other than the built-in one reaches a graph as a graph-input value of type
    ``LBPCascade``: ``gv.run(graph, inputs={"cascade": read_opencv_cascade(path)})``
    (keyed by its content), or the ``.npz`` a run wrote of it.

    Raises
    ------
    FileNotFoundError, ValueError
        Naming the file and what is wrong with it.
    """
    file = Path(path)
    if not file.is_file():
        raise FileNotFoundError(f"no such cascade file: {file}")
    size = file.stat().st_size
    if size > MAX_CASCADE_BYTES:
        raise ValueError(
            f"{file} is {size / 2**20:.0f} MB; a cascade file is at most "
            f"{MAX_CASCADE_BYTES // 2**20} MB"
        )
    return parse_opencv_cascade(file.read_bytes(), str(file))


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


# --- scanning ---------------------------------------------------------------------------


def window_scales(
    shape: tuple[int, int],
    window: tuple[int, int],
    scale_factor: float,
    min_size: float,
    max_size: float,
) -> np.ndarray:
    """Scales s = s0 · factor^k of the window (height, width), from the one whose larger
    side is ``min_size`` pixels, while its larger side is at most ``max_size`` and the
    window fits in the image (height, width)."""
    side = max(window)
    scales = []
    scale = min_size / side
    while (
        scale * side <= max_size + 1e-9
        and window[0] * scale <= shape[0]
        and window[1] * scale <= shape[1]
    ):
        scales.append(scale)
        scale *= scale_factor
    return np.array(scales)


def resampled_integral(padded: np.ndarray, scale: float) -> np.ndarray:
    r"""The zero-padded integral image of the image reduced by ``scale`` (area average,
    sums kept in input pixels): :math:`S_s(v, u) = F(v s, u s)`, F interpolated
    bilinearly (exact for a piecewise-constant image), float64
    (⌊H / s⌋ + 1, ⌊W / s⌋ + 1)."""
    from ._lbp_kernels import resample_integral

    return resample_integral(np.ascontiguousarray(padded, np.float64), float(scale))


def scan_step(scale: float, step: int) -> int:
    """The window step at ``scale`` in reduced pixels: ``step`` itself, or with ``step`` 0
    OpenCV's rule (``detectMultiScale``): 2 while the scale is at most 2, then 1."""
    if step:
        return step
    return 1 if scale > 2.0 else 2


def lbp_windows(
    image: np.ndarray,
    model: LBPCascadeModel,
    *,
    scale_factor: float = 1.1,
    step: int = 1,
    min_size: float = 24.0,
    max_size: float = 4096.0,
) -> tuple[np.ndarray, np.ndarray, int]:
    """Every window of a gray image that passes all stages: boxes (N, 4) (x0, y0, x1, y1)
    in input pixels, the last stage's margin (N,), and the weak classifiers evaluated
    (see the module for the scales, :func:`scan_step` for ``step``)."""
    from ._cascade_kernels import corner_offsets
    from ._lbp_kernels import padded_integral, resample_integral, scan_level

    padded = padded_integral(np.asarray(image, np.float64))
    window = (model.height, model.width)
    boxes, margins, evaluated = [], [], 0
    stage_end = model.stage_end
    offsets: dict[int, np.ndarray] = {}
    for scale in window_scales(image.shape, window, scale_factor, min_size, max_size):
        level = padded if scale == 1 else resample_integral(padded, float(scale))
        stride = level.shape[1]
        if stride not in offsets:
            offsets[stride] = corner_offsets(model.rects, model.feature, stride)
        found, margin, count = scan_level(
            level,
            model.height,
            model.width,
            scan_step(scale, step),
            offsets[stride],
            model.subsets,
            model.leaves,
            stage_end,
            model.stage_threshold,
        )
        evaluated += count
        top, left = found[:, 0] * scale, found[:, 1] * scale
        boxes.append(
            np.column_stack([left, top, left + model.width * scale, top + model.height * scale])
        )
        margins.append(margin)
    if not boxes:
        return np.zeros((0, 4)), np.zeros(0), 0
    return np.concatenate(boxes), np.concatenate(margins), evaluated


# --- grouping -------------------------------------------------------------------------


def _partition(xywh: np.ndarray, eps: float) -> np.ndarray:
    """Class labels of boxes under the transitive closure of OpenCV's ``SimilarRects``:
    every side within ``eps`` · (mean of the smaller width and smaller height)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    count = len(xywh)
    x0, y0, w, h = xywh.T
    x1, y1 = x0 + w, y0 + h
    rows, cols = [], []
    for start in range(0, count, 1024):  # bounded memory: 1024 × N comparisons at a time
        part = slice(start, min(start + 1024, count))
        delta = (
            eps
            * 0.5
            * (np.minimum(w[part, None], w[None, :]) + np.minimum(h[part, None], h[None, :]))
        )
        close = (np.abs(x0[part, None] - x0[None, :]) <= delta) & (
            np.abs(y0[part, None] - y0[None, :]) <= delta
        )
        close &= np.abs(x1[part, None] - x1[None, :]) <= delta
        close &= np.abs(y1[part, None] - y1[None, :]) <= delta
        r, c = np.nonzero(close)
        rows.append(r + start)
        cols.append(c)
    graph = coo_matrix(
        (np.ones(sum(len(r) for r in rows)), (np.concatenate(rows), np.concatenate(cols))),
        shape=(count, count),
    )
    return connected_components(graph, directed=False)[1]


def group_rectangles(
    xyxy: np.ndarray, min_neighbours: int, eps: float
) -> tuple[np.ndarray, np.ndarray]:
    """OpenCV's ``groupRectangles``: boxes (N, 4) fall into classes of similar boxes
    (:func:`_partition`), each class becomes its mean box, classes of at most
    ``min_neighbours`` boxes are dropped, and so is a class inside a clearly stronger
    one's box (grown by ``eps`` of its size: more than max(3, n) members, or the inner
    one has fewer than 3). Returns the boxes (M, 4) and their members (M,), strongest
    first. ``min_neighbours`` 0 returns the boxes as they are."""
    if len(xyxy) == 0:
        return np.zeros((0, 4)), np.zeros(0)
    if min_neighbours == 0:
        return xyxy.copy(), np.ones(len(xyxy))
    xywh = np.column_stack([xyxy[:, :2], xyxy[:, 2:] - xyxy[:, :2]])
    labels = _partition(xywh, eps)
    members = np.bincount(labels).astype(np.float64)
    means = (
        np.stack([np.bincount(labels, weights=xywh[:, i]) for i in range(4)], axis=1)
        / members[:, None]
    )
    strong = np.flatnonzero(members > min_neighbours)
    kept = []
    for i in strong:
        x, y, w, h = means[i]
        inside = False
        for j in strong:
            if j == i:
                continue
            bx, by, bw, bh = means[j]
            dx, dy = bw * eps, bh * eps
            if (
                x >= bx - dx
                and y >= by - dy
                and x + w <= bx + bw + dx
                and y + h <= by + bh + dy
                and (members[j] > max(3, members[i]) or members[i] < 3)
            ):
                inside = True
                break
        if not inside:
            kept.append(i)
    kept_array = np.array(kept, np.int64)
    order = kept_array[np.argsort(-members[kept_array], kind="stable")]
    boxes = means[order]
    return np.column_stack([boxes[:, :2], boxes[:, :2] + boxes[:, 2:]]), members[order]


# --- the node ----------------------------------------------------------------------------

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
