"""Reading an LBP cascade from OpenCV's XML format (what ``opencv_traincascade`` writes)
with the standard library's ``xml.etree``, and the cascades the libraries ship."""

from __future__ import annotations

import xml.etree.ElementTree as ElementTree
from pathlib import Path
from typing import Literal

import numpy as np

from graphvision import PortValueError

from ._lbp_model import LBPCascadeModel, LBPCascadePort

__all__ = [
    "BuiltinCascade",
    "builtin_cascade_file",
    "parse_opencv_cascade",
    "read_opencv_cascade",
]


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


def _read_stages(
    stages: ElementTree.Element, where: str
) -> tuple[list[int], list[list[int]], list[list[float]], list[int], list[float]]:
    """Per weak classifier its feature, subset words, leaf values and stage; per stage its
    threshold (see :func:`parse_opencv_cascade`)."""
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
    return feature, subsets, leaves, stage_of, thresholds


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
    feature, subsets, leaves, stage_of, thresholds = _read_stages(stages, where)
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
